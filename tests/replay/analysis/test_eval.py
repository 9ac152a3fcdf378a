import json
from pathlib import Path

import numpy as np
import polars as pl
import pytest

from trackreplay.replay.analysis.eval import evaluate
from trackreplay.replay.log.groundtruth import GT_SCHEMA
from trackreplay.replay.core.trajectory import state_row, trajectory_table
from trackreplay.trackers.base import TrackState


def _gt(n: int) -> pl.DataFrame:
    rows = [(f, f, 1, 10.0 + f, 20.0, 10.0, 10.0, None, None, None, 1.0, 0.0, True, None) for f in range(n)]
    return pl.DataFrame(rows, schema=GT_SCHEMA, orient="row")


def test_metrics_against_known_offsets() -> None:
    gt = _gt(10)
    rows = [state_row("flow", f, f, TrackState(1, x=13.0 + f, y=24.0, w=10.0, h=10.0, vx=1.5, vy=0.0)) for f in range(8)]
    summary, frames = evaluate(trajectory_table(rows), gt)
    assert summary.gt_frames == 10 and summary.tracked_frames == 8
    assert summary.centre_error_mean == pytest.approx(5.0)  # a 3-4-5 offset
    assert summary.precision_at_20px == pytest.approx(0.8)  # two missed frames count as failures
    assert summary.velocity_rmse_x == pytest.approx(0.5) and summary.velocity_rmse_y == pytest.approx(0.0)
    expected_iou = (7 * 6) / (200 - 42)
    assert summary.iou_mean == pytest.approx(expected_iou * 0.8)
    assert frames.height == 10


def test_frames_at_different_times_are_refused() -> None:
    """Frame k of the trajectory and of the truth must be the same moment (e.g. not a log cut or
    recovered without renumbering its ground truth)."""
    from trackreplay.schemas.errors import TrackreplayError

    gt = _gt(10)
    rows = [state_row("flow", f, f + (5 if f >= 4 else 0), TrackState(1, x=10.0 + f, y=20.0, w=10.0, h=10.0))
            for f in range(8)]
    with pytest.raises(TrackreplayError, match="frame 4 is at t=9 ns in the trajectory but at t=4 ns"):
        evaluate(trajectory_table(rows), gt)


def test_truth_that_places_nothing_is_one_sentence() -> None:
    """OTB's 0,0,0,0 rows mark the target absent: a file of only those once crashed eval (IndexError)."""
    from trackreplay.schemas.errors import TrackreplayError

    rows = [(f, f, 1, None, None, None, None, None, None, None, None, None, False, None) for f in range(3)]
    gt = pl.DataFrame(rows, schema=GT_SCHEMA, orient="row")
    traj = trajectory_table([state_row("flow", f, f, TrackState(1, x=1.0, y=1.0)) for f in range(3)])
    with pytest.raises(TrackreplayError, match="places no object on any frame"):
        evaluate(traj, gt)


# eval against a small recorded log: 8 frames at jittered epoch times, OTB truth (0,0,0,0 = not visible)

T0, STEP = 1_732_800_000_123_456_789, 33_333_333
TIMES = [T0 + k * STEP + (k % 3) for k in range(8)]  # ns jitter: interpolated times miss them
BOX = (20.0, 20.0, 10.0, 10.0)  # OTB x, y, w, h (1-based): centre (24, 24) here


def _recorded(tmp_path, truth: list[str]):
    """A log of ``len(truth)`` 64x64 images at ``TIMES`` with OTB truth lines ``truth``."""
    import cv2

    from trackreplay.replay.cli.main import main

    images = tmp_path / "img"
    images.mkdir()
    for k in range(len(truth)):
        cv2.imwrite(str(images / f"{k:03d}.png"), np.full((64, 64, 3), 40 + 20 * k, np.uint8))
    (tmp_path / "ts.txt").write_text("".join(f"{t}\n" for t in TIMES[: len(truth)]))
    (tmp_path / "gt.txt").write_text("".join(f"{line}\n" for line in truth))
    log = tmp_path / "log.mcap"
    assert main(["record", str(log), "--images", str(images), "--timestamps", str(tmp_path / "ts.txt"),
                 "--groundtruth", str(tmp_path / "gt.txt"), "--gt-format", "otb", "--quiet"]) == 0
    return log


