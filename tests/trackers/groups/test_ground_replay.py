"""`--tracker groups` on one camera with a ground plane: a small synthetic log of two textured
people walking side by side, replayed twice (the same digest), placed on the ground where they walk;
and the recorder's ground plane fitted to truth that places people on the ground."""

import json
from pathlib import Path

import cv2
import numpy as np
import polars as pl
import pytest

from trackreplay.replay.cli.main import main
from trackreplay.replay.core.api import replay_log
from trackreplay.replay.log.frames import FrameTopics, iter_frames
from trackreplay.replay.log.reader import LogReader
from trackreplay.schemas.errors import SourceError

W, H, F, CAM = 160, 120, 150.0, np.array([0.0, -2.0, 4.0])
TILT = np.radians(30.0)
FRAMES = 36


def _camera() -> tuple[np.ndarray, np.ndarray]:
    z = np.array([0.0, np.cos(TILT), -np.sin(TILT)])
    x = np.array([1.0, 0.0, 0.0])
    K = np.array([[F, 0.0, (W - 1) / 2], [0.0, F, (H - 1) / 2], [0.0, 0.0, 1.0]])
    return K, np.stack([x, np.cross(z, x), z], axis=1).T


def _project(points: np.ndarray) -> np.ndarray:
    K, R = _camera()
    p = (np.asarray(points, float) - CAM) @ R.T @ K.T
    return p[:, :2] / p[:, 2:]


def _image_to_ground() -> np.ndarray:
    K, R = _camera()
    return np.linalg.inv(K @ np.stack([R[:, 0], R[:, 1], -R @ CAM], axis=1))


def _people(f: int) -> list[np.ndarray]:
    """Two people 0.8 m apart walking across at 1 m/s, 6 m in front of the camera's foot."""
    x = -1.8 + f / 10.0
    return [np.array([x, 4.0]), np.array([x + 0.8, 4.0])]


def _write_clip(folder: Path) -> tuple[Path, Path]:
    """Frames (a grey textured floor, the people as textured 0.5 x 1.7 m boxes), the plane file and a MOT truth."""
    rng = np.random.default_rng(3)
    floor = rng.integers(70, 110, (H, W, 3)).astype(np.uint8)
    skins = [rng.integers(0, 255, (64, 32, 3)).astype(np.uint8) for _ in range(2)]
    images = folder / "frames"
    images.mkdir()
    truth = []
    for f in range(FRAMES):
        img = floor.copy()
        for pid, (foot, skin) in enumerate(zip(_people(f), skins), start=1):
            c = _project(np.array([[foot[0] - 0.25, foot[1], 1.7], [foot[0] + 0.25, foot[1], 0.0]]))
            x0, y0 = np.round(c[0]).astype(int)
            x1, y1 = np.round(c[1]).astype(int)
            img[y0:y1, x0:x1] = cv2.resize(skin, (x1 - x0, y1 - y0), interpolation=cv2.INTER_NEAREST)
            truth.append(f"{f + 1},{pid},{x0 + 1},{y0 + 1},{x1 - x0},{y1 - y0},1,{foot[0]:.4f},{foot[1]:.4f},0")
        cv2.imwrite(str(images / f"{f:04d}.png"), img)
    plane = folder / "plane.json"
    plane.write_text(json.dumps({"width": W, "height": H, "image_to_ground": _image_to_ground().tolist(),
                                 "camera_ground": CAM[:2].tolist(), "camera_height": float(CAM[2])}))
    gt = folder / "gt.txt"
    gt.write_text("\n".join(truth) + "\n")
    return plane, gt


@pytest.fixture(scope="module")
def clip(tmp_path_factory) -> tuple[Path, Path, Path]:
    folder = tmp_path_factory.mktemp("mono")
    plane, gt = _write_clip(folder)
    log = folder / "mono.mcap"
    assert main(["record", str(log), "--images", str(folder / "frames"), "--fps", "10", "--ground-plane", str(plane),
                 "--groundtruth", str(gt), "--quiet"]) == 0
    return folder, log, gt


