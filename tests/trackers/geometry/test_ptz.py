import numpy as np
import pytest

from trackreplay.schemas.records import LensEntry, LensTable, PtzReading
from trackreplay.trackers.geometry.ptz import PtzCamera, intrinsics_at, pan_tilt_towards, rotation_world_from_camera

LENS = LensTable(
    1280, 720,
    (LensEntry(0, 0, 1000, 1000, 640, 360), LensEntry(100, 0, 5000, 5000, 640, 360),
     LensEntry(0, 10, 1100, 1100, 640, 360), LensEntry(100, 10, 5500, 5500, 640, 360)),
    (0.0, 0.0, 2.0),
)


def test_lens_table_interpolates_zoom_then_focus() -> None:
    k = intrinsics_at(LENS, 50, 5)
    assert k.fx == pytest.approx((3000 + 3300) / 2)
    assert intrinsics_at(LENS, 1000, 0).fx == 5000  # clamps beyond the table


def test_rotation_is_orthonormal_and_axes_are_as_documented() -> None:
    R = rotation_world_from_camera(30.0, -10.0)
    assert R.T @ R == pytest.approx(np.eye(3))
    assert np.linalg.det(R) == pytest.approx(1.0)
    R0 = rotation_world_from_camera(0.0, 0.0)
    assert R0[:, 2] == pytest.approx([1, 0, 0])  # forward +X
    assert R0[:, 1] == pytest.approx([0, 0, -1])  # image down = world down


def test_project_back_project_round_trip() -> None:
    cam = PtzCamera.from_reading(PtzReading(0, 25.0, 5.0, 60, 3), LENS)
    rng = np.random.default_rng(0)
    pixels = rng.uniform([0, 0], [1280, 720], size=(50, 2))
    assert cam.project_directions(cam.line_of_sight(pixels)) == pytest.approx(pixels, abs=1e-6)


def test_line_of_sight_drawn_into_another_pose() -> None:
    """A world point seen under one pose lands where that pose's projection says under another."""
    point = np.array([[80.0, 30.0, 12.0]])
    a = PtzCamera.from_reading(PtzReading(0, *pan_tilt_towards(point[0] - LENS.camera_position), 0, 0), LENS)
    b = PtzCamera.from_reading(PtzReading(0, 15.0, 2.0, 40, 0), LENS)
    assert a.project_points(point)[0] == pytest.approx([640, 360])
    los = a.line_of_sight(a.project_points(point))
    assert b.project_directions(los) == pytest.approx(b.project_points(point), abs=1e-6)


def test_behind_the_camera_is_nan() -> None:
    cam = PtzCamera.from_reading(PtzReading(0, 0.0, 0.0, 0, 0), LENS)
    assert np.isnan(cam.project_directions(np.array([[-1.0, 0.0, 0.0]]))).all()


def test_pose_homography_moves_pixels_between_poses_and_zoom_area_ratio() -> None:
    from trackreplay.trackers.geometry.homography import apply_homography
    from trackreplay.trackers.geometry.ptz import pose_homography, zoom_area_ratio

    a = PtzCamera.from_reading(PtzReading(0, 20.0, 3.0, 10, 0), LENS)
    b = PtzCamera.from_reading(PtzReading(0, 22.0, 2.0, 60, 0), LENS)
    world = np.array([[80.0, 30.0, 4.0], [60.0, 20.0, 1.0]])
    assert apply_homography(pose_homography(a, b), a.project_points(world)) == pytest.approx(b.project_points(world), abs=1e-6)
    assert zoom_area_ratio(a, b) == pytest.approx(b.intrinsics.fx * b.intrinsics.fy / (a.intrinsics.fx * a.intrinsics.fy))


def test_rotation_and_matrices_are_computed_once_per_camera() -> None:
    cam = PtzCamera.from_reading(PtzReading(0, 25.0, 5.0, 60, 3), LENS)
    assert cam.R is cam.R and cam.K is cam.intrinsics.K
    assert cam.R == pytest.approx(rotation_world_from_camera(25.0, 5.0))


def test_intrinsics_of_two_tables_in_turn() -> None:
    """The grid kept for the last table is rebuilt for another table (and an equal copy gives the same)."""
    other = LensTable(LENS.width, LENS.height, tuple(LensEntry(e.zoom, e.focus, 2 * e.fx, e.fy, e.cx, e.cy)
                                                     for e in LENS.entries))
    copy = LensTable(LENS.width, LENS.height, tuple(LENS.entries))
    first = intrinsics_at(LENS, 50, 5)
    doubled = intrinsics_at(other, 50, 5)
    assert doubled.fx == 2 * first.fx and doubled.fy == first.fy
    assert intrinsics_at(copy, 50, 5) == first == intrinsics_at(LENS, 50, 5)


def test_interp_one_is_numpys_interp() -> None:
    """The lens table's scalar interpolation gives ``np.interp``'s floats bit for bit."""
    from trackreplay.trackers.geometry.ptz import interp_one

    rng = np.random.default_rng(3)
    for n in (1, 2, 5, 40):
        xs = np.sort(rng.uniform(-5.0, 50.0, n))
        ys = rng.normal(0.0, 2000.0, n)
        points = np.concatenate([rng.uniform(-10.0, 60.0, 400), xs, np.nextafter(xs, np.inf), np.nextafter(xs, -np.inf)])
        for x in points.tolist():
            assert interp_one(x, xs.tolist(), ys.tolist()) == float(np.interp(x, xs, ys))  # exactly


def test_intrinsics_and_rotation_are_the_numpy_forms() -> None:
    """``intrinsics_at`` and ``rotation_world_from_camera`` in Python floats give the numpy forms' bits."""
    from trackreplay.trackers.geometry.ptz import _intrinsics_at_numpy

    rng = np.random.default_rng(4)
    for zoom, focus in zip(rng.uniform(-10.0, 110.0, 300).tolist(), rng.uniform(-2.0, 12.0, 300).tolist()):
        fast, plain = intrinsics_at(LENS, zoom, focus), _intrinsics_at_numpy(LENS, zoom, focus)
        assert (fast.fx, fast.fy, fast.cx, fast.cy) == (plain.fx, plain.fy, plain.cx, plain.cy)
        assert type(fast.fx) is type(plain.fx)
    for pan, tilt in zip(rng.uniform(-360.0, 360.0, 300).tolist(), rng.uniform(-90.0, 90.0, 300).tolist()):
        p, t = np.deg2rad(pan), np.deg2rad(tilt)
        forward = np.array([np.cos(t) * np.cos(p), np.cos(t) * np.sin(p), np.sin(t)])
        right = np.array([np.sin(p), -np.cos(p), 0.0])
        plain = np.stack([right, np.cross(forward, right), forward], axis=1)
        assert rotation_world_from_camera(pan, tilt).tobytes() == plain.tobytes()  # signed zeros too
