"""GolfTracker end to end on small synthetic sequences (no log files): image mode, PTZ mode, determinism."""

import dataclasses
import math

import numpy as np
import pytest

from trackreplay.replay.core.digest import ReplayDigest
from trackreplay.trackers.frame import Frame
from trackreplay.trackers.golf import GolfConfig, GolfTracker
from trackreplay.trackers.golf.config import EkfConfig, ReinitConfig
from trackreplay.trackers.golf.notices import NO_ENCODER_NOTICE, NO_HINTS_NOTICE

BIG = 0.4  # m, the ball of the PTZ sequence (see conftest)


def run(tracker, frames):
    out = []
    for f in frames:
        out.append((tracker.step(f), tracker.intermediates))
    return out


def test_image_mode_tracks_and_says_so_once(image_sequence):
    track, frames = image_sequence()
    results = run(GolfTracker(GolfConfig(), np.random.default_rng(0)), frames)
    notices = [inter.notice for _, inter in results if inter.notice]
    assert notices == [NO_ENCODER_NOTICE]
    assert results[0][1].notice == NO_ENCODER_NOTICE
    errors, measured = [], 0
    for k, (states, inter) in enumerate(results):
        (s,) = states
        assert inter.mode == "image"
        assert s.dx is None and s.X is None  # no lines of sight without a camera pose
        if s.status == "measured":
            measured += 1
            errors.append(math.hypot(s.x - track[k, 0], s.y - track[k, 1]))
    assert measured >= 0.9 * len(frames)
    assert np.median(errors) < 0.5 and max(errors) < 2.0
    assert {inter.silhouette.lut_name for _, inter in results} == {"sky", "ground"}  # switched on the way up


def test_nothing_marked_nothing_tracked(backdrop, draw_ball):
    frame = Frame(0, 0, draw_ball(backdrop(), (300, 300), 5.0))
    tracker = GolfTracker(GolfConfig(), np.random.default_rng(0))
    assert tracker.step(frame) == []
    assert NO_HINTS_NOTICE in tracker.intermediates.notice
    assert tracker.intermediates.mode == "idle" and len(tracker.intermediates.particles.particles) == 0
    assert tracker.step(dataclasses.replace(frame, index=1)) == []
    assert tracker.intermediates.notice == ""


def digest_of(results) -> str:
    d = ReplayDigest()
    for k, (states, inter) in enumerate(results):
        d.add_frame(k, (inter, tuple(states)))
    return d._h.hexdigest()


def test_same_inputs_and_seed_give_identical_intermediates(image_sequence):
    _, frames = image_sequence(n=25)
    a = run(GolfTracker(GolfConfig(), np.random.default_rng(7)), frames)
    b = run(GolfTracker(GolfConfig(), np.random.default_rng(7)), frames)
    c = run(GolfTracker(GolfConfig(), np.random.default_rng(8)), frames)
    assert digest_of(a) == digest_of(b)
    assert digest_of(a) != digest_of(c)
    assert np.array_equal(a[-1][1].particles.particles, b[-1][1].particles.particles)


def test_ptz_mode_lines_of_sight_ekf_and_landing(ptz_sequence):
    world, uv, landing, frames = ptz_sequence()
    # the paper's re-initialisation at the predicted landing itself (the ball is measured throughout here)
    cfg = GolfConfig(ball_diameter_m=BIG, ekf=EkfConfig(drag_k=0.0), reinit=ReinitConfig(after_landing_frames=0))
    tracker = GolfTracker(cfg, np.random.default_rng(0))
    tracker.prepare([(frames[r.frame].image, [r]) for r in frames[0].all_hints])
    results = run(tracker, frames)
    assert all(inter.notice == "" for _, inter in results)
    events = [k for k, (_, inter) in enumerate(results) if inter.reinit.kind == "ekf_landing"]
    assert len(events) >= 1 and abs(events[0] - landing) <= 2
    measured = [k for k, (states, _) in enumerate(results) if states[0].status == "measured"]
    assert len(measured) >= 0.9 * len(frames)
    assert any(k > events[0] for k in measured[:]) and set(range(events[0] + 1, events[0] + 4)) & set(measured)
    cam = frames[0].camera
    for k in measured:
        s = results[k][0][0]
        los = np.array([s.dx, s.dy, s.dz])
        assert np.linalg.norm(los) == pytest.approx(1.0)
        assert los == pytest.approx(cam.line_of_sight(np.array([[s.x, s.y]]))[0])
    # Late in the flight the EKF knows where the ball is to a few per cent of the range.
    k = events[0] - 5
    s = results[k][0][0]
    rng = np.linalg.norm(world[k] - cam.position)
    assert np.linalg.norm(np.array([s.X, s.Y, s.Z]) - world[k]) < 0.08 * rng


