"""The synthetic broadcast camera: lens table, operator, encoders, and line-of-sight geometry."""

import math
from pathlib import Path

import numpy as np
import pytest

from trackreplay.recorder.synth.golf.flight import AIR, BOUNCE
from trackreplay.recorder.synth.golf.lens import COUNTS, BroadcastLens
from trackreplay.recorder.synth.golf.operator import EncoderModel, encoder_readings
from trackreplay.recorder.synth.golf.scene import GolfSceneConfig, logged_readings, plan_shot, write_golf_teeshot
from trackreplay.replay.log.frames import FrameTopics, iter_frames
from trackreplay.replay.log.groundtruth import read_groundtruth
from trackreplay.replay.log.reader import LogReader
from trackreplay.trackers.geometry.ptz import intrinsics_at


@pytest.fixture(scope="module")
def behind():
    return plan_shot(GolfSceneConfig())


def test_lens_table_spans_1x_to_20x_and_inverts() -> None:
    lens = BroadcastLens(1280, 720)
    table = lens.table((0.0, 0.0, 2.0))
    wide = intrinsics_at(table, 0, COUNTS)
    tele = intrinsics_at(table, COUNTS, COUNTS)
    assert tele.fx / wide.fx == pytest.approx(20.0)
    assert 50.0 < math.degrees(2 * math.atan(640 / wide.fx)) < 60.0
    assert abs(wide.cx - 639.5) < 5 and abs(tele.cy - 359.5) < 5
    for fx in (1500.0, 7000.0, 20000.0):
        assert intrinsics_at(table, float(lens.zoom_for_fx(fx)), COUNTS).fx == pytest.approx(fx, rel=2e-3)
    near = intrinsics_at(table, 5000, 0).fx / intrinsics_at(table, 5000, COUNTS).fx
    assert 1.0 < near < 1.02  # focus breathing: small
    assert BroadcastLens(1920, 1080).table((0, 0, 0)).entries[0].fx == pytest.approx(1.5 * table.entries[0].fx)


@pytest.mark.parametrize("camera", ["behind", "beside"])
def test_operator_keeps_the_ball_in_frame_and_zooms_in_as_it_comes_down(camera: str, behind) -> None:
    shot = behind if camera == "behind" else plan_shot(GolfSceneConfig(camera="beside"))
    flight = [tr for tr in shot.truth if tr.phase == AIR]
    assert np.mean([tr.in_frame for tr in flight]) > 0.9
    everything = [tr for tr in shot.truth if tr.phase != AIR]
    assert np.mean([tr.in_frame for tr in everything]) > 0.9
    apex = min(shot.truth, key=lambda tr: abs(tr.t - (shot.cfg.launch_at + shot.trajectory.apex_time)))
    landing = max((tr for tr in shot.truth if tr.phase == AIR), key=lambda tr: tr.t)
    assert landing.diameter > 1.2 * apex.diameter > 3.0
    _, _, zoom, _ = shot.path.at(np.array([apex.t, landing.t]))
    assert zoom[1] > zoom[0] + 1000
    # The operator lags at launch: the ball runs away from the centre, then is caught again.
    offs = [math.hypot(tr.uv[0] - 640, tr.uv[1] - 360) for tr in flight if tr.uv is not None]
    assert max(offs[:20]) > 100 and np.median(offs) < 60


def test_camera_widens_at_launch(behind) -> None:
    cfg = behind.cfg
    t = np.array([cfg.launch_at - 0.1, cfg.launch_at + 0.6])
    _, _, zoom, _ = behind.path.at(t)
    assert zoom[1] < zoom[0] - 500


