"""The one-camera source reading ahead (``ground.read_ahead``): MOG2 first taught frames spread over the
replayed window, with what stands anywhere for less than half of them replaced by the median, so a
person standing from the first frame is foreground; stereo logs never read ahead."""

from pathlib import Path

import cv2
import numpy as np
import polars as pl
import pytest

from trackreplay.replay.cli.main import main
from trackreplay.replay.core.api import replay_log
from trackreplay.trackers.base import READ_AHEAD_MAX
from trackreplay.trackers.groups import SPEC, GroupsConfig
from trackreplay.trackers.groups.config import GroundConfig
from trackreplay.trackers.groups.ground_depth import GroundDepth

W, H, F, CAM = 160, 120, 150.0, np.array([0.0, -2.0, 4.0])  # the camera of test_ground_replay.py
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

STAND = np.array([0.0, 5.0])  # where the person stands from the first frame (m on the ground)
LEAVES = 14  # the frame they start walking away (of FRAMES = 36: under half)


def _where(f: int) -> np.ndarray:
    return STAND if f < LEAVES else STAND + np.array([0.25 * (f - LEAVES + 1), 0.0])  # 2.5 m/s at 10 fps


def test_the_spec_reads_ahead_with_one_camera_only() -> None:
    on = GroupsConfig(ground=GroundConfig(read_ahead=30))
    assert SPEC.read_ahead(on, False) == 30 and SPEC.read_ahead(on, True) == 0
    assert SPEC.read_ahead(GroupsConfig(), False) == GroundConfig().read_ahead
    with pytest.raises(ValueError, match="ground.read_ahead"):
        GroundConfig(read_ahead=READ_AHEAD_MAX + 1)
    with pytest.raises(ValueError, match="ground.read_ahead"):
        GroundConfig(read_ahead=-1)


def _mog_mask(ground: GroundDepth, first: np.ndarray) -> np.ndarray:
    ground.start(10.0)
    return ground.foreground(first)


def test_a_person_standing_under_half_the_window_is_foreground_from_the_first_frame() -> None:
    rng = np.random.default_rng(0)
    plaza = rng.integers(80, 120, (60, 80, 3)).astype(np.uint8)
    frames = [np.clip(plaza.astype(np.int16) + rng.integers(-3, 4, plaza.shape), 0, 255).astype(np.uint8)
              for _ in range(20)]
    for f in frames[:8]:  # a dark person stands at rows 20-44, columns 30-40 in the first 8 of 20
        f[20:44, 30:40] = 20
    cfg = GroundConfig(open_px=0, close_px=0)
    without = GroundDepth(cfg, 4)
    for f in frames[:4]:
        without.add(f)
    assert not _mog_mask(without, frames[4])[20:44, 30:40].any()  # learnt as the plaza
    ahead = GroundDepth(cfg, 4)
    ahead.read_ahead(frames)
    assert len(ahead.ahead) == 20 and all((a[20:44, 30:40] != 20).all() for a in ahead.ahead)  # the median's plaza
    for f in frames[:4]:
        ahead.add(f)
    mask = _mog_mask(ahead, frames[4])
    assert mask[20:44, 30:40].mean() > 0.9 and mask.mean() < 0.1  # the person, not the plaza's noise
    assert ahead.ahead == [] and ahead.applied == 20 + 4 + 1  # read ahead, learnt, this frame: dropped once taught


