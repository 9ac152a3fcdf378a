import math

import numpy as np
import pytest

from trackreplay.recorder.synth.golf.flight import BallModel, Launch, simulate_shot
from trackreplay.schemas.records import LensEntry, LensTable, PtzReading
from trackreplay.trackers.geometry.ptz import PtzCamera, pan_tilt_towards
from trackreplay.trackers.golf.config import EkfConfig, RangeConfig
from trackreplay.trackers.golf.landing import MAX_REJECTIONS, BallisticEkf, EkfState, measurement_jacobian, predict_landing
from trackreplay.trackers.golf.range import RangeFromArea, nearer_than_predicted, range_from_area, range_rel_sigma
from trackreplay.trackers.golf.reinit import image_parabola_landing

LENS = LensTable(1280, 720, (LensEntry(0, 0, 1000, 1000, 640, 360), LensEntry(100, 0, 9000, 9000, 640, 360)), (-12.0, 18.0, 4.0))
FPS = 30.0
D = 0.04267


def follow(point: np.ndarray, diameter_px: float = 6.0) -> PtzCamera:
    """A camera aimed at ``point`` and zoomed so the ball looks ``diameter_px`` wide."""
    rel = point - np.array(LENS.camera_position)
    fx = diameter_px * np.linalg.norm(rel) / D
    zoom = float(np.clip((fx - 1000) / 80.0, 0, 100))
    return PtzCamera.from_reading(PtzReading(0, *pan_tilt_towards(rel), zoom, 0), LENS)


def observe(cam: PtzCamera, p: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, float]:
    uv = cam.project_points(p.reshape(1, 3))[0] + rng.normal(0.0, 0.5, 2)
    d = cam.intrinsics.fx * D / np.linalg.norm(p - cam.position)
    area = math.pi / 4 * d * d * (1 + rng.normal(0.0, 0.1))
    return uv, area


@pytest.mark.parametrize("lift", [False, True])
def test_predicted_landing_matches_the_simulated_flight(lift):
    traj = simulate_shot(Launch(speed=55.0, elevation=20.0, azimuth=3.0, backspin_rpm=3000.0), BallModel(lift=lift))
    ekf = BallisticEkf(EkfConfig(), D / 2)
    rng = np.random.default_rng(0)
    times = np.arange(0.1, traj.landing_time, 1 / FPS)
    flight = traj.sample(times)
    stop = int(0.75 * len(times))  # the ball is lost for the last quarter of its flight
    for k in range(stop):
        if k:
            ekf.predict(1 / FPS)
        cam = follow(flight.position[k])
        uv, area = observe(cam, flight.position[k], rng)
        r = range_from_area(area, cam, D)
        ekf.update(cam, uv, r, range_rel_sigma(area, RangeConfig().rel_sigma))
    assert ekf.armed
    t_land, point = ekf.landing()
    true_t = traj.landing_time - times[stop - 1]
    carry = traj.carry
    # Range from a 6 px ball is good to ~15 % per frame; the filter, with gravity known, does far
    # better. Magnus lift is not in the model (only in its noise), and costs little this late.
    assert np.linalg.norm(point[:2] - traj.landing_point[:2]) < 0.04 * carry
    assert abs(t_land - true_t) < 0.15

    # Predicting on without measurements, the filter crosses the ground at about that point and time.
    steps = 0
    while True:
        previous = ekf.x.copy()
        ekf.predict(1 / FPS)
        steps += 1
        contact = ekf.ground_contact(previous)
        if contact is not None:
            break
        assert steps < 10 * FPS
    assert np.linalg.norm(contact.point - point) < 0.05 * carry
    assert abs(contact.point[2] - D / 2) < 1e-9


def test_range_from_area_inverts_the_projection():
    cam = follow(np.array([80.0, 5.0, 20.0]))
    d = cam.intrinsics.fx * D / 60.0
    assert range_from_area(math.pi / 4 * d * d, cam, D) == pytest.approx(60.0)
    assert range_rel_sigma(math.pi / 4 * d * d, 0.1) > 0.1