def test_encoders_have_their_own_rate_quantisation_and_noise(behind) -> None:
    readings = logged_readings(behind)
    times = np.array([r.t_ns for r in readings])
    assert np.all(np.diff(times) == 10_000_000)  # 100 Hz, frames are at 30 fps
    assert len(readings) == int(behind.duration * 100) + 1
    pan = np.array([r.pan for r in readings])
    zoom = np.array([r.zoom for r in readings])
    assert np.allclose(pan / 0.001, np.round(pan / 0.001), atol=1e-6)
    assert np.all(zoom == np.round(zoom))
    true_pan, _, true_zoom, _ = behind.path.at(times / 1e9)
    err = pan - true_pan
    assert 0.0002 < np.std(err) < 0.002 and np.abs(err).max() < 0.005
    assert np.abs(zoom - true_zoom).max() <= 3.0
    exact = encoder_readings(behind.path, EncoderModel(noisy=False), np.random.default_rng(0), behind.duration)
    assert [r.pan for r in exact] == pytest.approx(list(true_pan), abs=1e-12)


def test_encoder_dropout_leaves_a_gap(behind) -> None:
    rng = np.random.default_rng(0)
    full = encoder_readings(behind.path, EncoderModel(), rng, 3.0)
    gap = encoder_readings(behind.path, EncoderModel(), np.random.default_rng(0), 3.0, dropout=(1.0, 1.5))
    t = np.array([r.t_ns for r in gap]) / 1e9
    assert not np.any((t >= 1.0) & (t < 1.5)) and np.any(t < 1.0) and np.any(t >= 1.5)
    # Outside the gap the readings (noise included) are the same as without it.
    kept = {r.t_ns: r for r in full}
    assert all(kept[r.t_ns] == r for r in gap)


def test_logged_exact_encoders_reproject_the_ground_truth(tmp_path: Path) -> None:
    """Replay's interpolated pose + lens table + GT world point lands on the GT pixel."""
    out = tmp_path / "exact.mcap"
    cfg = GolfSceneConfig(width=320, height=180, duration=2.5, encoder_noise=False, distractors=False)
    write_golf_teeshot(out, cfg)
    reader = LogReader(out)
    gt = read_groundtruth(reader)
    rows = {r["frame"]: r for r in gt.iter_rows(named=True)}
    errors = []
    for frame in iter_frames(reader, FrameTopics.detect(reader)):
        row = rows[frame.index]
        if row["x"] is None:
            continue
        uv = frame.camera.project_points(np.array([[row["X"], row["Y"], row["Z"]]]))[0]
        errors.append((frame.index, math.hypot(uv[0] - row["x"], uv[1] - row["y"])))
        # And the other way round: the line of sight through the GT pixel points at the ball.
        los = frame.camera.line_of_sight(np.array([[row["x"], row["y"]]]))[0]
        to_ball = np.array([row["X"], row["Y"], row["Z"]]) - frame.camera.position
        assert math.degrees(math.acos(min(1.0, los @ to_ball / np.linalg.norm(to_ball)))) < 0.05
    errors = np.array(errors)
    assert len(errors) > 60
    assert errors[errors[:, 0] % 3 == 0, 1].max() < 1e-6  # frames on an encoder tick: exact
    assert errors[:, 1].max() < 0.5  # between ticks: linear interpolation of a smooth path


def test_cut_jumps_the_pose_and_zooms_out() -> None:
    shot = plan_shot(GolfSceneConfig(cut_at=4.0))
    assert shot.cut_time == pytest.approx(4.0)
    k = int(round(shot.cut_time * shot.cfg.fps))
    before, after = shot.truth[k - 1], shot.truth[k]
    assert after.diameter < 0.45 * before.diameter  # 3x wider
    assert before.uv is not None and after.uv is not None
    assert math.hypot(after.uv[0] - before.uv[0], after.uv[1] - before.uv[1]) > 150  # ball off-centre
    recovered = shot.truth[k + 45]
    assert recovered.uv is not None and math.hypot(recovered.uv[0] - 640, recovered.uv[1] - 360) < 60
    assert recovered.diameter > 1.8 * after.diameter  # zooming back in
    assert all(tr.in_frame for tr in shot.truth[k : k + 45])
    assert shot.truth[k].phase in (AIR, BOUNCE)
