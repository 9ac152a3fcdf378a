"""The golf tracker on a synthetic broadcast tee shot (recorder.synth.golf): detection rate, pixel
error, landing re-initialisation and re-acquisition after the bounce, against the log's ground truth."""

from __future__ import annotations

import math

import numpy as np
import pytest

scene = pytest.importorskip("trackreplay.recorder.synth.golf.scene")

from trackreplay.recorder.synth.golf.flight import Launch  # noqa: E402
from trackreplay.recorder.synth.golf.operator import OperatorConfig  # noqa: E402
from trackreplay.replay.core import registry  # noqa: E402
from trackreplay.replay.core.engine import ReplayRequest, iter_steps  # noqa: E402
from trackreplay.replay.log.frames import FrameTopics, iter_frames  # noqa: E402
from trackreplay.replay.log.groundtruth import read_groundtruth  # noqa: E402
from trackreplay.replay.log.reader import LogReader  # noqa: E402
from trackreplay.trackers.golf import GolfConfig, GolfTracker  # noqa: E402

pytestmark = pytest.mark.slow  # minutes of synthetic scenes: run by `pytest -m slow` (CI runs both)

# A short shot at 640x360, the operator zoomed in twice as far as his 720p default so the ball has
# the same pixel size as there (3.5 px in the climb, 5 px at landing).
SHOT = dict(
    width=640, height=360, seed=3,
    launch=Launch(speed=32.0, elevation=24.0, azimuth=0.0, backspin_rpm=7000.0),
    operator=OperatorConfig(size_tee_px=20.0, size_launch_px=7.0, size_landing_px=14.0, size_ground_px=16.0),
)


@pytest.fixture(scope="module")
def teeshot(tmp_path_factory):
    path = tmp_path_factory.mktemp("golf") / "teeshot.mcap"
    summary = scene.write_golf_teeshot(path, scene.GolfSceneConfig(**SHOT))
    return path, summary


def replay_steps(path, config=None, seed=0):
    """The engine's own loop (LUTs built from every marked frame first), with the ground truth."""
    steps = iter_steps(ReplayRequest(log=path, tracker="golf", config=config, seed=seed))
    out = [(step.frame, list(step.states), step.intermediates) for step in steps]
    gt = {r["frame"]: r for r in read_groundtruth(LogReader(path)).filter(id=1).iter_rows(named=True)}
    return out, gt


def scores(out, gt, frames=None):
    hits, visible, errors = 0, 0, []
    for f, states, _ in out:
        if frames is not None and f.index not in frames:
            continue
        g = gt[f.index]
        if not g["visible"] or g["x"] is None:
            continue
        visible += 1
        s = states[0]
        if s.status == "measured":
            e = math.hypot(s.x - g["x"], s.y - g["y"])
            errors.append(e)
            hits += e <= 5.0
    return hits / visible, np.array(errors)


def test_tee_shot_detection_landing_and_reacquisition(teeshot):
    path, summary = teeshot
    out, gt = replay_steps(path)
    rate, errors = scores(out, gt)
    assert rate >= 0.65, rate  # the climb right after the launch is a blurred streak: not detectable
    assert np.median(errors) < 1.0
    assert all(inter.notice == "" for _, _, inter in out)  # encoders present: no notice
    # The EKF's ground contact, then its bounce, re-initialise the particles once the ball is missed at the landing ...
    landings = [f.index for f, _, inter in out if inter.reinit.kind in ("ekf_landing", "after_landing")]
    assert any(abs(k - summary.landing_frame) <= 3 for k in landings), (landings, summary.landing_frame)
    # ... and the ball is followed again once it rolls: nearly every frame from a second after it.
    after = set(range(summary.landing_frame + int(summary.fps), summary.frames))
    rate_after, _ = scores(out, gt, after)
    assert rate_after >= 0.9, rate_after
    # Lines of sight are unit vectors through the reported pixel under that frame's pose.
    for f, states, _ in out[::10]:
        s = states[0]
        if s.status == "measured":
            los = f.camera.line_of_sight(np.array([[s.x, s.y]]))[0]
            assert np.array([s.dx, s.dy, s.dz]) == pytest.approx(los)
    # The 3-D filter knows where the rolling ball is to a few per cent of its range.
    f, states, _ = out[-1]
    g = gt[f.index]
    s = states[0]
    truth = np.array([g["X"], g["Y"], g["Z"]])
    assert np.linalg.norm(np.array([s.X, s.Y, s.Z]) - truth) < 0.08 * np.linalg.norm(truth - f.camera.position)