def _boxes(frames, status="measured", times=TIMES) -> pl.DataFrame:
    return trajectory_table([state_row("flow", f, times[f], TrackState(1, x=24.0, y=24.0, w=10.0, h=10.0, status=status))
                             for f in frames])


def _mot(tmp_path, table: pl.DataFrame, log, *extra: str):
    from trackreplay.replay.cli.main import main
    from trackreplay.replay.core.export import write_trajectory

    traj = write_trajectory(table, tmp_path / f"t{len(list(tmp_path.glob('t*.parquet')))}.parquet")
    out = tmp_path / "m.json"
    code = main(["eval", str(traj), str(log), "--mot", "--json", str(out), *extra])
    return code, (json.loads(out.read_text(), parse_constant=_no_nan) if code == 0 else None)


def _no_nan(name: str):
    raise AssertionError(f"{name} in JSON")


def test_a_box_where_the_truth_shows_nothing_is_a_false_positive(tmp_path) -> None:
    """A review: a box reported on frames whose truth says the object is not visible (and has no box)
    was not counted at all, because such frames were dropped with their invisible truth."""
    log = _recorded(tmp_path, [",".join(map(str, BOX))] * 4 + ["0,0,0,0"] * 4)
    code, tracked = _mot(tmp_path, _boxes(range(4)), log)
    assert code == 0 and tracked["image"]["false_positives"] == 0 and tracked["image"]["mota"] == 1.0
    code, hidden = _mot(tmp_path, _boxes(range(8)), log)  # and on the 4 frames where nothing is visible
    assert code == 0
    assert hidden["image"]["false_positives"] == 4 and hidden["image"]["hypotheses"] == 8
    assert hidden["image"]["mota"] == pytest.approx(0.0)  # 1 - 4 FP / 4 truth
    assert hidden["hota"]["image"]["detpr"] == pytest.approx(0.5)  # 4 of the 8 predictions unmatched


def test_frames_without_any_truth_row_count_when_annotated() -> None:
    """A frame whose truth message lists no object (MOTChallenge frames with nobody) is annotated:
    a box there is a false positive; frames the truth does not annotate are left out."""
    from trackreplay.replay.analysis.mot import mot_metrics

    gt = _gt(3)
    traj = trajectory_table([state_row("flow", f, f, TrackState(1, x=10.0 + f, y=20.0, w=10.0, h=10.0)) for f in range(5)])
    assert mot_metrics(traj, gt).false_positives == 0
    assert mot_metrics(traj, gt, frames=range(4)).false_positives == 1


def test_eval_refuses_a_trajectory_not_from_the_log(tmp_path, capsys) -> None:
    from trackreplay.replay.cli.main import main
    from trackreplay.replay.core.export import write_trajectory

    log = _recorded(tmp_path, [",".join(map(str, BOX))] * 6)
    beyond = write_trajectory(_boxes(range(6)).vstack(_boxes([7])), tmp_path / "beyond.parquet")
    late = write_trajectory(_boxes(range(6)).with_columns(pl.col("t_ns") + 1), tmp_path / "late.parquet")
    for traj, says in ((beyond, "frame 7 (t="), (late, "frame 0 (t=")):
        for mot in ([], ["--mot"]):
            capsys.readouterr()
            assert main(["eval", str(traj), str(log), *mot]) == 2
            err = capsys.readouterr().err.strip()
            assert err.startswith(f"trackreplay: error: {traj}: {says}") and "\n" not in err
            assert "not replayed from this log" in err and str(log) in err


def test_interpolated_rows_keep_interpolated_times(tmp_path, capsys) -> None:
    """The export's gap filling gives added rows times between their neighbours': with a log's ns
    jitter they are not the frames' own, and eval once refused the tool's own export for it."""
    from trackreplay.replay.cli.main import main
    from trackreplay.replay.core.export import write_trajectory

    log = _recorded(tmp_path, [",".join(map(str, BOX))] * 8)
    holes = write_trajectory(_boxes([0, 1, 2, 6, 7]), tmp_path / "holes.parquet")
    filled = tmp_path / "filled.parquet"
    assert main(["export", str(holes), str(filled)]) == 0
    table = pl.read_parquet(filled)
    assert table.filter(pl.col("status") == "interpolated")["t_ns"].to_list() != TIMES[3:6]  # interpolated, not the log's
    for mot in ([], ["--mot"]):
        assert main(["eval", str(filled), str(log), *mot]) == 0
    # a measured row at an interpolated time is still refused
    write_trajectory(table.with_columns(pl.lit("measured").alias("status")), tmp_path / "claimed.parquet")
    capsys.readouterr()
    assert main(["eval", str(tmp_path / "claimed.parquet"), str(log)]) == 2
    assert "frame 3 (t=" in capsys.readouterr().err


