"""Ball physics of the synthetic tee shot: analytic limits, drag, bounce, roll to rest."""

import math

import numpy as np
import pytest

from trackreplay.recorder.synth.golf.flight import AIR, BOUNCE, PHASES, REST, ROLL, TEE, BallModel, Launch, simulate_shot

VACUUM = BallModel(drag_cd=0.0, lift=False)


def test_without_air_the_flight_is_the_analytic_parabola() -> None:
    v, el = 40.0, 30.0
    traj = simulate_shot(Launch(speed=v, elevation=el, backspin_rpm=0.0), VACUUM)
    g = VACUUM.gravity
    th = math.radians(el)
    assert traj.carry == pytest.approx(v * v * math.sin(2 * th) / g, rel=1e-6)
    assert traj.landing_time == pytest.approx(2 * v * math.sin(th) / g, rel=1e-6)
    assert traj.apex_point[2] - VACUUM.radius == pytest.approx((v * math.sin(th)) ** 2 / (2 * g), rel=1e-4)
    # Sampled between integration steps (Hermite), the positions still follow the parabola.
    t = np.linspace(0.0, traj.landing_time, 37)
    f = traj.sample(t)
    assert f.position[:, 0] == pytest.approx(v * math.cos(th) * t, abs=1e-6)
    assert f.position[:, 2] - VACUUM.radius == pytest.approx(v * math.sin(th) * t - 0.5 * g * t * t, abs=1e-6)


def test_drag_shortens_and_backspin_lift_lengthens_the_carry() -> None:
    launch = Launch(speed=50.0, elevation=18.0, backspin_rpm=6000.0)
    vacuum = simulate_shot(launch, VACUUM).carry
    drag = simulate_shot(launch, BallModel(lift=False)).carry
    lift = simulate_shot(launch, BallModel()).carry
    assert drag < 0.8 * vacuum
    assert lift > drag
    # The default shot is a plausible par-3 tee shot.
    traj = simulate_shot(Launch(speed=46.0, elevation=22.0, backspin_rpm=8000.0), BallModel(friction=0.6, rolling_resistance=0.3))
    assert 120.0 < traj.carry < 180.0 and 15.0 < traj.apex_point[2] < 35.0
    land = traj.landing_velocity
    assert 30.0 < math.degrees(math.atan2(-land[2], math.hypot(land[0], land[1]))) < 60.0  # descent angle


def test_sidespin_curves_the_ball_left_and_azimuth_turns_the_line() -> None:
    draw = simulate_shot(Launch(speed=50.0, elevation=18.0, backspin_rpm=6000.0, sidespin_rpm=800.0))
    assert draw.landing_point[1] > 3.0
    turned = simulate_shot(Launch(speed=50.0, elevation=18.0, azimuth=90.0, backspin_rpm=6000.0))
    assert abs(turned.landing_point[0]) < 1e-6 and turned.landing_point[1] > 100.0


def test_a_dropped_ball_bounces_to_e_squared_of_its_height() -> None:
    h = 5.0
    ball = BallModel(drag_cd=0.0, lift=False, restitution=0.4)
    traj = simulate_shot(Launch(speed=0.0, backspin_rpm=0.0, position=(0.0, 0.0, h)), ball)
    drop = h - ball.radius
    assert traj.landing_time == pytest.approx(math.sqrt(2 * drop / ball.gravity), rel=1e-6)
    assert traj.bounce_apexes[0] == pytest.approx(ball.restitution**2 * drop, rel=1e-3)
    assert traj.bounce_apexes[1] == pytest.approx(ball.restitution**4 * drop, rel=1e-3)
    # With air, a bit lower still.
    airy = simulate_shot(Launch(speed=0.0, backspin_rpm=0.0, position=(0.0, 0.0, h)), BallModel(lift=False))
    assert 0.9 * ball.restitution**2 * drop < airy.bounce_apexes[0] < ball.restitution**2 * drop


def test_the_shot_bounces_rolls_and_comes_to_rest() -> None:
    traj = simulate_shot(Launch(speed=46.0, elevation=22.0, backspin_rpm=8000.0))
    assert len(traj.bounce_times) >= 2
    hops = np.array(traj.bounce_apexes)
    assert np.all(np.diff(hops) < 0)  # each hop lower than the last
    assert traj.landing_time < traj.roll_start < traj.rest_time < 30.0
    t = np.linspace(-0.5, traj.rest_time + 2.0, 800)
    f = traj.sample(t)
    order = {TEE: 0, AIR: 1, BOUNCE: 2, ROLL: 3, REST: 4}
    ranks = np.array([order[int(p)] for p in f.phase])
    assert np.all(np.diff(ranks) >= 0) and set(f.phase_names()) == set(PHASES)
    assert np.all(f.position[:, 2] >= traj.ball.radius - 1e-9)
    rest = f.phase == REST
    assert np.allclose(f.velocity[rest], 0.0) and np.allclose(f.position[rest], traj.rest_point)
    assert traj.rest_point[0] > traj.landing_point[0]  # rolled on forward
    # Position is continuous through the bounces (velocity is not).
    fine = traj.sample(np.arange(0.0, traj.rest_time, 1e-3))
    assert np.abs(np.diff(fine.position, axis=0)).max() < 0.06


def test_without_bounce_the_ball_checks_and_rolls_out() -> None:
    traj = simulate_shot(Launch(speed=46.0, elevation=22.0, backspin_rpm=8000.0), bounce=False)
    assert traj.bounce_times == () and traj.roll_start == traj.landing_time
    after = traj.sample(np.linspace(traj.landing_time, traj.rest_time + 1.0, 100))
    assert np.allclose(after.position[:, 2], traj.ball.radius)
    assert traj.rest_time > traj.landing_time
