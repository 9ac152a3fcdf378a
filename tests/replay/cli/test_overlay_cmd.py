"""`trackreplay overlay` for trackers without lines of sight: flow, colour PF, groups (stereo), golf on plain video."""

from pathlib import Path

import cv2
import numpy as np
import polars as pl
import pytest
import rerun.chunk as rc

from trackreplay.replay.cli.main import main
from trackreplay.replay.core.export import write_trajectory
from trackreplay.replay.log.groundtruth import read_groundtruth
from trackreplay.replay.log.reader import LogReader
from trackreplay.replay.views.overlay import STATUS_BGR, TRUTH_BGR

GOLDEN = Path(__file__).resolve().parents[2] / "golden"


def _far_truth_corner(log: Path, traj: Path, frame: int, shape: tuple[int, int]) -> tuple[int, int]:
    """(row, column) of the bottom-right corner of a truth box on ``frame`` far from every track there."""
    truth = read_groundtruth(LogReader(log)).filter((pl.col("frame") == frame) & pl.col("w").is_not_null())
    tracks = pl.read_parquet(traj).filter((pl.col("frame") == frame) & pl.col("x").is_not_null())
    for x, y, w, h in truth.select("x", "y", "w", "h").iter_rows():
        col, row = int(round(x + w / 2)), int(round(y + h / 2))
        near = ((tracks["x"] - x).abs() < (tracks["w"] + w) / 2 + 10) & ((tracks["y"] - y).abs() < (tracks["h"] + h) / 2 + 10)
        if 0 <= row < shape[0] and 0 <= col < shape[1] and not near.any():
            return row, col
    raise AssertionError("no truth box away from the tracks on that frame")


def test_groups_overlay_draws_tracks_and_the_truth_of_a_stereo_log(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    log, traj = GOLDEN / "groups-crossing-320x240.mcap", GOLDEN / "groups.trajectory.parquet"
    out = tmp_path / "g.png"
    assert main(["overlay", str(log), str(traj), "--frame", "14", "--out", str(out)]) == 0
    assert "1 track position(s) and 5 truth object(s) on frame 14" in capsys.readouterr().out
    image = cv2.imread(str(out))
    row, col = _far_truth_corner(log, traj, 14, image.shape[:2])
    assert tuple(image[row, col]) == TRUTH_BGR
    track = pl.read_parquet(traj).filter(pl.col("frame") == 14).row(0, named=True)
    x0, y0 = int(round(track["x"] - track["w"] / 2)), int(round(track["y"] + track["h"] / 2))  # bottom-left
    assert tuple(image[min(y0, image.shape[0] - 1), x0]) == STATUS_BGR["measured"]
    bare = tmp_path / "bare.png"
    assert main(["overlay", str(log), str(traj), "--frame", "14", "--out", str(bare), "--no-truth"]) == 0
    assert tuple(cv2.imread(str(bare))[row, col]) != TRUTH_BGR


def test_colour_pf_video_has_every_frame_and_an_rrd(tmp_path: Path) -> None:
    log, traj = GOLDEN / "colorpf-approach-320x240.mcap", GOLDEN / "colorpf.trajectory.parquet"
    video, rrd = tmp_path / "c.avi", tmp_path / "c.rrd"
    assert main(["overlay", str(log), str(traj), "--video", str(video), "--rrd", str(rrd)]) == 0
    cap = cv2.VideoCapture(str(video))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 40
    frames = [f for c in rc.RrdReader(str(rrd)).stream() if str(c.entity_path) == "/overlay/image"
              for f in c.to_record_batch().column("frame").to_pylist()]
    assert sorted(frames) == list(range(40))


def test_golf_on_plain_video_is_drawn_from_its_image_positions(tmp_path: Path) -> None:
    """A golf trajectory without lines of sight (no encoders): boxes, not projected directions."""
    log = GOLDEN / "golf-teeshot-640x360.mcap"
    table = pl.read_parquet(GOLDEN / "golf.trajectory.parquet").with_columns(
        pl.lit(None, dtype=pl.Float64).alias(c) for c in ("dx", "dy", "dz"))
    traj = write_trajectory(table, tmp_path / "plain.parquet")
    out = tmp_path / "p.png"
    assert main(["overlay", str(log), str(traj), "--frame", "5", "--out", str(out), "--no-truth"]) == 0
    image = cv2.imread(str(out))
    row = table.filter(pl.col("frame") == 5).row(0, named=True)
    x0, y0 = int(round(row["x"] - row["w"] / 2)), int(round(row["y"] - row["h"] / 2))
    assert tuple(image[y0, x0]) == STATUS_BGR[row["status"]]
    # with lines of sight the same frame is the projected path (kept as it was), unless asked for positions
    with_sight = tmp_path / "s.png"
    assert main(["overlay", str(log), str(GOLDEN / "golf.trajectory.parquet"), "--frame", "5", "--out",
                 str(with_sight), "--image-positions", "--no-truth"]) == 0
    assert np.array_equal(cv2.imread(str(with_sight)), image)