def test_mot_on_a_2d_tracker_says_the_3d_block_does_not_apply(tmp_path, capsys) -> None:
    log = _recorded(tmp_path, [",".join(map(str, BOX))] * 3 + ["0,0,0,0"])
    code, m = _mot(tmp_path, _boxes(range(3)), log)
    assert code == 0
    out = capsys.readouterr().out
    assert "3-D positions (<= 1 m): not applicable (the trajectory has no X, Y, Z)" in out and "MOTA -1" not in out
    assert m["3d"] is None and m["hota"]["3d"] is None and m["3d_not_applicable"] == "the trajectory has no X, Y, Z"
    code, m = _mot(tmp_path, _boxes([3]), log)  # no match at all: MOTP undefined, null in the JSON
    assert code == 0 and m["image"]["motp"] is None


def test_a_match_distance_that_is_not_positive_is_refused(capsys) -> None:
    """A review: ``--max-distance-m -1`` printed a LocA above 1 and exited 0."""
    from trackreplay.replay.cli.main import main

    for bad in ("-1", "0", "nan"):
        with pytest.raises(SystemExit) as exit_:
            main(["eval", "t.parquet", "l.mcap", "--mot", "--max-distance-m", bad])
        assert exit_.value.code == 2
        assert "--max-distance-m" in capsys.readouterr().err


def _long_case(n: int = 300) -> tuple[pl.DataFrame, pl.DataFrame]:
    """A track with gaps (no row), predicted and lost rows, boxes of varying overlap, and a truth that
    is invisible on some frames and has no box or velocity on others; a second track as a distractor."""
    rng = np.random.default_rng(3)
    gt_rows, rows = [], []
    for f in range(n):
        visible = f % 17 != 5
        box = f % 23 != 7
        gt_rows.append((f, 10 * f, 1, 50.0 + f * 0.5, 40.0, 8.0 if box else None, 6.0 if box else None, None, None, None,
                        (0.5 if f % 11 else None), 0.0, visible, None))
        if f % 13 in (3, 4):  # a gap: no row at all
            continue
        status = "lost" if f % 29 == 2 else ("predicted" if f % 7 == 1 else "measured")
        if status == "lost":
            rows.append(state_row("flow", f, 10 * f, TrackState(1, status="lost")))
            continue
        dx, dy = rng.normal(0, 4, 2)
        rows.append(state_row("flow", f, 10 * f, TrackState(1, x=50.0 + f * 0.5 + dx, y=40.0 + dy, w=8.0 + rng.normal(0, 1),
                                                            h=6.0, vx=0.5 + rng.normal(0, 0.1), vy=rng.normal(0, 0.1),
                                                            status=status)))
        rows.append(state_row("flow", f, 10 * f, TrackState(2, x=5.0, y=5.0, w=3.0, h=3.0)))
    gt = pl.DataFrame(gt_rows, schema=GT_SCHEMA, orient="row")
    return trajectory_table(rows), gt


@pytest.mark.parametrize("chunk", [7, 64, 10_000])
def test_chunked_evaluation_equals_the_whole_table(chunk: int) -> None:
    """The chunked path (a lazy scan, a few truth frames at a time) gives the very same summary as
    the whole per-frame table: every field equal to the bit, JSON alike."""
    from trackreplay.replay.analysis.eval import evaluate_chunked

    traj, gt = _long_case()
    assert (traj["status"] == "predicted").any() and (~gt["visible"]).any()
    whole, _ = evaluate(traj, gt, track_id=1)
    chunked = evaluate_chunked(traj.lazy(), gt, track_id=1, chunk_frames=chunk)
    assert json.dumps(chunked.as_dict()) == json.dumps(whole.as_dict())
    assert whole.measured_iou_50 is not None and whole.velocity_frames > 0 and whole.tracked_frames < whole.gt_frames
    shuffled = gt.sample(fraction=1.0, shuffle=True, seed=1)  # a truth not read in frame order is sorted first
    assert evaluate_chunked(traj.lazy(), shuffled, track_id=1, chunk_frames=chunk).as_dict() == whole.as_dict()