def test_a_blob_far_too_big_for_the_predicted_ball_is_too_near():
    """A cloud puff of 300 px where the filter has the ball 56 m away: as a ball it would be ~9 m
    from the lens. The same puff is no contradiction when the filter is unsure of its range."""
    cam = follow(np.array([40.0, 0.0, 15.0]), diameter_px=3.0)
    predicted = np.array([40.0, 0.0, 15.0])
    sure, unsure = np.eye(3) * 1.0, np.eye(3) * 15.0**2  # 1 m, 15 m along the line of sight
    puff = range_from_area(300.0, cam, D)
    ball = range_from_area(math.pi / 4 * 9.0, cam, D)  # the 3 px ball the camera was zoomed for
    distance = float(np.linalg.norm(predicted - cam.position))
    assert puff < distance / 4 and abs(ball - distance) < 1.0
    assert nearer_than_predicted(puff, predicted, sure, cam.position, factor=2.0)
    assert not nearer_than_predicted(ball, predicted, sure, cam.position, factor=2.0)
    assert not nearer_than_predicted(puff, predicted, unsure, cam.position, factor=2.0)  # 3 sigma reaches it
    assert not nearer_than_predicted(0.6 * distance, predicted, sure, cam.position, factor=2.0)  # within the factor
    assert not nearer_than_predicted(math.nan, predicted, sure, cam.position, factor=2.0)


def test_landing_of_a_vacuum_shot_is_analytic():
    v0, el = 30.0, math.radians(40)
    x = np.array([0.0, 0.0, 10.0, v0 * math.cos(el), 0.0, v0 * math.sin(el)])
    t, p = predict_landing(x, 0.0, 9.81, 0.0, 20.0, 0.01)
    vz = v0 * math.sin(el)
    t_true = (vz + math.sqrt(vz * vz + 2 * 9.81 * 10.0)) / 9.81
    assert t == pytest.approx(t_true, abs=1e-3)
    assert p[0] == pytest.approx(v0 * math.cos(el) * t_true, abs=0.02)


def test_a_wild_measurement_is_gated_then_the_filter_restarts():
    ekf = BallisticEkf(EkfConfig(), D / 2)
    cam = follow(np.array([50.0, 0.0, 10.0]))
    p = np.array([50.0, 0.0, 10.0])
    uv = cam.project_points(p.reshape(1, 3))[0]
    ekf.update(cam, uv, 60.0, 0.05)
    start = ekf.x.copy()
    for _ in range(2):
        assert not ekf.update(cam, uv + [300.0, 0.0], 60.0, 0.05)
    assert np.array_equal(ekf.x, start)
    ekf.update(cam, uv + [300.0, 0.0], 60.0, 0.05)  # third in a row: restart there
    assert np.allclose(cam.project_points(ekf.x[:3].reshape(1, 3))[0], uv + [300.0, 0.0], atol=1e-6)


def test_image_parabola_brackets_the_bounce():
    t = np.arange(10.0)
    history = np.stack([t, 100 + 5 * t, 300 - 20 * t + 2.5 * t * t], axis=1)  # descending at the end
    centre, half = image_parabola_landing(history, 12.0)
    end = np.array([160.0, 300 - 240 + 2.5 * 144])
    assert centre == pytest.approx(0.5 * (history[-1, 1:] + end))
    assert half == pytest.approx(0.5 * np.abs(end - history[-1, 1:]))
    rising = history.copy()
    rising[:, 2] = 300 - 20 * t
    assert image_parabola_landing(rising, 12.0) is None


