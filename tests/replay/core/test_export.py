from pathlib import Path

import numpy as np
import polars as pl
import pytest

from trackreplay.replay.core.export import fill_gaps, read_trajectory, write_trajectory
from trackreplay.replay.core.trajectory import COLUMNS, state_row, table_digest, trajectory_table
from trackreplay.schemas.errors import TrackreplayError
from trackreplay.trackers.base import TrackState


def _table(frames, positions, statuses=None):
    statuses = statuses or ["measured"] * len(frames)
    rows = []
    for f, p, s in zip(frames, positions, statuses):
        state = TrackState(1, x=p, y=2 * p, w=4.0, h=4.0, status=s) if p is not None else TrackState(1, status=s)
        rows.append(state_row("flow", f, f * 1000, state))
    return trajectory_table(rows)


def test_linear_fill_of_missing_and_lost_frames() -> None:
    df = _table([0, 1, 2, 5, 6], [0.0, 1.0, None, 5.0, 6.0], ["measured", "measured", "lost", "measured", "measured"])
    out = fill_gaps(df, "linear", max_gap=5)
    assert out["frame"].to_list() == list(range(7))
    assert out["x"].to_list() == pytest.approx([0, 1, 2, 3, 4, 5, 6])
    assert out["t_ns"].to_list() == [f * 1000 for f in range(7)]
    assert out["status"].to_list()[2:5] == ["interpolated"] * 3


def test_gap_longer_than_max_stays_lost() -> None:
    df = _table([0, 1, 6, 7], [0.0, 1.0, 6.0, 7.0])
    out = fill_gaps(df, "linear", max_gap=3)
    assert out["status"].to_list()[2:6] == ["lost"] * 4
    assert out["x"].to_list()[2:6] == [None] * 4


def test_cubic_follows_a_parabola_exactly_where_linear_cannot() -> None:
    frames = [0, 1, 2, 3, 7, 8, 9, 10]
    xs = [float(f * f) for f in frames]
    cubic = fill_gaps(_table(frames, xs), "cubic", 5)
    linear = fill_gaps(_table(frames, xs), "linear", 5)
    gap = [4, 5, 6]
    err_cubic = np.abs(np.array(cubic["x"].to_list())[gap] - np.array(gap) ** 2).max()
    err_linear = np.abs(np.array(linear["x"].to_list())[gap] - np.array(gap) ** 2).max()
    assert err_cubic < 0.5 < err_linear


def test_round_trip_formats(tmp_path: Path) -> None:
    df = _table([0, 1, 2], [10.0, 11.0, 12.0])
    for suffix in (".parquet", ".csv"):
        path = write_trajectory(df, tmp_path / f"t{suffix}")
        assert table_digest(read_trajectory(path)) == table_digest(df)
    mot = write_trajectory(df, tmp_path / "t.txt").read_text().splitlines()
    assert mot[0] == "1,1,9.000,19.000,4.000,4.000,1.000,-1.000,-1.000,-1.000"  # 1-based frame and pixels
    assert len(mot) == 3


def test_mot_ground_truth_round_trips_through_a_trajectory(tmp_path: Path) -> None:
    """MOT ground truth imported, 'tracked' perfectly and exported gives the file's own boxes back."""
    from trackreplay.recorder.sources.groundtruth import read_groundtruth

    gt = tmp_path / "gt.txt"
    gt.write_text("1,1,1.000,1.000,10.000,8.000,1,-1,-1,-1\n2,1,3.500,2.000,10.000,8.000,1,-1,-1,-1\n")
    table = read_groundtruth(gt, "mot")
    xs = [table.objects_at(f)[0].x for f in (0, 1)]
    ys = [table.objects_at(f)[0].y for f in (0, 1)]
    assert xs == [5.0, 7.5]  # the top-left pixel (1, 1) is our (0, 0): a 10 px box from it is centred at 5
    df = _table([0, 1], xs).with_columns(pl.Series("y", ys), pl.lit(10.0).alias("w"), pl.lit(8.0).alias("h"))
    lines = write_trajectory(df, tmp_path / "out.txt").read_text().splitlines()
    assert [line.split(",")[2:6] for line in lines] == [r.split(",")[2:6] for r in gt.read_text().splitlines()]