def test_chunked_evaluation_from_a_parquet_scan(tmp_path) -> None:
    """Through the checked Parquet scan: the track chosen alike, the same summary; a defective file is
    left to the whole read (None), which names the defect."""
    from trackreplay.replay.analysis.eval import checked_scan, evaluate_chunked
    from trackreplay.replay.core.export import write_trajectory

    traj, gt = _long_case()
    path = tmp_path / "t.parquet"
    write_trajectory(traj, path)
    scan, keys = checked_scan(path, chunk_rows=50)
    assert keys.height == traj.height and keys["frame"].to_list() == traj["frame"].to_list()
    whole, _ = evaluate(traj, gt)
    assert evaluate_chunked(scan, gt, chunk_frames=40).as_dict() == whole.as_dict()
    traj.vstack(traj.head(1)).write_parquet(tmp_path / "dup.parquet")  # a second row for one track and frame
    assert checked_scan(tmp_path / "dup.parquet", chunk_rows=50) is None


def test_chunked_evaluation_refuses_frames_at_other_times() -> None:
    from trackreplay.replay.analysis.eval import evaluate_chunked
    from trackreplay.schemas.errors import TrackreplayError

    gt = _gt(10)
    rows = [state_row("flow", f, f + (5 if f >= 4 else 0), TrackState(1, x=10.0 + f, y=20.0, w=10.0, h=10.0))
            for f in range(8)]
    with pytest.raises(TrackreplayError, match=r"frame 4 is at t=9 ns in the trajectory but at t=4 ns .*\(4 frame"):
        evaluate_chunked(trajectory_table(rows).lazy(), gt, chunk_frames=3)


def test_eval_of_one_track_reads_the_truth_a_chunk_at_a_time(tmp_path, monkeypatch, capsys, benchmark_module) -> None:
    """Issue 33: `eval` of one Parquet track against a log's one truth object reads the truth from the
    log a chunk at a time (truth_index, truth_parts) and checks the frames a piece at a time: the same
    --json as the whole table's path (--per-frame takes it), and the same sentence for a frame at
    another time."""
    from trackreplay.replay.analysis import eval as ev
    from trackreplay.replay.cli.main import main

    bench = benchmark_module("bench_long_log")
    log, traj = tmp_path / "long.mcap", tmp_path / "t.parquet"
    bench.write_long_log(log, 700)
    bench.write_spill(traj, 700)
    monkeypatch.setattr(ev, "EVAL_CHUNK_FRAMES", 64)
    monkeypatch.setattr(ev, "MATCH_ROWS", 50)
    used: list = []
    real = ev.truth_parts
    monkeypatch.setattr(ev, "truth_parts", lambda *a, **k: used.append(a[2]) or real(*a, **k))
    from trackreplay.replay.cli.commands import eval_cmd

    monkeypatch.setattr(eval_cmd, "truth_parts", ev.truth_parts)
    assert main(["eval", str(traj), str(log), "--json", str(tmp_path / "a.json")]) == 0
    assert used == [1]
    assert main(["eval", str(traj), str(log), "--json", str(tmp_path / "b.json"), "--per-frame",
                 str(tmp_path / "pf.parquet")]) == 0
    assert used == [1] and (tmp_path / "a.json").read_text() == (tmp_path / "b.json").read_text()
    table = pl.read_parquet(traj)
    frame = int(table.filter((pl.col("frame") > 300) & (pl.col("status") == "measured"))["frame"][0])
    moved = table.with_columns(pl.when(pl.col("frame") == frame).then(pl.col("t_ns") + 5).otherwise(pl.col("t_ns")).alias("t_ns"))
    moved.write_parquet(traj)
    capsys.readouterr()
    assert main(["eval", str(traj), str(log)]) != 0
    chunked = capsys.readouterr().err
    assert main(["eval", str(traj), str(log), "--per-frame", str(tmp_path / "pf.parquet")]) != 0
    assert f"frame {frame} " in chunked and chunked == capsys.readouterr().err