def test_config_loads_nested_from_a_dict_or_toml_and_rejects_nonsense(tmp_path):
    from trackreplay.replay.core.config import config_from_dict, load_config
    from trackreplay.schemas.errors import TrackreplayError

    cfg = config_from_dict(GolfConfig, {"particles": {"n": 500, "sigma_px": 4.0}, "reinit": {"lost": "stay"}})
    assert cfg.particles.n == 500 and cfg.particles.sigma_px == 4.0 and cfg.reinit.lost == "stay"
    assert cfg.particles.alpha == GolfConfig().particles.alpha and cfg.lut == GolfConfig().lut
    toml = tmp_path / "golf.toml"
    toml.write_text("[golf]\nmax_predicted_frames = 3\n[golf.lut]\nball_weight = 500.0\n[golf.reinit]\nlanding = false\n")
    cfg = load_config(GolfConfig, toml, table="golf")
    assert (cfg.max_predicted_frames, cfg.lut.ball_weight, cfg.reinit.landing) == (3, 500.0, False)
    with pytest.raises(TrackreplayError, match="lost"):
        config_from_dict(GolfConfig, {"reinit": {"lost": "everywhere"}})
    with pytest.raises(TrackreplayError, match="unknown key particles.count"):
        config_from_dict(GolfConfig, {"particles": {"count": 10}})
    with pytest.raises(TrackreplayError, match="unknown"):
        config_from_dict(GolfConfig, {"n_particles": 10})  # the flat names of before are gone


def test_each_stage_gets_its_own_table():
    """A stage never holds the whole config (docs/architecture.md §1 Layers: shared parts take only their parameters)."""
    tracker = GolfTracker(GolfConfig(), np.random.default_rng(0))
    cfg = tracker.config
    assert tracker.luts.config is cfg.lut and tracker.ekf.config is cfg.ekf and tracker.range.config is cfg.range
    assert tracker.reinit.cfg is cfg.reinit and tracker.reinit.search is cfg.search
    for part in (tracker.luts, tracker.ekf, tracker.range, tracker.reinit):
        assert not any(isinstance(v, GolfConfig) for v in vars(part).values())


def _landing_run(frames, after_landing_frames: int):
    cfg = GolfConfig(ball_diameter_m=BIG, ekf=EkfConfig(drag_k=0.0), reinit=ReinitConfig(after_landing_frames=after_landing_frames))
    tracker = GolfTracker(cfg, np.random.default_rng(0))
    tracker.prepare([(frames[r.frame].image, [r]) for r in frames[0].all_hints])
    return run(tracker, frames)


def test_a_landing_predicted_while_the_ball_is_measured_moves_no_samples(ptz_sequence):
    world, uv, landing, frames = ptz_sequence()
    at_once = _landing_run(frames, 0)
    fired = next(k for k, (_, inter) in enumerate(at_once) if inter.reinit.kind == "ekf_landing")
    followed = _landing_run(frames, 30)  # the ball is found on every frame: the landing never lost it
    assert all(inter.reinit.kind not in ("ekf_landing", "after_landing") for _, inter in followed)
    assert all(states[0].status == "measured" for states, _ in followed[fired - 3:fired + 6])


def test_a_ball_missed_after_the_landing_is_searched_for_where_the_3d_filter_predicts_it(ptz_sequence):
    world, uv, landing, frames = ptz_sequence()
    fired = next(k for k, (_, inter) in enumerate(_landing_run(frames, 0)) if inter.reinit.kind == "ekf_landing")
    gone = list(frames)
    for k in (fired + 2, fired + 3):
        gone[k] = dataclasses.replace(frames[k], image=_without_ball(frames, uv, k))
    results = _landing_run(gone, 30)
    kinds = [inter.reinit.kind for _, inter in results]
    assert kinds[:fired + 3].count("after_landing") == 0 and "ekf_landing" not in kinds
    assert kinds[fired + 3] == kinds[fired + 4] == "after_landing"  # each frame after a miss
    for k in (fired + 3, fired + 4):
        reinit = results[k][1].reinit
        assert np.hypot(*(reinit.point - uv[k])) < 3.0 * np.hypot(*reinit.sigma)
    assert results[fired + 4][0][0].status == "measured"  # found again where the filter said
    assert kinds[fired + 5:].count("after_landing") == 0  # measured again: later misses are not the landing's
    # without it: the samples follow the image motion model through the two missing frames
    assert "after_landing" not in [inter.reinit.kind for _, inter in _landing_run(gone, 0)]


def _without_ball(frames, uv: np.ndarray, k: int) -> np.ndarray:
    """Frame ``k``'s picture with its ball painted over from frame ``k - 30`` (same backdrop, the ball far away)."""
    image, other = frames[k].image.copy(), frames[k - 30].image
    assert np.hypot(*(uv[k] - uv[k - 30])) > 60
    ys, xs = np.mgrid[0:image.shape[0], 0:image.shape[1]]
    near = np.hypot(xs - uv[k][0], ys - uv[k][1]) < 30
    image[near] = other[near]
    return image