def test_schema_is_the_contract() -> None:
    df = _table([0], [1.0])
    assert tuple(df.columns) == COLUMNS
    assert df.schema["frame"] == pl.Int64 and df.schema["x"] == pl.Float64 and df.schema["status"] == pl.String


def test_bad_inputs(tmp_path: Path) -> None:
    with pytest.raises(TrackreplayError, match="unknown trajectory format"):
        write_trajectory(_table([0], [1.0]), tmp_path / "t.xlsx")
    bad = tmp_path / "bad.csv"
    bad.write_text("a,b\n1,2\n")
    with pytest.raises(TrackreplayError, match="lacks trajectory columns"):
        read_trajectory(bad)
    with pytest.raises(TrackreplayError, match="interpolation method"):
        fill_gaps(_table([0], [1.0]), "quadratic")


def test_lost_state_with_a_position_is_refused_and_confidence_is_bounded() -> None:
    import pytest

    from trackreplay.trackers.base import TrackState

    with pytest.raises(ValueError, match="no position"):
        TrackState(1, x=3.0, y=4.0, status="lost")
    with pytest.raises(ValueError, match="confidence"):
        TrackState(1, x=3.0, y=4.0, confidence=1.5)
    assert TrackState(1, status="lost", confidence=0.0).x is None


def test_epoch_times_stay_exact_through_gap_filling_and_smoothing() -> None:
    """Wall-clock log times (~1.7e18 ns) do not fit float64's 53 bits: a review found every row's
    t_ns rounded by the gap filling (and smoothing), and eval then refusing the tool's own output."""
    from trackreplay.replay.analysis.smooth import smooth_trajectory
    from trackreplay.replay.core.trajectory import interpolated_times, state_row, trajectory_table
    from trackreplay.trackers.base import TrackState

    t0, step = 1_732_800_000_123_456_789, 33_333_333
    times = {f: t0 + f * step + (f % 3) for f in range(12)}  # not a float64-representable run
    rows = [state_row("flow", f, times[f], TrackState(1, x=10.0 + f, y=5.0, status="measured"))
            for f in range(12) if f not in (4, 5, 6)]
    filled = fill_gaps(trajectory_table(rows), "linear", max_gap=5)
    got = dict(zip(filled["frame"].to_list(), filled["t_ns"].to_list()))
    assert all(got[f] == times[f] for f in range(12) if f not in (4, 5, 6))
    assert [got[f] for f in (4, 5, 6)] == [int(v) for v in interpolated_times(
        np.arange(12), np.array([times.get(f, 0) for f in range(12)]), np.array([f not in (4, 5, 6) for f in range(12)]))[4:7]]
    assert times[3] < got[4] < got[5] < got[6] < times[7]
    smoothed, _ = smooth_trajectory(trajectory_table(rows), frame_times=times)
    assert dict(zip(smoothed["frame"].to_list(), smoothed["t_ns"].to_list())) == times


def test_interpolated_times_known_values() -> None:
    from trackreplay.replay.core.trajectory import interpolated_times

    t = interpolated_times(np.array([0, 1, 2, 3, 5]), np.array([0, 0, 10, 0, 0]), np.array([False, False, True, False, True]))
    assert t.tolist() == [10, 10, 10, 7, 0]  # the start held at the first known; 10 - 10/3 = 6.67 -> 7
    t = interpolated_times(np.array([0, 1, 2, 4]), np.array([100, 0, 0, 401]), np.array([True, False, False, True]))
    assert t.tolist() == [100, 175, 251, 401]  # 100 + 301/4 = 175.25 -> 175, 100 + 602/4 = 250.5 -> 251 (half up)