@pytest.mark.parametrize("missing", [False, True])
def test_frame_times_compared_a_piece_at_a_time_as_whole(missing: bool) -> None:
    from trackreplay.replay.analysis.eval import _mismatches
    from trackreplay.replay.core.trajectory import frame_time_mismatches

    rng = np.random.default_rng(4)
    n = 500
    frames = np.sort(rng.integers(0, 300, n))  # a frame on several rows (several tracks)
    a = pl.DataFrame({"frame": frames, "t_ns": frames * 10 + (rng.random(n) < 0.05),
                      "status": rng.choice(["measured", "lost", "predicted"], n)})
    bf = rng.permutation(np.arange(0, 300))[:280]  # some frames missing, in no order
    b = pl.DataFrame({"frame": np.concatenate([bf, bf[:5]]), "t_ns": np.concatenate([bf * 10, bf[:5] * 10 + 1])})
    for table in (a, a.sample(fraction=1.0, shuffle=True, seed=1)):  # by frame, or by track then frame
        whole = frame_time_mismatches(table, b, missing=missing)
        assert whole.height > 5
        for rows in (1, 7, 64, 499):
            assert _mismatches(table, b, missing=missing, rows=rows).equals(whole, null_equal=True)


@pytest.mark.parametrize("extra", [[], ["--per-frame", "pf.parquet"]], ids=["truth-in-chunks", "whole-table"])
def test_eval_of_a_log_time_beyond_int64_is_one_sentence(tmp_path, capsys, extra) -> None:
    """Issue 33, defect 3, through `eval` (its own truth and image passes): exit 2, one sentence."""
    import importlib.util

    from trackreplay.replay.cli.main import main

    golden = Path(__file__).resolve().parents[2] / "golden"
    spec = importlib.util.spec_from_file_location("log_mutations", golden.parent / "fuzz" / "log_mutations.py")
    mutations = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mutations)
    log = mutations.rewrite(golden / "flow-sim1-24f.mcap", tmp_path / "t.mcap", time=2**63, at=5, library="test")
    capsys.readouterr()
    argv = ["eval", str(golden / "flow.trajectory.parquet"), str(log)] + [str(tmp_path / e) if e.endswith(".parquet") else e
                                                                           for e in extra]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "beyond the signed 64-bit range" in err[0] and "internal error" not in err[0]


@pytest.mark.parametrize("objects", [0, 2], ids=["truth-places-nothing", "two-objects"])
def test_eval_of_one_track_when_the_truth_has_no_single_object(tmp_path, capsys, objects: int, benchmark_module) -> None:
    """The truth read in chunks is for one truth object: a truth that places none is refused in the
    whole-table path's sentence, and two objects are told apart by the whole table (the object the
    track lies on), with the same --json as with --per-frame."""
    from trackreplay.recorder.image_codec import compressed_image
    from trackreplay.recorder.writer import LogWriter
    from trackreplay.replay.cli.main import main
    from trackreplay.schemas import topics as T
    from trackreplay.schemas.records import GroundTruthFrame, GroundTruthObject

    bench = benchmark_module("bench_long_log")
    log, traj = tmp_path / "t.mcap", tmp_path / "t.parquet"
    bench.write_spill(traj, 60)
    picture = bench.cv2.imencode(".png", np.zeros((8, 8), np.uint8))[1].tobytes()
    with LogWriter(log) as out:
        for i in range(60):
            t_ns = i * 1_000_000_000 // 30
            out.write(T.CAMERA_IMAGE, compressed_image(picture, "png", t_ns, "camera"), t_ns)
            here = (GroundTruthObject(id=1, visible=False),) if objects == 0 else (
                GroundTruthObject(id=1, x=15.5, y=15.5, w=5.0, h=5.0, visible=True),
                GroundTruthObject(id=2, x=3.0, y=3.0, w=5.0, h=5.0, visible=True))
            out.write(T.GROUNDTRUTH, GroundTruthFrame(i, t_ns, here).to_pb(), t_ns)
    capsys.readouterr()
    code = main(["eval", str(traj), str(log), "--json", str(tmp_path / "a.json")])
    first = capsys.readouterr()
    whole = main(["eval", str(traj), str(log), "--json", str(tmp_path / "b.json"), "--per-frame", str(tmp_path / "p.csv")])
    second = capsys.readouterr()
    assert "internal error" not in first.err and first.err == second.err and code == whole
    if objects == 0:
        assert code == 2 and "places no object" in first.err
    else:
        assert code == 0 and (tmp_path / "a.json").read_text() == (tmp_path / "b.json").read_text()