def test_without_encoders_it_still_tracks_in_the_image(teeshot):
    """The same log with the camera poses taken out of the frames (so stepped by hand, not by the engine)."""
    import dataclasses

    path, _ = teeshot
    reader = LogReader(path)
    frames = [dataclasses.replace(f, camera=None, ptz=None, lens=None) for f in iter_frames(reader, FrameTopics.detect(reader))]
    tracker = GolfTracker(GolfConfig(), np.random.default_rng(0))
    marked = sorted({r.frame for r in frames[0].all_hints})
    tracker.prepare([(frames[k].image, [r for r in frames[0].all_hints if r.frame == k]) for k in marked])
    out = [(f, tracker.step(f), tracker.intermediates) for f in frames]
    gt = {r["frame"]: r for r in read_groundtruth(reader).filter(id=1).iter_rows(named=True)}
    notices = [inter.notice for _, _, inter in out if inter.notice]
    assert len(notices) == 1 and "image coordinates only" in notices[0]
    assert all(s[0].dx is None for _, s, _ in out)
    rate, errors = scores(out, gt)
    assert rate >= 0.6 and np.median(errors) < 1.0


@pytest.mark.skipif("golf" not in registry.NAMES, reason="the golf tracker is not registered with the engine yet")
def test_engine_replay_is_deterministic_and_prints_no_notice(teeshot, capsys):
    from trackreplay.replay.core.engine import ReplayRequest, replay

    path, summary = teeshot
    a = replay(ReplayRequest(log=path, tracker="golf", seed=5, end_s=4.0))
    b = replay(ReplayRequest(log=path, tracker="golf", seed=5, end_s=4.0))
    assert a.digest == b.digest
    assert a.trajectory.height > 0
    assert "golf" not in capsys.readouterr().err


def measured_off_the_ball(out, gt, px=10.0):
    """Frames reported ``measured`` more than ``px`` from the ball (or where it is not in view)."""
    return [f.index for f, states, _ in out if states[0].status == "measured"
            and (gt[f.index]["x"] is None or math.hypot(states[0].x - gt[f.index]["x"], states[0].y - gt[f.index]["y"]) > px)]


@pytest.mark.parametrize("fps", [120, 240])
def test_a_far_ball_among_cloud_puffs_at_high_frame_rates_is_never_a_puff(tmp_path, fps):
    """The descent at 120 and 240 fps: a 1-3 px ball among cloud puffs, the camera following. Found
    (before the fixes) 3 and 72 frames measured 20-50 px off the ball: the ground LUT, tried over open
    sky, passed the puffs; and a far ball rolling along the line of sight looked "at rest", so a miss
    opened a strike's wide search, in which any speck fits a 1 px target."""
    path = tmp_path / "shot.mcap"
    scene.write_golf_teeshot(path, scene.GolfSceneConfig(**{**SHOT, "seed": 1, "fps": float(fps), "duration": 3.0}))
    out, gt = replay_steps(path)
    assert measured_off_the_ball(out, gt) == []
    rate, errors = scores(out, gt)
    assert rate >= 0.4 and np.median(errors) < 1.0


def test_a_cloud_puff_too_big_for_the_ball_the_3d_filter_predicts_is_not_confirmed(tmp_path):
    """The default 720p shot at 240 fps, cut at 1 s: the ball leaves the picture's top, and once it
    is lost a cloud puff (96-133 px) moving with the tilting camera forms a tentative track that
    nothing else in view rivals. Found: confirmed, then 26 frames measured ~200 px off. The 3-D
    filter has the ball far enough that a ball that big would be a few metres from the lens. (Since
    blobs.complete_streak the ball is not lost there: the scene is replayed without it, as found.)"""
    path = tmp_path / "shot240.mcap"
    scene.write_golf_teeshot(path, scene.GolfSceneConfig(fps=240.0, duration=1.0))
    as_found = {"blobs": {"complete_streak": 0.0}}
    default, gt = replay_steps(path)
    assert measured_off_the_ball(default, gt) == []  # the defaults are honest on this scene too
    out, gt = replay_steps(path, config=as_found)
    assert measured_off_the_ball(out, gt) == []
    assert "too_near" in [inter.validation.verdict for _, _, inter in out]
    off, _ = replay_steps(path, config={**as_found, "validate": {"confirm_max_nearer": 0.0}})
    assert measured_off_the_ball(off, gt)  # without the check the puff is taken (the test can fail)


def test_a_streak_is_measured_at_its_centre_not_at_its_bright_end(tmp_path):
    """The default 720p shot (seed 0): climbing off its bounce the ball slows during the exposure and
    the far end of its streak is the brightest; one silhouette level kept that end alone, measured
    9.7 px from the ball (frame 195). Grown by hysteresis over the top-hat (blobs.complete_streak),
    the whole streak's centre is the ball's; no other frame moves by more than a pixel."""
    path = tmp_path / "shot.mcap"
    scene.write_golf_teeshot(path, scene.GolfSceneConfig(seed=0, duration=7.0))
    errors = {}
    for complete in (0.35, 0.0):
        out, gt = replay_steps(path, config={"blobs": {"complete_streak": complete}})
        errors[complete] = {f.index: math.hypot(s[0].x - gt[f.index]["x"], s[0].y - gt[f.index]["y"])
                            for f, s, _ in out if s[0].status == "measured" and gt[f.index]["x"] is not None}
    on, off = errors[0.35], errors[0.0]
    assert on.keys() == off.keys()
    fixed = [f for f in on if off[f] > 5.0 >= on[f]]
    assert fixed and all(on[f] < 1.0 for f in fixed)
    assert all(on[f] <= off[f] + 1.0 for f in on)
