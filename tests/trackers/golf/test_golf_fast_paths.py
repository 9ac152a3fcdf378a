"""Fast paths of the golf stages, pinned bit for bit to the plain forms they replace."""

import cv2
import numpy as np

from trackreplay.trackers.appearance.color import to_ycbcr
from trackreplay.trackers.foreground.blobs import measure_blobs
from trackreplay.trackers.golf.blobs import _disc_table
from trackreplay.trackers.golf.silhouette import previous_in_pose
from trackreplay.trackers.median import median_and_mad


def test_median_and_mad_from_counts_are_numpys():
    rng = np.random.default_rng(0)
    for n in [*range(1, 40), 999, 1000, 4096]:
        y = rng.integers(0, 256, n).astype(np.uint8) if n % 2 else np.minimum(rng.geometric(0.3, n), 255).astype(np.uint8)
        med = float(np.median(y))  # contrast_silhouette's plain form: the MAD over float32
        assert median_and_mad(y, 0, 256) == (med, float(np.median(np.abs(y.astype(np.float32) - med))))
        rise = (rng.integers(-255, 256, n) if n % 3 else np.clip(rng.normal(0, 4, n).round(), -255, 255)).astype(np.int16)
        med = float(np.median(rise))  # moving_silhouette's plain form: the MAD over float64
        assert median_and_mad(rise, -255, 511) == (med, float(np.median(np.abs(rise - med))))


def test_disc_table_in_one_mask_is_the_disc_by_disc_table():
    areas, circs = [], []
    for r in np.arange(0.5, 60.0, 0.25):
        n = int(np.ceil(r)) + 2
        ys, xs = np.mgrid[-n:n + 1, -n:n + 1]
        for cx, cy in ((0.0, 0.0), (0.5, 0.5), (0.5, 0.0)):
            b = measure_blobs((((xs - cx) ** 2 + (ys - cy) ** 2) <= r * r).astype(np.uint8), moments=False)
            if len(b) == 1:
                areas.append(b.area[0])
                circs.append(b.circularity[0])
    areas, circs = np.array(areas), np.array(circs)
    levels = np.unique(areas)
    table = _disc_table()
    assert table[0].tobytes() == levels.tobytes()
    assert table[1].tobytes() == np.array([np.median(circs[areas == a]) for a in levels]).tobytes()


def test_previous_in_pose_is_the_y_of_to_ycbcr():
    rng = np.random.default_rng(1)
    frame = rng.integers(0, 256, (90, 120, 3)).astype(np.uint8)
    homography = np.array([[1.01, 0.02, -3.0], [-0.01, 0.99, 2.5], [1e-5, 0.0, 1.0]])
    y = previous_in_pose(frame, homography, (10, 7), (40, 50))
    to_crop = np.array([[1.0, 0.0, -10.0], [0.0, 1.0, -7.0], [0.0, 0.0, 1.0]]) @ homography
    bgr = cv2.warpPerspective(frame, to_crop, (50, 40), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT,
                              borderValue=(255, 255, 255))
    assert np.array_equal(y, to_ycbcr(bgr)[..., 0])


def test_median_and_mad_of_images_are_numpys():
    """The 2-D crops the silhouettes pass (counted by ``cv2.calcHist``): numpy's medians too."""
    rng = np.random.default_rng(1)
    for shape in [(1, 1), (3, 7), (43, 43), (320, 320), (150, 69), (200, 90)]:
        hat = np.minimum(rng.geometric(0.2, shape), 255).astype(np.uint8)
        med = float(np.median(hat))
        assert median_and_mad(hat, 0, 256) == (med, float(np.median(np.abs(hat.astype(np.float32) - med))))
        rise = np.clip(rng.normal(0, 9, shape).round(), -255, 255).astype(np.int16)
        med = float(np.median(rise))
        assert median_and_mad(rise, -255, 511) == (med, float(np.median(np.abs(rise - med))))


def test_every_nth_is_the_strided_view():
    from trackreplay.trackers.golf.lut import every_nth

    rng = np.random.default_rng(2)
    for shape in [(720, 1280, 3), (1080, 1920, 3), (360, 640, 3), (37, 53, 3), (64, 96, 3), (8, 8, 3), (720, 1280)]:
        image = rng.integers(0, 256, shape, dtype=np.uint8)
        for s in (1, 2, 3, 4, 8):
            got = every_nth(image, s)
            assert got.flags.c_contiguous and np.array_equal(got, image[::s, ::s])