def test_filled_rows_move_at_their_positions_rate() -> None:
    """A review found filled rows' vx, vy interpolated on their own (y advancing 29.9 px/frame while
    vy ramped 5.8 -> 46.2): a filled row's velocity is its positions' rate, measured rows keep theirs."""
    frames = [0, 1, 2, 3, 8, 9, 10, 11]
    rows = [state_row("flow", f, f, TrackState(1, x=float(f * f), y=3.0 * f, w=4.0, h=4.0, vx=100.0 + f, vy=-1.0))
            for f in frames]
    linear = fill_gaps(trajectory_table(rows), "linear", 5)
    gap = linear.filter(pl.col("status") == "interpolated")
    assert gap["frame"].to_list() == [4, 5, 6, 7]
    assert gap["vx"].to_list() == pytest.approx([(64 - 9) / 5] * 4)  # the segment's slope, px/frame
    assert gap["vy"].to_list() == pytest.approx([3.0] * 4)
    measured = linear.filter(pl.col("status") == "measured")
    assert measured["vx"].to_list() == [100.0 + f for f in frames] and measured["vy"].to_list() == [-1.0] * 8
    cubic = fill_gaps(trajectory_table(rows), "cubic", 5)
    from scipy.interpolate import CubicSpline

    spline = CubicSpline(frames, [float(f * f) for f in frames], bc_type="natural")
    gap = cubic.filter(pl.col("status") == "interpolated")
    assert gap["x"].to_list() == pytest.approx(spline([4, 5, 6, 7]).tolist())
    assert gap["vx"].to_list() == pytest.approx(spline([4, 5, 6, 7], 1).tolist())  # the spline's own derivative
    assert cubic.filter(pl.col("status") == "measured")["vx"].to_list() == [100.0 + f for f in frames]


def _written(tmp_path: Path, df: pl.DataFrame, name: str = "t.parquet") -> Path:
    path = tmp_path / name
    df.write_parquet(path) if path.suffix == ".parquet" else df.write_csv(path)
    return path


@pytest.mark.parametrize("change, says", [
    (lambda d: d.with_columns(pl.format("{}x", "frame").alias("frame")), "row 1: frame is '0x', not an integer"),
    (lambda d: d.with_columns(pl.col("frame").cast(pl.Float64) + 0.5), "row 1: frame is 0.5, not an integer"),
    (lambda d: d.with_columns(pl.when(pl.col("frame") == 2).then(pl.lit("gone")).otherwise("status").alias("status")),
     "row 3: status 'gone' is not one of measured, predicted, interpolated, lost"),
    (lambda d: pl.concat([d, d.slice(1, 1)]), "row 4: a second row for track 1 (flow) on frame 1: one row per track and frame"),
    (lambda d: d.with_columns(pl.when(pl.col("frame") == 1).then(pl.lit("lost")).otherwise("status").alias("status")),
     "row 2: a lost row of track 1 on frame 1 carries a position (x); lost rows have none"),
    (lambda d: d.with_columns(pl.col("frame") - 1), "row 1: frame -1 is negative"),
    (lambda d: d.with_columns(pl.lit(None, dtype=pl.String).alias("status")), "row 1: no status"),
])
def test_malformed_tables_are_refused_naming_the_row(tmp_path: Path, change, says: str) -> None:
    path = _written(tmp_path, change(_table([0, 1, 2], [1.0, 2.0, 3.0])))
    with pytest.raises(TrackreplayError) as err:
        read_trajectory(path)
    assert str(err.value).startswith(f"{path} {says}")


def test_a_csv_cell_that_is_not_a_number_is_one_sentence_naming_the_line(tmp_path: Path) -> None:
    path = _written(tmp_path, _table([0, 1, 2], [1.0, 2.0, 3.0]), "t.csv")
    lines = path.read_text().splitlines()
    lines[2] = lines[2].replace(",2.0,", ",abc,", 1)
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(TrackreplayError) as err:
        read_trajectory(path)
    assert str(err.value) == f"{path} line 3: x is 'abc', not a number"