def test_measurement_jacobian_by_finite_differences():
    cam = follow(np.array([60.0, 10.0, 15.0]))
    p = np.array([61.0, 9.0, 14.0])
    h, H = measurement_jacobian(cam, p)
    assert h[:2] == pytest.approx(cam.project_points(p.reshape(1, 3))[0])
    assert h[2] == pytest.approx(np.linalg.norm(p - cam.position))
    eps = 1e-5
    numeric = np.stack([(measurement_jacobian(cam, p + eps * e)[0] - measurement_jacobian(cam, p - eps * e)[0]) / (2 * eps)
                        for e in np.eye(3)], axis=1)
    assert H[:, :3] == pytest.approx(numeric, rel=1e-5, abs=1e-6)
    assert not H[:, 3:].any()


def falling(height: float) -> tuple[BallisticEkf, PtzCamera]:
    """A drag-free filter started 40 m out, then set falling from ``height`` (10 m/s on, 5 m/s down),
    armed for a landing; and the camera that saw it."""
    ekf = BallisticEkf(EkfConfig(drag_k=0.0), D / 2)
    cam = follow(np.array([40.0, 0.0, 3.0]))
    ekf.update(cam, cam.project_points(np.array([[40.0, 0.0, 3.0]]))[0], 40.0, 0.05)
    ekf.kf.x = np.array([40.0, 0.0, height, 10.0, 0.0, -5.0])
    ekf.armed = True
    return ekf, cam


def test_advance_reports_the_landing_once_and_bounces():
    ekf, cam = falling(3.0)
    landings = [ekf.advance(1 / FPS) for _ in range(30)]
    hits = [k for k, p in enumerate(landings) if p is not None]
    assert len(hits) == 1 and not ekf.armed
    assert landings[hits[0]][2] == pytest.approx(D / 2)
    assert ekf.x[2] >= D / 2 - 1e-9  # never below the ground
    state = EkfState.of(ekf, cam)
    assert state.x.shape == (6,) and state.P.shape == (6, 6)
    empty = EkfState.of(BallisticEkf(EkfConfig(), D / 2), cam)
    assert np.isnan(empty.x).all() and np.isnan(empty.landing_world).all()


def test_predicted_landing_is_integrated_when_read_and_not_hashed(monkeypatch):
    """The landing is drawn, never used by the tracker: EkfState.of does not integrate it (a replay
    without Rerun never pays for it), reading it gives the filter's own prediction, and it is not a
    hashed field (the digest hashes the state it comes from)."""
    import dataclasses

    import trackreplay.trackers.golf.landing as landing_module

    ekf, cam = falling(3.0)
    expected = ekf.landing()
    calls = []
    real = landing_module.predict_landing
    monkeypatch.setattr(landing_module, "predict_landing", lambda *a: calls.append(a) or real(*a))
    state = EkfState.of(ekf, cam)
    assert calls == []
    seconds, world = expected
    assert state.landing_in_s == seconds and state.landing_world.tolist() == world.tolist()
    assert state.landing_image.tolist() == cam.project_point(world).tolist()
    state.landing_world, state.landing_image
    assert len(calls) == 1  # once, then kept
    assert {f.name for f in dataclasses.fields(EkfState)} == {"x", "P", "nis", "landing_from"}
    no_pose = EkfState.of(ekf, None)
    assert np.isnan(no_pose.landing_image).all() and no_pose.landing_world.tolist() == world.tolist()
    # what it is drawn from is a field the digest skips: dataclasses.replace keeps it (a review: it was an
    # attribute outside the fields, and a replaced state drew a NaN landing), the digest does not see it
    from trackreplay.replay.core.digest import _field_names

    assert dataclasses.replace(state, nis=1.0).landing_world.tolist() == world.tolist()
    assert _field_names(EkfState) == ("x", "P", "nis")


def test_range_calibration_on_a_ball_resting_on_the_ground():
    point = np.array([60.0, 5.0, D / 2])
    cam = follow(point, diameter_px=8.0)
    uv = cam.project_points(point.reshape(1, 3))[0]
    true_area = math.pi / 4 * (cam.intrinsics.fx * D / np.linalg.norm(point - cam.position)) ** 2
    ranging = RangeFromArea(RangeConfig(), D)
    ranging.calibrate(cam, uv, 0.64 * true_area)  # a silhouette that lost the ball's edge
    assert ranging.scale == pytest.approx(0.8, rel=1e-3)
    r, rel = ranging.measure(0.64 * true_area, cam)
    assert r == pytest.approx(np.linalg.norm(point - cam.position), rel=1e-3)
    assert rel > RangeConfig().rel_sigma