def test_at_least_is_numpys_comparison():
    from trackreplay.trackers.golf.silhouette import at_least

    rng = np.random.default_rng(3)
    for shape in [(1, 1), (43, 43), (320, 320), (7, 150)]:
        images = [rng.integers(0, 256, shape, dtype=np.uint8), rng.integers(-255, 256, shape).astype(np.int16)]
        images[1].flat[:2] = [-32768, 32767]
        for values in images:
            for t in [-40000.0, -255.5, -1.0, -0.5, 0.0, 0.25, 1.0, 15.0, 40.0, 41.3, 254.5, 255.0, 255.5, 300.0,
                      32766.5, 32767.0, 40000.0, float(rng.normal(20, 30)), np.float64(17.75)]:
                got = at_least(values, t)
                assert got.dtype == np.uint8 and got.shape == values.shape
                assert np.array_equal(got, (values >= t).astype(np.uint8)), (values.dtype, t)


def test_ekf_substep_matrices_per_interval_are_the_rebuilt_ones():
    """The substep Q and F kept per interval: the same predictions as building them every time."""
    from trackreplay.trackers.golf.config import EkfConfig
    from trackreplay.trackers.golf.landing import BallisticEkf

    cached, rebuilt = BallisticEkf(EkfConfig(), 0.02), BallisticEkf(EkfConfig(), 0.02)
    for ekf in (cached, rebuilt):
        ekf.kf.x = np.array([0.0, 0.0, 0.5, 40.0, 3.0, 20.0])
        ekf.kf.P = np.diag([1.0, 1.0, 1.0, 25.0, 25.0, 25.0])
        ekf.initialised = True
    rng = np.random.default_rng(4)
    for dt in rng.choice([33333333, 33333334, 33333333, 66666667, 20000000], 60) / 1e9:
        rebuilt._substeps.clear()
        cached.predict(dt)
        rebuilt.predict(dt)
        assert cached.kf.x.tobytes() == rebuilt.kf.x.tobytes() and cached.kf.P.tobytes() == rebuilt.kf.P.tobytes()
    assert len(cached._substeps) <= 16


def test_sky_score_of_planes_is_the_reshaped_one():
    """sky_score sums the crop's planes where they lie: the numbers of the (N, 3) reshape's column sums."""
    from trackreplay.trackers.golf.lut import sky_score

    rng = np.random.default_rng(5)
    assert sky_score(np.zeros((0, 0, 3), np.uint8)) == 0.0
    for shape in [(1, 1), (7, 3), (64, 48), (201, 333)]:
        bgr = rng.integers(0, 256, (*shape, 3), dtype=np.uint8)
        for ycc in (to_ycbcr(bgr), np.ascontiguousarray(to_ycbcr(bgr)), to_ycbcr(bgr).reshape(-1, 3)):
            c = ycc.reshape(-1, 3)
            n = len(c)
            y, cb, cr = (int(c[:, i].sum(dtype=np.int64)) for i in range(3))
            plain = float((cb - cr) / n + 0.25 * (y / n - 128.0)) if n else 0.0
            assert sky_score(ycc) == plain


def test_line_of_sight_norm_is_numpys():
    from trackreplay.trackers.geometry.pinhole import Intrinsics
    from trackreplay.trackers.geometry.ptz import PtzCamera

    rng = np.random.default_rng(6)
    for _ in range(50):
        camera = PtzCamera(rng.normal(0, 5, 3), rng.uniform(-180, 180), rng.uniform(-30, 60),
                           Intrinsics(*rng.uniform(500, 9000, 2), *rng.uniform(300, 900, 2), 1280, 720))
        pixels = rng.uniform(-100, 1400, (int(rng.integers(1, 20)), 2))
        rays = camera.intrinsics.back_project(pixels) @ camera.R.T
        assert camera.line_of_sight(pixels).tobytes() == (rays / np.linalg.norm(rays, axis=1, keepdims=True)).tobytes()