@pytest.mark.parametrize("verb", ["export", "smooth", "eval"])
@pytest.mark.parametrize("case", ["text frame", "duplicate", "empty"])
def test_every_verb_refuses_a_bad_or_empty_table(tmp_path: Path, capsys, verb: str, case: str) -> None:
    """Once: a text frame column ended in an internal error (exit 70), duplicate rows made eval count
    102 frames of a 51-frame log and smooth crash, an empty table was exported and smoothed to an empty file."""
    from trackreplay.replay.cli.main import main

    golden = Path(__file__).resolve().parents[2] / "golden"
    table = read_trajectory(golden / "flow.trajectory.parquet")
    bad = {"text frame": table.with_columns(pl.col("frame").cast(pl.String) + "x"),
           "duplicate": pl.concat([table, table.head(1)]),
           "empty": table.clear()}[case]
    path = _written(tmp_path, bad)
    out = tmp_path / "out.parquet"
    argv = {"export": [str(path), str(out)], "smooth": [str(path), str(golden / "flow-sim1-24f.mcap"), "--out", str(out)],
            "eval": [str(path), str(golden / "flow-sim1-24f.mcap")]}[verb]
    assert main([verb, *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"trackreplay: error: {path} ") and "\n" not in err
    assert not out.exists()


def _long_tracks(seed: int = 0) -> pl.DataFrame:
    """Three tracks in replay order (frame by frame): positions with lost runs (short and long),
    absent frames, rows without a time, a world position on some rows only."""
    from trackreplay.replay.core.trajectory import SCHEMA

    rng = np.random.default_rng(seed)
    parts = []
    for tid, n in ((1, 900), (2, 40), (3, 500)):
        frame = np.sort(rng.choice(np.arange(n + n // 10), n, replace=False)) + 5 * tid
        status = np.where(rng.random(n) < 0.15, "lost", np.where(rng.random(n) < 0.1, "predicted", "measured"))
        status[(frame % 97) < 20] = "lost"  # long gaps, left lost
        pos = status != "lost"
        x = np.where(pos, 100 + 0.5 * frame + rng.normal(0, 1, n), np.nan)
        parts.append(pl.DataFrame({
            "tracker": ["flow"] * n, "track_id": tid, "frame": frame,
            "t_ns": np.where(rng.random(n) < 0.05, None, frame * 33_333_333).tolist(),
            "x": x, "y": x / 2, "w": np.where(pos, 10.0, np.nan), "h": np.where(pos, 12.0, np.nan),
            "vx": np.where(pos, 0.5, np.nan), "vy": np.where(pos, 0.25, np.nan),
            "X": np.where(pos & (frame % 3 == 0), frame / 10, np.nan), "Y": np.nan, "Z": np.nan,
            "dx": np.nan, "dy": np.nan, "dz": np.nan, "status": status, "confidence": np.where(pos, 0.9, np.nan),
        }, strict=False))
    df = pl.concat(parts).select(COLUMNS).cast(SCHEMA)
    return df.with_columns(pl.col(c).fill_nan(None) for c, t in SCHEMA.items() if t == pl.Float64).sort("frame", "track_id")


@pytest.mark.parametrize("method", ["linear", "cubic", "none"])
@pytest.mark.parametrize("suffix", [".parquet", ".csv"])
def test_a_spilled_trajectory_is_exported_in_pieces_as_a_whole(tmp_path: Path, method: str, suffix: str) -> None:
    """Issue 33: a spilled trajectory is gap-filled and written a piece at a time (a long track cut at
    known rows, short tracks together): the same rows as filling the whole table at once."""
    from trackreplay.replay.core.export import _pieces, export_trajectory
    from trackreplay.replay.core.trajectory import SpilledTrajectory, canonical_order

    table = _long_tracks()
    spill = tmp_path / "spill.parquet"
    table.write_parquet(spill, row_group_size=128)
    want = canonical_order(table) if method == "none" else fill_gaps(canonical_order(table), method, 15)
    assert sum(counts is not None for _, _, counts in _pieces(spill, 100, split=True)) >= 5  # cut into pieces
    out = tmp_path / f"t{suffix}"
    rows, filled = export_trajectory(SpilledTrajectory(spill), out, method, 15, rows=100)
    got = pl.read_parquet(out) if suffix == ".parquet" else pl.read_csv(out, schema=want.schema)
    assert got.equals(want, null_equal=True)
    assert (rows, filled) == (want.height, want.filter(pl.col("status") == "interpolated").height)
    if method == "linear":
        assert filled > 0


def test_a_spilled_replay_exports_as_it_would_in_memory(tmp_path: Path) -> None:
    """`replay --export` hands the replay's spill file to export_trajectory: the golden flow log replayed
    with a tiny spill bound and exported a few frames at a time gives the in-memory table's gap filling."""
    from trackreplay.replay.core.engine import ReplayRequest, replay
    from trackreplay.replay.core.export import export_trajectory
    from trackreplay.replay.core.trajectory import SpilledTrajectory

    result = replay(ReplayRequest(log=Path(__file__).resolve().parents[2] / "golden" / "flow-sim1-24f.mcap",
                                  tracker="flow", spill_rows=4))
    assert isinstance(result.table, SpilledTrajectory)
    out = tmp_path / "t.parquet"
    export_trajectory(result.table, out, "linear", 15, rows=6)
    assert pl.read_parquet(out).equals(fill_gaps(result.trajectory, "linear", 15), null_equal=True)


@pytest.mark.parametrize("method", ["linear", "cubic", "none"])
@pytest.mark.parametrize("suffix", [".parquet", ".csv"])
def test_export_of_a_parquet_file_streams_its_checks_and_pieces(tmp_path: Path, monkeypatch, capsys, method: str,
                                                                 suffix: str) -> None:
    """Issue 33: `trackreplay export TRAJ.parquet OUT` checks the file a piece at a time and exports it a
    piece at a time, each piece cast as reading the whole file casts it (here: Float32 positions, Int32
    ids, no confidence column, an extra column): the same rows and counts as the whole-table path."""
    from trackreplay.replay.cli.commands import export as export_cmd
    from trackreplay.replay.cli.main import main
    from trackreplay.replay.core import export as ex

    table = _long_tracks().drop("confidence").with_columns(
        pl.col("x", "y").cast(pl.Float32), pl.col("track_id").cast(pl.Int32), pl.lit("rts").alias("fill"))
    src = tmp_path / "in.parquet"
    table.sample(fraction=1.0, shuffle=True, seed=2).write_parquet(src, row_group_size=64)  # in no order
    want = read_trajectory(src)
    want = want if method == "none" else fill_gaps(want, method, 15)
    monkeypatch.setattr(ex, "EXPORT_ROWS", 100)
    streamed: list = []
    real = ex.export_trajectory
    monkeypatch.setattr(export_cmd, "export_trajectory",
                        lambda t, *a, **k: streamed.append(t) or real(t, *a, **{**k, "rows": 100}))
    out = tmp_path / f"t{suffix}"
    assert main(["export", str(src), str(out), "--interpolate", method]) == 0
    assert len(streamed) == 1 and isinstance(streamed[0], ex.CheckedParquet)
    got = pl.read_parquet(out) if suffix == ".parquet" else pl.read_csv(out, schema=want.schema)
    assert got.equals(want, null_equal=True)
    filled = want.filter(pl.col("status") == "interpolated").height
    assert f"{want.height} rows, {filled} interpolated" in capsys.readouterr().out
    table.vstack(table.head(1)).write_parquet(src)  # a second row for one track and frame: read whole, named
    assert main(["export", str(src), str(out)]) != 0
    assert "a second row for track" in capsys.readouterr().err and len(streamed) == 1


def _csv_table(rows: int = 900) -> pl.DataFrame:
    """Three tracks of ``rows`` frames in all, gaps and lost rows, shuffled, with a ``fill`` column."""
    rng = np.random.default_rng(4)
    states = []
    for tid in (1, 2, 3):
        for f in range(rows // 3):
            lost = rng.random() < 0.1
            pos = {} if lost else {"x": float(f) + rng.random(), "y": 2.0 * f, "w": 5.0, "h": 5.0, "vx": 1.0, "vy": 2.0}
            states.append(state_row("flow", f, f * 33_333_333, TrackState(
                tid, **pos, status="lost" if lost else "measured", confidence=None if lost else float(rng.uniform(0.1, 1.0)))))
    table = trajectory_table(states)
    return table.with_columns(pl.lit("rts").alias("fill")).sample(fraction=1.0, shuffle=True, seed=0)


def test_a_csv_trajectory_read_in_pieces_is_the_whole_read(tmp_path: Path, monkeypatch) -> None:
    """Issue 33: a CSV trajectory is read, cast and checked ``CSV_BYTES`` at a time (the typed rows
    kept, not the file as text): the same table as reading it whole; a defect anywhere falls back to the
    whole read, so its sentence is the same (a bad cell after an earlier defect, a frame twice across
    pieces)."""
    from trackreplay.replay.core import export

    path = tmp_path / "t.csv"
    _csv_table().write_csv(path)
    pieces = []
    real = export._csv_in_pieces
    monkeypatch.setattr(export, "_csv_in_pieces", lambda *a: pieces.append(real(*a)) or pieces[-1])
    monkeypatch.setattr(export, "CSV_BYTES", 4000)  # ~40 lines a piece
    got = read_trajectory(path, keep_fill=True)
    assert pieces[-1] is not None  # the pieces' path answered
    monkeypatch.setattr(export, "_csv_in_pieces", lambda *a: None)
    whole = read_trajectory(path, keep_fill=True)
    assert got.equals(whole, null_equal=True) and got.schema == whole.schema and "fill" in got.columns
    monkeypatch.setattr(export, "_csv_in_pieces", real)
    assert read_trajectory(path).equals(whole.drop("fill"), null_equal=True)

    lines = path.read_text().splitlines()
    header = lines[0].split(",")
    frame, x = header.index("frame"), header.index("x")

    def broken(edits: dict[int, tuple[int, str]], extra: list[str] = ()) -> Path:
        out = lines[:] + list(extra)
        for i, (col, value) in edits.items():
            cells = out[i].split(",")
            cells[col] = value
            out[i] = ",".join(cells)
        bad = tmp_path / f"bad{len(list(tmp_path.iterdir()))}.csv"
        bad.write_text("\n".join(out) + "\n")
        return bad

    for bad in (broken({5: (frame, "-3"), 800: (x, "abc")}), broken({}, [lines[700]])):
        messages = []
        for pieces_fn in (real, lambda *a: None):
            monkeypatch.setattr(export, "_csv_in_pieces", pieces_fn)
            with pytest.raises(TrackreplayError) as err:
                read_trajectory(bad)
            messages.append(str(err.value))
        assert messages[0] == messages[1]
    assert "not a number" in messages[0] or "second row" in messages[0]


@pytest.mark.parametrize("batch", [1, 3, 7, 64, 1000])
def test_ordered_tracks_are_whole_tracks_of_the_read_table(tmp_path: Path, batch: int) -> None:
    """Issue 33 (`smooth`): a file in canonical order read once from its start, ``batch`` rows at a time,
    gives whole tracks (short ones together up to ``rows``), the rows and types of read_trajectory's table."""
    from trackreplay.replay.core.export import ordered_tracks

    rng = np.random.default_rng(1)
    parts = []
    for tracker in ("colorpf", "flow"):
        for tid in range(1, 6):
            n = int(rng.integers(1, 40))
            parts.append(pl.DataFrame({"tracker": tracker, "track_id": tid, "frame": np.arange(n) + int(rng.integers(0, 5)),
                                       "t_ns": None, "x": rng.uniform(0, 9, n), "y": rng.uniform(0, 9, n),
                                       "status": "measured"}))
    from trackreplay.replay.core.trajectory import SCHEMA

    path = tmp_path / "t.parquet"
    table = pl.concat(parts, how="diagonal_relaxed")
    table.with_columns(pl.lit(None, dtype=t).alias(c) for c, t in SCHEMA.items() if c not in table.columns).write_parquet(path)
    whole = read_trajectory(path)
    pieces = list(ordered_tracks(path, rows=30, batch=batch))
    assert pl.concat(pieces).equals(whole, null_equal=True)
    keys = [set(p.select("tracker", "track_id").unique().iter_rows()) for p in pieces]
    assert all(not (a & b) for i, a in enumerate(keys) for b in keys[i + 1:])  # no track in two pieces
    assert all(p.height < 30 + 40 + batch for p in pieces) and (len(pieces) >= 3 or batch >= whole.height)


@pytest.mark.parametrize("method", ["linear", "none"])
@pytest.mark.parametrize("suffix", [".parquet", ".csv"])
def test_export_of_a_csv_file_streams_its_checks_and_pieces(tmp_path: Path, monkeypatch, capsys, method: str,
                                                             suffix: str) -> None:
    """Issue 33: `trackreplay export TRAJ.csv OUT` casts and checks the CSV a piece at a time into a temporary
    Parquet file and exports that a piece at a time: the same file and counts as the whole-table path; a
    defect is named in the whole read's sentence (a bad cell, a frame twice across pieces)."""
    from trackreplay.replay.cli.commands import export as export_cmd
    from trackreplay.replay.cli.main import main
    from trackreplay.replay.core import export as ex

    src = tmp_path / "in.csv"
    _csv_table().write_csv(src)
    monkeypatch.setattr(ex, "CSV_BYTES", 4000)  # ~40 lines a piece
    streamed: list = []
    real = ex.export_trajectory
    monkeypatch.setattr(export_cmd, "export_trajectory",
                        lambda t, *a, **k: streamed.append(t) or real(t, *a, **{**k, "rows": 100}))
    a, b = tmp_path / f"a{suffix}", tmp_path / f"b{suffix}"
    capsys.readouterr()
    assert main(["export", str(src), str(a), "--interpolate", method]) == 0
    said = capsys.readouterr().out
    assert len(streamed) == 1 and isinstance(streamed[0], ex.CheckedParquet)
    real_csv = ex.csv_as_parquet
    monkeypatch.setattr(ex, "csv_as_parquet", lambda *a: False)  # the whole table
    assert main(["export", str(src), str(b), "--interpolate", method]) == 0
    assert len(streamed) == 1 and said.replace(str(a), str(b)) == capsys.readouterr().out
    if suffix == ".csv":
        assert a.read_bytes() == b.read_bytes()
    else:
        assert pl.read_parquet(a).equals(pl.read_parquet(b), null_equal=True)
    assert not list(tmp_path.glob("*.partial"))

    lines = src.read_text().splitlines()
    x = lines[0].split(",").index("x")
    bad_cell = lines[:]
    cells = bad_cell[800].split(",")
    cells[x] = "abc"
    bad_cell[800] = ",".join(cells)
    for i, broken in enumerate((bad_cell, lines + [lines[700]])):
        bad = tmp_path / f"bad{i}.csv"
        bad.write_text("\n".join(broken) + "\n")
        errors = []
        for pieces in (real_csv, lambda *a: False):
            monkeypatch.setattr(ex, "csv_as_parquet", pieces)
            assert main(["export", str(bad), str(a)]) == 2
            errors.append(capsys.readouterr().err)
        assert errors[0] == errors[1] and ("not a number" in errors[0] or "second row" in errors[0])
    assert len(streamed) == 1


@pytest.mark.parametrize("method", ["linear", "cubic", "none"])
def test_a_spilled_trajectory_is_written_as_motchallenge_a_window_of_frames_at_a_time(tmp_path: Path, monkeypatch,
                                                                                        method: str) -> None:
    """Issue 33: MOTChallenge lines (sorted by frame) of a spilled trajectory are written from its filled pieces a
    few frames at a time: the same bytes as the whole table's, two trackers with the same track ids included."""
    from trackreplay.replay.core import export as ex
    from trackreplay.replay.core.export import export_trajectory, write_mot
    from trackreplay.replay.core.trajectory import SpilledTrajectory, canonical_order

    table = _long_tracks()
    table = pl.concat([table, table.with_columns(pl.lit("colorpf").alias("tracker"), pl.col("x") + 1.0)])
    spill = tmp_path / "spill.parquet"
    table.write_parquet(spill, row_group_size=128)
    want = canonical_order(table) if method == "none" else fill_gaps(canonical_order(table), method, 15)
    write_mot(want, tmp_path / "whole.txt")
    monkeypatch.setattr(ex, "MOT_FRAMES", 37)
    monkeypatch.setattr(ex, "write_trajectory", lambda *a, **k: pytest.fail("the whole table written"))
    rows, filled = export_trajectory(SpilledTrajectory(spill), tmp_path / "t.txt", method, 15, rows=100)
    assert (tmp_path / "t.txt").read_bytes() == (tmp_path / "whole.txt").read_bytes()
    assert (rows, filled) == (want.height, want.filter(pl.col("status") == "interpolated").height)
    assert len((tmp_path / "t.txt").read_text().splitlines()) == want.filter(
        pl.col("x").is_not_null() & (pl.col("status") != "lost")).height
