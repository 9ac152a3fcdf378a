import numpy as np

from trackreplay.trackers.geometry.box import centre_box, clip_box, crop
from trackreplay.trackers.geometry.ground_plane import GroundPlane
from trackreplay.trackers.geometry.homography import apply_homography, transfer_velocities
from trackreplay.trackers.geometry.stereo import StereoRig


def test_stereo_round_trip_and_jacobian_by_finite_differences() -> None:
    rig = StereoRig(f=420.0, baseline=0.12, cx=320.0, cy=240.0)
    pts = np.array([[0.5, -0.2, 4.0], [-1.0, 0.8, 9.5]])
    np.testing.assert_allclose(rig.to_points(rig.to_uvd(pts)), pts, atol=1e-12)
    J = rig.jacobian(pts[0])
    eps = 1e-6
    numeric = np.stack([(rig.to_uvd(pts[0] + eps * e) - rig.to_uvd(pts[0] - eps * e))[0] / (2 * eps) for e in np.eye(3)], axis=1)
    np.testing.assert_allclose(J, numeric, rtol=1e-6)


def test_ground_plane_distance_from_a_known_camera() -> None:
    # Camera 5 m up looking straight down: pixels scale 0.01 m/px around the principal point.
    H = np.array([[0.01, 0.0, -3.2], [0.0, 0.01, -2.4], [0.0, 0.0, 1.0]])
    plane = GroundPlane(H, camera_ground=(0.0, 0.0), camera_height=5.0)
    np.testing.assert_allclose(plane.distance(np.array([[320.0, 240.0], [620.0, 640.0]])), [5.0, np.sqrt(3**2 + 4**2 + 25)])
    np.testing.assert_allclose(plane.to_image(plane.to_ground(np.array([[10.0, 20.0]]))), [[10.0, 20.0]])


def test_homography_moves_points_and_velocities() -> None:
    H = np.array([[2.0, 0.0, 5.0], [0.0, 2.0, -1.0], [0.0, 0.0, 1.0]])
    p, v = transfer_velocities(H, np.array([[1.0, 1.0]]), np.array([[0.5, -0.5]]))
    np.testing.assert_allclose(p, [[7.0, 1.0]])
    np.testing.assert_allclose(v, [[1.0, -1.0]])
    np.testing.assert_allclose(apply_homography(np.eye(3), np.array([[3.0, 4.0]])), [[3.0, 4.0]])


def test_box_clip_and_crop() -> None:
    img = np.arange(100).reshape(10, 10)
    box = clip_box(*centre_box(1.0, 1.0, 6.0, 4.0), 10, 10)
    assert box == (0, 0, 4, 3)
    patch, offset = crop(img, box)
    assert patch.shape == (3, 4) and offset == (0, 0)
    assert clip_box(20, 20, 30, 30, 10, 10) == (10, 10, 10, 10)
