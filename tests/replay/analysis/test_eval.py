import json

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