@pytest.fixture(scope="module")
def standing_log(tmp_path_factory) -> Path:
    """A person standing still from the first frame until frame 14 of 36, then walking away."""
    import json

    folder = tmp_path_factory.mktemp("standing")
    rng = np.random.default_rng(4)
    floor = rng.integers(70, 110, (H, W, 3)).astype(np.uint8)
    skin = rng.integers(0, 255, (64, 32, 3)).astype(np.uint8)
    (folder / "frames").mkdir()
    for f in range(FRAMES):
        img = floor.copy()
        foot = _where(f)
        c = _project(np.array([[foot[0] - 0.25, foot[1], 1.7], [foot[0] + 0.25, foot[1], 0.0]]))
        x0, y0 = np.round(c[0]).astype(int)
        x1, y1 = np.round(c[1]).astype(int)
        x0c, x1c = max(x0, 0), min(x1, W)
        if x1c > x0c:
            img[y0:y1, x0c:x1c] = cv2.resize(skin, (x1 - x0, y1 - y0), interpolation=cv2.INTER_NEAREST)[:, x0c - x0:x1c - x0]
        cv2.imwrite(str(folder / "frames" / f"{f:04d}.png"), img)
    plane = folder / "plane.json"
    plane.write_text(json.dumps({"width": W, "height": H, "image_to_ground": _image_to_ground().tolist(),
                                 "camera_ground": CAM[:2].tolist(), "camera_height": float(CAM[2])}))
    log = folder / "standing.mcap"
    assert main(["record", str(log), "--images", str(folder / "frames"), "--fps", "10", "--ground-plane", str(plane),
                 "--quiet"]) == 0
    return log


def test_reading_ahead_finds_the_person_standing_from_the_first_frame_and_replays_the_same(standing_log: Path) -> None:
    config = {"ground": {"read_ahead": 30}}
    first = replay_log(standing_log, "groups", seed=0, config=config)
    second = replay_log(standing_log, "groups", seed=0, config=config)
    assert first.digest == second.digest
    standing = range(GroupsConfig().background.frames, LEAVES)  # after the first frames MOG2 learns, before they walk

    def near(result) -> set[int]:
        rows = result.trajectory.filter((pl.col("status") == "measured") & pl.col("frame").is_in(list(standing)))
        return {f for f, X, Y in rows.select("frame", "X", "Y").iter_rows() if np.hypot(X - STAND[0], Y - STAND[1]) < 1.0}

    assert len(near(first)) >= len(standing) // 2  # measured where they stand on most of those frames
    assert near(replay_log(standing_log, "groups", seed=0, config={"ground": {"read_ahead": 0}})) == set()  # MOG2's plaza


def test_reading_ahead_tracks_from_the_first_frame_at_the_log_s_rate(standing_log: Path) -> None:
    from trackreplay.replay.core.engine import ReplayRequest, iter_steps

    steps = iter_steps(ReplayRequest(log=standing_log, tracker="groups", config={"ground": {"read_ahead": 12}}))
    first = next(steps)
    assert first.intermediates.mode == "tracking" and steps.tracker.fps == pytest.approx(10.0)
    steps.close()
    steps = iter_steps(ReplayRequest(log=standing_log, tracker="groups"))
    assert next(steps).intermediates.mode == "learning"  # without: the first background.frames are learnt
    steps.close()


def test_held_to_the_window_s_median_the_standing_person_stays_foreground(standing_log: Path) -> None:
    """With ``read_ahead_hold`` MOG2 never learns the standing person (present on under half the window),
    so the region is foreground on every frame they stand; without it MOG2 absorbs them."""
    from trackreplay.replay.core.engine import ReplayRequest, iter_steps

    where = _project(np.array([[STAND[0], STAND[1], 1.0]]))[0].round().astype(int)  # a pixel of their body

    def shown(extra: dict) -> list[bool]:
        config = {"ground": {"read_ahead": 30, "open_px": 0, "close_px": 0, **extra}}
        steps = iter_steps(ReplayRequest(log=standing_log, tracker="groups", config=config))
        out = [bool(s.intermediates.fg_left[where[1], where[0]]) for s, _ in zip(steps, range(LEAVES))]
        steps.close()
        return out

    held = shown({"read_ahead_hold": True, "read_ahead_fresh": True})
    assert all(held)
    assert not all(shown({"read_ahead_fresh": True}))  # learnt at MOG2's fresh rate, from the first frame
