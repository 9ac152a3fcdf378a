"""The golf flight fit pinned by the ground: bounce, roll and a launch the tracker missed (issue 13)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from trackreplay.recorder.synth.golf.flight import ROLL, BallModel, Launch, simulate_shot
from trackreplay.replay.analysis.flight import G, NAMES, FlightConfig, Observations, _fly, _initial, fit_flight, simulate
from trackreplay.trackers.golf.ball_flight import FittedLift, acceleration

pytestmark = pytest.mark.slow  # minutes of synthetic scenes: run by `pytest -m slow` (CI runs both)

CAMERA = np.array([-10.0, -2.0, 2.5])  # behind the tee, as the synthetic scenes' "behind" camera
FPS, T_LAUNCH = 30.0, 0.5


def _observe(traj, ball: BallModel, keep) -> tuple[Observations, np.ndarray, np.ndarray]:
    """Noiseless lines of sight (and apparent sizes) from CAMERA at the frames ``keep(t, phase)`` selects."""
    t = np.arange(int((T_LAUNCH + traj.rest_time + 1.0) * FPS)) / FPS
    s = traj.sample(t - T_LAUNCH)
    sel = keep(t - T_LAUNCH, s.phase)
    t, pos = t[sel], s.position[sel]
    rel = pos - CAMERA
    r = np.linalg.norm(rel, axis=1)
    fx = np.clip(150.0 * r, 1500.0, 25000.0)  # the operator zooms in on the far ball
    size = fx * ball.diameter / r
    return Observations(np.flatnonzero(sel), t, rel / r[:, None], size, fx, CAMERA), t, pos


@pytest.fixture(scope="module")
def drive():
    """The synthetic scenes' default drive (46 m/s at 22°, 8000 rpm) seen as the golf tracker sees it:
    on the tee, then lost for 1.4 s after the launch, found again, lost for 0.7 s at the first bounce,
    then the hops and the roll to rest on the ground."""
    ball = BallModel(friction=0.6, rolling_resistance=0.3)
    traj = simulate_shot(Launch(speed=46.0, elevation=22.0, azimuth=0.0, backspin_rpm=8000.0), ball)

    def keep(ts, phase):
        lost_launch = (ts >= 0.0) & (ts < 1.4)
        lost_landing = (ts >= traj.landing_time - 0.1) & (ts < traj.landing_time + 0.6)
        return ~lost_launch & ~lost_landing

    obs, _, _ = _observe(traj, ball, keep)
    fit = fit_flight(obs, FlightConfig(jackknife_blocks=0), FPS)
    return traj, fit


def test_landing_is_pinned_by_the_hops_and_the_roll(drive) -> None:
    traj, fit = drive
    rep = fit.report
    landing = np.array([v.value for v in rep.landing_point])
    # The end of the descent and the first bounce are missing; the hops and the roll after them (the
    # rolling ball's line of sight meets the known ground) place the landing within 0.7 % of carry
    # (1.0 m of 149 m; 0.5 % here, the rest is the model's lift law against the truth's). The
    # previous model (one horizontal retention for every impact, the launch time free) missed this
    # noiseless landing by 2.8 m (1.9 %).
    assert np.linalg.norm(landing[:2] - traj.landing_point[:2]) < 0.007 * traj.carry
    assert abs(rep.carry.value - traj.carry) < 0.007 * traj.carry
    assert abs(rep.apex_height.value - traj.apex_point[2]) < 0.4
    rest = np.array([v.value for v in rep.rest_point])
    assert np.linalg.norm(rest[:2] - traj.rest_point[:2]) < 0.3
    # The bounce parameters are the scene's own (restitution 0.4); the friction is capped (rolling
    # without slipping after the first impact), so only the landing backspin sets the hop's speed.
    assert abs(rep.restitution.value - 0.4) < 0.03


def test_the_launch_is_within_a_frame_of_the_last_tee_frame(drive) -> None:
    """The tracker loses the ball at the launch: the fit launches it before the next frame, not in
    the middle of the 1.4 s gap (where speed, launch time and lift trade off)."""
    _, fit = drive
    assert T_LAUNCH - 0.5 / FPS <= fit.report.launch_time.value <= T_LAUNCH + 1.0 / FPS + 1e-9


def test_no_launch_bound_without_frames_on_the_tee() -> None:
    """A track that starts in the air (marked over the sky) has no frame of the ball at rest: its
    first frame must not bound the launch (it did, and the 'beside' shot launched at its first frame)."""
    ball = BallModel(friction=0.6, rolling_resistance=0.3)
    traj = simulate_shot(Launch(speed=46.0, elevation=22.0, azimuth=0.0, backspin_rpm=8000.0), ball)
    on_tee, _, _ = _observe(traj, ball, lambda ts, phase: ~((ts >= 0.0) & (ts < 1.4)))
    in_air, _, _ = _observe(traj, ball, lambda ts, phase: ts >= 2.0)
    _, _, t_hi = _initial(on_tee, FlightConfig(), FPS)
    assert abs(t_hi - T_LAUNCH) < 1e-9  # the last frame on the tee is one frame before the launch
    _, _, t_hi = _initial(in_air, FlightConfig(), FPS)
    assert t_hi == math.inf


def test_bounce_model_matches_the_truths_impacts() -> None:
    """Coulomb friction capped at rolling without slipping: a ball landing with the truth's velocity
    and backspin hops and rolls to rest where the truth's does (given the truth's restitution and
    friction): the landing point is continuous with what follows."""
    ball = BallModel(friction=0.6, rolling_resistance=0.3, lift=False, drag_cd=0.0)
    launch = Launch(speed=30.0, elevation=35.0, azimuth=10.0, backspin_rpm=5000.0)
    truth = simulate_shot(launch, ball, dt=1e-4)
    # The fit's model with the same launch, no drag and no lift in the air; landing spin = the
    # truth's backspin surface speed at the landing (the spin decays with a 25 s e-folding time).
    spin = ball.radius * 5000.0 * 2 * math.pi / 60 * math.exp(-truth.landing_time / ball.spin_decay_s)
    theta = dict(t0=0.0, X0=0.0, Y0=0.0, Z0=ball.radius, speed=30.0, elevation=35.0, azimuth=10.0, cd=0.0, cl=0.0,
                 cl_slope=0.0, spin_tilt=0.0, restitution=ball.restitution, friction=ball.friction, landing_spin=spin,
                 roll_decel=ball.rolling_resistance * ball.gravity)
    shot = simulate(np.array([theta[n] for n in NAMES]), FlightConfig(step_s=1e-3, hop_lift=False), truth.rest_time + 1.0)
    assert np.linalg.norm(shot.landing_point[:2] - truth.landing_point[:2]) < 0.01
    assert abs(shot.rest_time - truth.rest_time) < 0.01
    assert np.linalg.norm(shot.rest_point[:2] - truth.rest_point[:2]) < 0.02
    # ... and rolling starts where the truth's does
    pos, phase = shot.at(np.array([truth.roll_start + 0.05]))
    assert phase[0] == ROLL


def test_the_inlined_rk4_stages_agree_with_one_acceleration() -> None:
    """``_fly`` writes the acceleration out once per RK4 stage (for speed): the four copies must be
    the shared model's physics. A plain RK4 over its one acceleration function (B1 with the fit's lift
    law B3), with drag, lift growing as the ball slows and a tilted spin axis, follows the same path
    to rounding."""
    kd, (l0, l1, v0) = 0.004, (0.003, 0.002, 47.0)
    w = tuple(float(c) for c in np.array([0.3, -0.9, 0.3]) / math.sqrt(0.99))  # a unit spin axis, as the fit's
    lift = FittedLift(l0, l1, v0)

    def accel(v):
        return np.array(acceleration(tuple(v), kd, G, w, lift))

    h = 1 / 60
    out: list[tuple] = []
    _, _, t_hit, hit = _fly((1.0, 2.0, 0.5), (40.0, 5.0, 17.0), 0.25, h, kd, (l0, l1, v0), w, 0.02, 30.0, 1, out)
    rows = np.array(out)
    assert hit and len(rows) > 100
    p, v = np.array([1.0, 2.0, 0.5]), np.array([40.0, 5.0, 17.0])
    for row in rows[1:-1]:  # the last row is the contact, interpolated within the step
        a1 = accel(v)
        a2 = accel(v + h / 2 * a1)
        a3 = accel(v + h / 2 * a2)
        a4 = accel(v + h * a3)
        p, v = p + h / 6 * (v + 2 * (v + h / 2 * a1) + 2 * (v + h / 2 * a2) + (v + h * a3)), v + h / 6 * (a1 + 2 * a2 + 2 * a3 + a4)
        np.testing.assert_allclose(row[1:7], np.concatenate([p, v]), rtol=1e-11, atol=1e-11)


def test_a_landing_no_frame_saw_is_not_reported() -> None:
    """The log ends during the descent, 0.1 s before the ball comes down: whatever the fit puts
    there is an extrapolation, so landing, carry and rest come out as NaN, with the reason; the
    launch and apex, which frames did see, are still reported; the bounce and roll parameters, which
    no frame constrained, are not."""
    ball = BallModel(friction=0.6, rolling_resistance=0.3)
    traj = simulate_shot(Launch(speed=46.0, elevation=22.0, azimuth=0.0, backspin_rpm=8000.0), ball)
    obs, _, _ = _observe(traj, ball, lambda ts, phase: ((ts < 0.0) | (ts >= 1.4)) & (ts < traj.landing_time - 0.1))
    rep = fit_flight(obs, FlightConfig(jackknife_blocks=0), FPS).report
    assert any("not seen after the fitted landing" in n for n in rep.notes), rep.notes
    unreported = (rep.carry, *rep.landing_point, rep.landing_time, rep.time_of_flight, *rep.rest_point, rep.rest_time)
    assert all(math.isnan(v.value) and math.isnan(v.std) for v in unreported)
    assert all(math.isnan(v.value) for v in (rep.restitution, rep.friction, rep.landing_spin, rep.roll_decel))  # no impact seen
    assert math.isfinite(rep.apex_height.value) and math.isfinite(rep.launch_speed.value)