def test_eval_of_one_track_among_several_objects_reads_the_truth_a_chunk_at_a_time(tmp_path, monkeypatch, capsys,
                                                                                     benchmark_module) -> None:
    """Issue 33: one track against a truth of several objects (no --gt-id) finds the object it lies on most
    often from the log's truth a chunk at a time, then scores it a chunk at a time: the whole truth table is
    never read, and the printed choice and --json are the whole table's (--per-frame takes that path)."""
    from trackreplay.recorder.image_codec import compressed_image
    from trackreplay.recorder.writer import LogWriter
    from trackreplay.replay.analysis import eval as ev
    from trackreplay.replay.cli.commands import eval_cmd
    from trackreplay.replay.cli.main import main
    from trackreplay.schemas import topics as T
    from trackreplay.schemas.records import GroundTruthFrame, GroundTruthObject

    bench = benchmark_module("bench_long_log")
    log, traj = tmp_path / "t.mcap", tmp_path / "t.parquet"
    bench.write_spill(traj, 300)  # the track circles (15.5, 15.5) at radius 6
    picture = bench.cv2.imencode(".png", np.zeros((8, 8), np.uint8))[1].tobytes()
    with LogWriter(log) as out:
        for i in range(300):
            t_ns = i * 1_000_000_000 // 30
            out.write(T.CAMERA_IMAGE, compressed_image(picture, "png", t_ns, "camera"), t_ns)
            here = [GroundTruthObject(id=7, x=15.5, y=15.5, w=30.0, h=30.0, visible=True)]  # under it everywhere
            if i % 4:  # placed on more frames, under the track on fewer of them
                here.append(GroundTruthObject(id=3, x=21.5, y=15.5, w=3.0, h=3.0, visible=i % 5 != 0))
            if i < 200:
                here.append(GroundTruthObject(id=5, x=15.5, y=15.5, w=40.0, h=40.0, visible=True))
            out.write(T.GROUNDTRUTH, GroundTruthFrame(i, t_ns, tuple(here)).to_pb(), t_ns)
    monkeypatch.setattr(ev, "EVAL_CHUNK_FRAMES", 32)
    whole_reads: list = []
    real = eval_cmd.groundtruth_with_frames
    monkeypatch.setattr(eval_cmd, "groundtruth_with_frames", lambda *a, **k: whole_reads.append(1) or real(*a, **k))
    capsys.readouterr()
    assert main(["eval", str(traj), str(log), "--json", str(tmp_path / "a.json")]) == 0
    chunked = capsys.readouterr().out
    assert not whole_reads
    assert main(["eval", str(traj), str(log), "--json", str(tmp_path / "b.json"), "--per-frame", str(tmp_path / "p.csv")]) == 0
    assert whole_reads and chunked == capsys.readouterr().out
    assert chunked.splitlines()[0] == ("scoring track 1 (the trajectory's only one) against truth object 7, the one of 3 it "
                                       "lies on most often (--gt-id ID chooses)")
    assert (tmp_path / "a.json").read_text() == (tmp_path / "b.json").read_text()


@pytest.mark.parametrize("chunk", [1, 5, 64])
def test_the_object_followed_counted_a_chunk_at_a_time_is_the_whole_tables(chunk: int) -> None:
    from trackreplay.replay.analysis.eval import object_followed, object_followed_parts

    rng = np.random.default_rng(3)
    n = 120
    traj = pl.DataFrame({"track_id": rng.integers(1, 3, n), "frame": np.arange(n), "x": rng.uniform(0, 20, n),
                         "y": rng.uniform(0, 20, n)}).with_columns(pl.when(pl.col("frame") % 9 == 0).then(None)
                                                                   .otherwise(pl.col("x")).alias("x"))
    rows = [(f, f * 10, o, float(rng.uniform(0, 20)), float(rng.uniform(0, 20)), w, w, None, None, v)
            for f in range(n) for o, w, v in ((1, 8.0, True), (2, None, None), (3, 12.0, f % 3 != 0)) if rng.random() < 0.8]
    from trackreplay.replay.analysis.eval import TRUTH_COLUMNS

    gt = pl.DataFrame(rows, schema=TRUTH_COLUMNS, orient="row")
    for track_id in (1, 2):
        def parts(): return (gt.slice(a, chunk) for a in range(0, gt.height, chunk))
        assert object_followed_parts(traj, parts, track_id) == object_followed(traj, gt, track_id)
    assert object_followed_parts(traj, lambda: iter(()), 1) is None