def test_a_ball_on_the_ground_is_ranged_where_its_line_of_sight_meets_the_ground():
    point = np.array([140.0, -3.0, D / 2])
    cam = follow(point, diameter_px=6.0)
    uv = cam.project_points(point.reshape(1, 3))[0]
    r, rel = RangeFromArea(RangeConfig(), D).on_ground(cam, uv)
    assert r == pytest.approx(np.linalg.norm(point - cam.position), rel=1e-9)
    assert rel == RangeConfig().ground_sigma
    sky = follow(np.array([60.0, 0.0, 30.0]))  # a line of sight above the horizon never meets the ground
    assert RangeFromArea(RangeConfig(), D).on_ground(sky, np.array([640.0, 360.0])) is None


def test_the_filter_knows_when_the_ball_rolls():
    ekf = BallisticEkf(EkfConfig(), D / 2)
    assert not ekf.on_ground(0.5)  # not started
    rolling = np.array([100.0, 0.0, D / 2])
    cam = follow(rolling)
    ekf.update(cam, cam.project_points(rolling.reshape(1, 3))[0], np.linalg.norm(rolling - cam.position), 0.05)
    ekf.kf.x[3:] = [8.0, 0.0, 0.0]
    ekf.kf.x[2] = D / 2
    assert not ekf.on_ground(0.5)  # before a landing, a state at the contact height is a range error
    ekf.kf.x[2], ekf.kf.x[3:] = 0.3, [8.0, 0.0, -6.0]  # coming down after a flight that was high enough
    ekf.armed = True
    assert [ekf.advance(1 / FPS) is not None for _ in range(4)].count(True) == 1 and ekf.landed
    ekf.kf.x[3:] = [8.0, 0.0, 0.0]
    ekf.kf.x[2] = D / 2
    assert ekf.on_ground(0.5)
    ekf.kf.x[5] = 3.0  # bouncing up again
    assert not ekf.on_ground(0.5)
    ekf.kf.x[2], ekf.kf.x[5] = 1.0, 0.0  # in the air
    assert not ekf.on_ground(0.5)


def test_a_question_to_the_filter_does_not_restart_it():
    # may_restart=False (the tracker asks whether a ground range fits): a gated-out answer is not
    # counted towards the restart, and the state is left as it was.
    ekf = BallisticEkf(EkfConfig(), D / 2)
    point = np.array([80.0, 0.0, 10.0])
    cam = follow(point)
    uv = cam.project_points(point.reshape(1, 3))[0]
    ekf.update(cam, uv, np.linalg.norm(point - cam.position), 0.02)
    before = ekf.x.copy()
    for _ in range(5):
        assert not ekf.update(cam, uv, 3.0 * np.linalg.norm(point - cam.position), 0.01, may_restart=False)
    assert ekf.rejections == 0 and np.array_equal(ekf.x, before)
    for _ in range(MAX_REJECTIONS):  # the same wild range, as a measurement: the filter restarts there
        ekf.update(cam, uv, 3.0 * np.linalg.norm(point - cam.position), 0.01)
    assert np.linalg.norm(ekf.x[:3] - cam.position) == pytest.approx(3.0 * np.linalg.norm(point - cam.position), rel=1e-6)


def test_the_landing_flag_is_cleared_only_when_the_filter_forgets():
    ekf, cam = falling(0.2)
    while ekf.advance(1 / FPS) is None:
        pass
    assert ekf.landed
    ekf.initialise(cam, cam.project_points(np.array([[41.0, 0.0, D / 2]]))[0], 41.0, 0.05)  # a restart keeps it
    assert ekf.landed
    ekf.forget()
    assert not ekf.landed