def test_project_point_is_project_points():
    from trackreplay.trackers.geometry.pinhole import Intrinsics
    from trackreplay.trackers.geometry.ptz import PtzCamera

    rng = np.random.default_rng(7)
    for _ in range(300):
        camera = PtzCamera(rng.normal(0, 5, 3), rng.uniform(-180, 180), rng.uniform(-30, 60),
                           Intrinsics(*rng.uniform(500, 9000, 2), *rng.uniform(300, 900, 2), 1280, 720))
        point = rng.normal(0, 200, 3)
        assert camera.project_point(point).tobytes() == camera.project_points(point.reshape(1, 3))[0].tobytes()
    camera = PtzCamera(np.zeros(3), 0.0, 0.0, Intrinsics(1000.0, 1000.0, 640.0, 360.0, 1280, 720))
    for point in ([-5.0, 0.0, 0.0], [np.nan, 1.0, 1.0], [10.0, 0.0, 0.0], [1e-12, 0.0, 0.0]):
        point = np.array(point)
        assert camera.project_point(point).tobytes() == camera.project_points(point.reshape(1, 3))[0].tobytes()


def test_trail_in_image_with_every_line_of_sight_is_the_masked_form():
    from trackreplay.trackers.geometry.pinhole import Intrinsics
    from trackreplay.trackers.geometry.ptz import PtzCamera
    from trackreplay.trackers.golf.trail import Trail

    rng = np.random.default_rng(8)
    camera = PtzCamera(np.zeros(3), 10.0, 5.0, Intrinsics(2000.0, 2000.0, 640.0, 360.0, 1280, 720))
    for n in (1, 5, 40, 130):
        trail = Trail(60)
        for _ in range(n):
            los = rng.normal(0, 1, 3)
            trail.add((float(rng.uniform(0, 1280)), float(rng.uniform(0, 720))), los / np.linalg.norm(los), None)
        rows = trail.image.ordered()
        plain = rows[:, :2].copy()
        has = np.isfinite(rows[:, 2])
        plain[has] = camera.project_directions(rows[has, 2:5])
        assert trail.in_image(camera).tobytes() == plain.tobytes()


def test_single_candidate_likelihood_is_the_plain_form():
    """Eq. (2) against one candidate in one buffer: numpy's temporaries' numbers."""
    from trackreplay.trackers.golf.particles import likelihood

    rng = np.random.default_rng(9)
    for n in (0, 1, 7, 1000, 4099):
        particles = rng.normal(300, 80, (n, 4))
        particles[: n // 10, :2] = [[310.0, 295.0]]  # on the candidate: d² = 0
        for sigma, alpha in ((6.0, 0.01), (0.37, 1e-6), (25.0, 0.0)):
            cx, cy = np.array([[310.0, 295.0]])[0]
            out = np.full(n, alpha, dtype=np.float64)
            d2 = (particles[:, 0] - cx) ** 2 + (particles[:, 1] - cy) ** 2
            out += np.exp(-d2 / (2.0 * sigma * sigma)) / (np.sqrt(2.0 * np.pi) * sigma)
            assert likelihood(np.array([[310.0, 295.0]]), sigma, alpha)(particles).tobytes() == out.tobytes()


def test_measurement_jacobian_is_the_plain_form():
    import math

    from trackreplay.trackers.geometry.pinhole import Intrinsics
    from trackreplay.trackers.geometry.ptz import PtzCamera
    from trackreplay.trackers.golf.landing import measurement_jacobian

    rng = np.random.default_rng(10)
    for _ in range(300):
        camera = PtzCamera(rng.normal(0, 5, 3), rng.uniform(-180, 180), rng.uniform(-30, 60),
                           Intrinsics(*rng.uniform(500, 9000, 2), *rng.uniform(300, 900, 2), 1280, 720))
        p = camera.position + rng.normal(0, 100, 3) * (rng.random() < 0.95)  # now and then at the camera: r = 0
        k, Rt = camera.intrinsics, camera.R.T
        fx, fy = float(k.fx), float(k.fy)
        rel = p - camera.position
        a, b, c = (Rt @ rel).tolist()
        c = max(c, 1e-6)
        r = math.sqrt(float(rel.dot(rel)))
        H = np.zeros((3, 6))
        H[:2, :3] = np.array([[fx / c, 0.0, -fx * a / (c * c)], [0.0, fy / c, -fy * b / (c * c)]]) @ Rt
        H[2, :3] = rel / max(r, 1e-9)
        h, got = measurement_jacobian(camera, p)
        assert got.tobytes() == H.tobytes() and h.tobytes() == np.array([fx * a / c + k.cx, fy * b / c + k.cy, r]).tobytes()
