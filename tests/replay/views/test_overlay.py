from pathlib import Path

import cv2
import numpy as np
import pytest

from trackreplay.recorder.image_codec import image_message
from trackreplay.recorder.writer import LogWriter
from trackreplay.replay.cli.main import main
from trackreplay.replay.core.export import write_trajectory
from trackreplay.replay.core.trajectory import state_row, trajectory_table
from trackreplay.schemas import topics as T
from trackreplay.schemas.records import LensEntry, LensTable, PtzReading
from trackreplay.trackers.base import TrackState
from trackreplay.trackers.geometry.ptz import PtzCamera, pan_tilt_towards

LENS = LensTable(320, 240, (LensEntry(0, 0, 300, 300, 160, 120), LensEntry(10, 0, 900, 900, 160, 120)), (0.0, 0.0, 1.5))
FRAMES = 10
MS = 1_000_000


def _scene(tmp_path: Path) -> tuple[Path, Path, np.ndarray]:
    """A camera panning after a ball on a world parabola; the trajectory holds its lines of sight."""
    t = np.arange(FRAMES) / 10.0
    world = np.stack([60 + 30 * t, 10 * t, 1.5 + 20 * t - 4.9 * 10 * t * t / 2], axis=1)
    log = tmp_path / "ptz.mcap"
    rows = []
    with LogWriter(log) as w:
        w.write(T.PTZ_LENS_TABLE, LENS.to_pb(0), 0)
        for k in range(FRAMES):
            pan, tilt = pan_tilt_towards(world[k] - LENS.camera_position)
            zoom = float(k)
            w.write(T.PTZ_ENCODERS, PtzReading(k * 100 * MS, pan, tilt, zoom, 0.0).to_pb(), k * 100 * MS)
            w.write(T.CAMERA_IMAGE, image_message(np.full((240, 320, 3), 40, np.uint8), "png", k * 100 * MS), k * 100 * MS)
            cam = PtzCamera.from_reading(PtzReading(0, pan, tilt, zoom, 0.0), LENS)
            d = cam.line_of_sight(np.array([[160.0, 120.0]]))[0]
            rows.append(state_row("golf", k, k * 100 * MS, TrackState(1, x=160.0, y=120.0, dx=d[0], dy=d[1], dz=d[2])))
    traj = write_trajectory(trajectory_table(rows), tmp_path / "traj.parquet")
    return log, traj, world


def test_overlay_draws_every_line_of_sight_where_the_other_pose_sees_it(tmp_path: Path) -> None:
    log, traj, world = _scene(tmp_path)
    out = tmp_path / "overlay.png"
    assert main(["overlay", str(log), str(traj), "--frame", "2", "--out", str(out)]) == 0
    image = cv2.imread(str(out))
    pan, tilt = pan_tilt_towards(world[2] - LENS.camera_position)
    cam = PtzCamera.from_reading(PtzReading(0, pan, tilt, 2.0, 0.0), LENS)
    expected = cam.project_points(world)
    inside = cam.in_image(expected)
    assert inside.sum() >= 3
    for u, v in expected[inside]:
        patch = image[int(v) - 2 : int(v) + 3, int(u) - 2 : int(u) + 3]
        assert (patch != 40).any(), f"nothing drawn near ({u:.1f}, {v:.1f})"
    assert (image[0:20, 0:20] == 40).all()  # away from the path the image is untouched


def test_overlay_video_and_errors(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    log, traj, _ = _scene(tmp_path)
    video = tmp_path / "o.avi"
    assert main(["overlay", str(log), str(traj), "--video", str(video)]) == 0
    cap = cv2.VideoCapture(str(video))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == FRAMES
    assert main(["overlay", str(log), str(traj), "--frame", "99", "--out", str(tmp_path / "x.png")]) == 2
    assert "has no frame 99" in capsys.readouterr().err
    # found by a review: an unknown image format was an internal error after the work, a missing track drew nothing
    assert main(["overlay", str(log), str(traj), "--frame", "1", "--out", str(tmp_path / "x.xyz")]) == 2
    assert "writes no image format by that name" in capsys.readouterr().err
    assert main(["overlay", str(log), str(traj), "--frame", "1", "--track-id", "7", "--out", str(tmp_path / "y.png")]) == 2
    assert "has no track 7 with lines of sight" in capsys.readouterr().err
    assert main(["flight", str(traj), str(log), "--track", "9"]) == 2
    assert "has no track 9" in capsys.readouterr().err
    assert main(["flight", str(traj), str(log), "--out", str(tmp_path / "f.xyz")]) == 2
    assert "a flight is written as .parquet or .csv" in capsys.readouterr().err
    assert main(["frame", str(log), "1", "--out", str(tmp_path / "f.png"), "--scale", "100000"]) == 2
    assert "at most 268435456 pixels" in capsys.readouterr().err
