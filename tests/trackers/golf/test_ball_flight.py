"""The one ball-flight model (trackers.golf.ball_flight) and its three users: synthesiser, flight fit, landing EKF."""

from __future__ import annotations

import math

import numpy as np
import pytest

from trackreplay.trackers.golf import ball_flight as bf
from trackreplay.trackers.golf.config import EkfConfig, GolfConfig
from trackreplay.trackers.golf.landing import _substep_jacobian, predict_landing, propagate

BALL = bf.BallModel()


def test_gravity_and_drag_of_b1() -> None:
    assert bf.acceleration((0.0, 0.0, 0.0), 0.01, bf.GRAVITY) == (0.0, 0.0, -bf.GRAVITY)
    v = np.array([30.0, -4.0, 12.0])
    a = np.array(bf.acceleration(tuple(v), 0.01, 9.81))
    drag = a - [0.0, 0.0, -9.81]
    # quadratic drag, opposite the velocity: |a_drag| = k C_d |v|²
    assert np.linalg.norm(drag) == pytest.approx(0.01 * float(v @ v), rel=1e-12)
    assert np.allclose(np.cross(drag, v), 0.0, atol=1e-12) and float(drag @ v) < 0


def test_backspin_lifts_with_the_spin_law_of_b2() -> None:
    """A ball flying along +X with backspin (axis -Y, the launch's "right"): the Magnus term points up,
    perpendicular to the velocity, of size k C_L |v|² with C_L = S / (1 + 2S)."""
    k, r = BALL.k, BALL.radius
    v, w = (40.0, 0.0, 0.0), (0.0, -600.0, 0.0)
    plain = np.array(bf.acceleration(v, k * BALL.drag_cd, BALL.gravity))
    lifted = np.array(bf.acceleration(v, k * BALL.drag_cd, BALL.gravity, w, bf.SpinLift(k, r)))
    magnus = lifted - plain
    s = r * 600.0 / 40.0
    assert magnus[2] == pytest.approx(k * s / (1 + 2 * s) * 40.0**2, rel=1e-12)
    assert magnus[0] == 0.0 and magnus[1] == 0.0
    assert bf.spin_lift_coefficient(s) == pytest.approx(s / (1 + 2 * s))
    # no spin or no lift law: no Magnus term
    assert bf.acceleration(v, 0.0, 9.81, (0.0, 0.0, 0.0), bf.SpinLift(k, r)) == bf.acceleration(v, 0.0, 9.81)


def test_the_fits_lift_law_b3_grows_as_the_ball_slows() -> None:
    lift = bf.FittedLift(0.004, 0.002, 50.0)
    assert lift(50.0, 1.0) == pytest.approx(0.004 * 50.0)  # C_L0 at the launch speed
    assert lift(25.0, 1.0) / 25.0 == pytest.approx(0.004 + 0.002 * (50.0 / 25.0 - 1.0))
    assert lift(25.0, 2.0) == pytest.approx(lift(25.0, 1.0) / 2.0)  # per unit axis length


def test_drag_jacobian_is_the_derivative_of_b1() -> None:
    v = np.array([35.0, 3.0, -8.0])
    J = bf.drag_jacobian(v, 0.0047)
    eps = 1e-6
    numeric = np.stack([(np.array(bf.acceleration(tuple(v + eps * e), 0.0047, 9.81))
                         - np.array(bf.acceleration(tuple(v - eps * e), 0.0047, 9.81))) / (2 * eps) for e in np.eye(3)], axis=1)
    np.testing.assert_allclose(J, numeric, rtol=1e-6, atol=1e-9)
    assert not bf.drag_jacobian(np.zeros(3), 0.0047).any()