def test_two_replays_of_a_mono_log_with_a_plane_agree_and_place_the_pair_on_the_ground(clip) -> None:
    _, log, _ = clip
    from trackreplay.replay.core.engine import ReplayRequest, replay

    first = replay_log(log, "groups", seed=0)
    second = replay_log(log, "groups", seed=0)
    threads = replay(ReplayRequest(log=log, tracker="groups", seed=1, opencv_threads=2))  # MOG2 runs per pixel
    assert first.digest == second.digest == threads.digest and first.position_frame == "world"
    measured = first.trajectory.filter(pl.col("status") == "measured")
    assert measured.height >= 10  # from the first frames after learning the background and a time window
    for f, X, Y, Z in measured.select("frame", "X", "Y", "Z").iter_rows():
        centre = np.mean(_people(f), axis=0)
        assert abs(X - centre[0]) < 0.6 and abs(Y - centre[1]) < 0.6 and 0.0 < Z < 1.7  # on the ground, in metres


def test_a_mono_log_without_a_plane_is_refused_in_one_sentence(clip, capsys) -> None:
    folder, log, _ = clip
    bare = folder / "bare.mcap"
    assert main(["filter", str(log), str(bare), "--topic", "/camera/image"]) == 0
    capsys.readouterr()
    assert main(["replay", str(bare), "--tracker", "groups", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "or one fixed camera with a ground plane" in err and err.count("\n") == 1


def test_the_plane_fitted_to_the_truth_is_the_camera_s(clip, capsys) -> None:
    """People all over the ground (the clip's pair walks one line: a line of feet fits no plane, and is refused)."""
    folder, _, line = clip
    with pytest.raises(SourceError, match="fit no plane"):
        from trackreplay.recorder.record import record

        record(folder / "line.mcap", images=folder / "frames", fps=10, groundtruth=line, ground_plane_from_truth=True)
    ground = np.random.default_rng(5).uniform([-2.0, 3.0], [2.0, 9.0], (3 * FRAMES, 2))
    feet = _project(np.c_[ground, np.zeros(len(ground))])
    gt = folder / "spread.txt"
    gt.write_text("".join(f"{k // 3 + 1},{k % 3 + 1},{u - 5 + 1:.2f},{v - 30 + 1:.2f},10,30,1,{X:.4f},{Y:.4f},0\n"
                          for k, ((u, v), (X, Y)) in enumerate(zip(feet, ground))))
    log = folder / "fitted.mcap"
    assert main(["record", str(log), "--images", str(folder / "frames"), "--fps", "10", "--groundtruth", str(gt),
                 "--ground-plane-from-truth"]) == 0
    assert f"ground plane fitted to the feet of {3 * FRAMES} truth rows" in capsys.readouterr().err
    frame = next(iter_frames(LogReader(log), FrameTopics.detect(LogReader(log), None, None)))
    plane = frame.ground_plane
    feet = _project(np.array([[0.5, 3.0, 0.0], [-1.0, 6.0, 0.0], [1.2, 8.0, 0.0]]))
    np.testing.assert_allclose(plane.to_ground(feet), [[0.5, 3.0], [-1.0, 6.0], [1.2, 8.0]], atol=0.01)
    np.testing.assert_allclose(plane.camera_ground, CAM[:2], atol=0.02)
    assert plane.camera_height == pytest.approx(CAM[2], abs=0.02) and plane.focal_px == pytest.approx(F, rel=0.01)


def test_the_plane_from_truth_needs_truth_with_ground_positions(clip, tmp_path) -> None:
    from trackreplay.recorder.record import record

    folder, _, gt = clip
    with pytest.raises(SourceError, match="give --groundtruth"):
        record(tmp_path / "a.mcap", images=folder / "frames", fps=10, ground_plane_from_truth=True)
    flat = tmp_path / "gt.txt"
    flat.write_text("\n".join(",".join(line.split(",")[:7]) for line in gt.read_text().splitlines()) + "\n")
    with pytest.raises(SourceError, match="ground position"):
        record(tmp_path / "b.mcap", images=folder / "frames", fps=10, groundtruth=flat, ground_plane_from_truth=True)