def test_the_ekf_steps_the_shared_equation_and_its_jacobian() -> None:
    """propagate is one Heun step of (B1) without lift, bit for bit; the EKF's unrolled F is
    ``F0 + h drag_jacobian`` bit for bit; the landing is the same Heun steps, to the ground."""
    rng = np.random.default_rng(3)
    g, k = EkfConfig().gravity, EkfConfig().drag_k
    for _ in range(50):
        x = np.concatenate([rng.normal(size=3) * 30 + [0, 0, 40], rng.normal(size=3) * 25])
        dt = float(rng.uniform(0.001, 0.02))
        a1 = np.array(bf.acceleration(tuple(x[3:]), k, g))
        v1 = x[3:] + dt * a1
        a2 = np.array(bf.acceleration(tuple(v1), k, g))
        heun = np.concatenate([x[:3] + 0.5 * dt * (x[3:] + v1), x[3:] + 0.5 * dt * (a1 + a2)])
        assert propagate(x, dt, g, k).tobytes() == heun.tobytes()
        F = np.eye(6)
        F[:3, 3:] = dt * np.eye(3)
        expected = F.copy()
        expected[3:, 3:] += dt * bf.drag_jacobian(x[3:], k)
        assert _substep_jacobian(x[3:], k, dt, F).tobytes() == expected.tobytes()
    x = np.array([0.0, 0.0, 30.0, 40.0, 0.0, 5.0])
    t, point = predict_landing(x, 0.02, g, k, 12.0, 0.02)
    steps = int(t // 0.02)
    state = x
    for _ in range(steps):
        state = propagate(state, 0.02, g, k)
    assert state[2] > 0.02 >= propagate(state, 0.02, g, k)[2]
    assert point[0] == pytest.approx(state[0], abs=2.0) and point[2] == 0.02


def test_an_impact_stops_the_slip_at_most_and_reverses_the_normal_speed() -> None:
    """(B4): with ample friction one impact leaves the contact point rolling (slip 0); with little, the
    friction impulse is μ times the normal one."""
    v, w = np.array([20.0, 0.0, -15.0]), np.array([0.0, -500.0, 0.0])  # backspin
    r = BALL.radius
    for mu in (0.05, 5.0):
        ball = bf.BallModel(friction=mu)
        v1, w1 = bf.impact(ball, v, w, 0.4)
        assert v1[2] == pytest.approx(0.4 * 15.0)
        slip0 = v[0] - r * w[1]
        slip1 = v1[0] - r * w1[1]
        jt = v[0] - v1[0]
        assert jt == pytest.approx(bf.friction_impulse(mu * 1.4 * 15.0, slip0))
        if mu > 1:
            assert slip1 == pytest.approx(0.0, abs=1e-9)  # rolling: the 2/7 cap
        else:
            assert jt == pytest.approx(mu * 1.4 * 15.0) and slip1 > 0


def test_a_roll_comes_to_rest_where_kinematics_says() -> None:
    s0, a = 6.0, 0.2 * 9.81
    t_rest = s0 / a
    assert bf.roll_distance(s0, a, t_rest) == pytest.approx(s0 * s0 / (2 * a))
    assert bf.no_slip(10.0, 7.0) == pytest.approx(10.0 - 2.0)  # 2/7 of the slip
    assert bf.hop_height(2.0, 9.81) == pytest.approx(4.0 / (2 * 9.81))


def test_one_set_of_constants_and_phases() -> None:
    """Every user takes its constants and phase codes from the one model."""
    from trackreplay.recorder.synth.golf import flight as synth
    from trackreplay.replay.analysis import flight as fit
    from trackreplay.replay.views.flight import COLOURS

    assert synth.PHASES is fit.PHASES is bf.PHASES and synth.BallModel is bf.BallModel
    assert (bf.TEE, bf.AIR, bf.BOUNCE, bf.ROLL, bf.REST) == tuple(bf.PHASES.index(p) for p in bf.PHASES)
    assert set(COLOURS) == set(bf.PHASES)
    assert fit.FlightConfig().ball == BALL and fit.G == bf.GRAVITY == EkfConfig().gravity
    assert fit.MIN_HOP_M == BALL.min_hop and fit.FlightConfig().spin_decay_s == BALL.spin_decay_s
    # the fit's k is the model's to rounding (its own order of operations, kept bit for bit)
    assert fit.air_k(BALL) == pytest.approx(BALL.k, rel=1e-15)
    # the EKF: the regulation ball's k C_d to two figures, its restitution; the tracker's ball size
    assert EkfConfig().drag_k == 0.0047 == pytest.approx(BALL.k * BALL.drag_cd, rel=0.01)
    assert EkfConfig().restitution == BALL.restitution and GolfConfig().ball_diameter_m == BALL.diameter
    assert math.isclose(BALL.area, math.pi * BALL.radius**2)
