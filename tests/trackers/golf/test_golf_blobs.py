import cv2
import numpy as np
import pytest

from trackreplay.trackers.golf.blobs import REASONS, BlobTargets, gate, measure_blobs, nearest


def rows_for(mask, targets, predicted=(100.0, 100.0), widen=1.0):
    rows = measure_blobs(mask, (0, 0), np.array(predicted), min_area=2.0, max_blobs=48)
    return gate(rows, targets, area_tolerance=3.0, circularity_tolerance=0.35, widen=widen)


def reason_at(rows, x, y):
    i = int(np.argmin((rows[:, 0] - x) ** 2 + (rows[:, 1] - y) ** 2))
    return REASONS[int(rows[i, 5])], bool(rows[i, 4])


@pytest.fixture
def shapes():
    m = np.zeros((200, 300), np.uint8)
    cv2.circle(m, (50, 50), 5, 1, -1)  # the ball: area 81
    m[100:102, 20:60] = 1  # a long bar, area 80: right area, wrong shape
    cv2.circle(m, (200, 100), 30, 1, -1)  # a huge blob
    cv2.circle(m, (250, 30), 1, 1, -1)  # much too small (area 5)
    m[180, 280] = 1  # one pixel: noise
    return m


def test_each_shape_gets_its_reason(shapes):
    rows = rows_for(shapes, BlobTargets(area=80.0, circularity=0.85))
    assert len(rows) == 5
    assert reason_at(rows, 50, 50) == ("ok", True)
    assert reason_at(rows, 39.5, 100.5) == ("circularity", False)
    assert reason_at(rows, 200, 100) == ("area_large", False)
    assert reason_at(rows, 250, 30) == ("area_small", False)
    assert reason_at(rows, 280, 180) == ("tiny", False)
    disc = rows[int(np.argmin((rows[:, 0] - 50) ** 2 + (rows[:, 1] - 50) ** 2))]
    assert disc[0] == pytest.approx(50.0) and disc[1] == pytest.approx(50.0)
    assert disc[2] == 81 and 0.8 < disc[3] < 1.05


def test_circularity_of_discs_bars_and_ellipses():
    for r in (2, 3, 5, 8, 15):
        m = np.zeros((60, 60), np.uint8)
        cv2.circle(m, (30, 30), r, 1, -1)
        circ = measure_blobs(m, (0, 0), np.zeros(2), min_area=0, max_blobs=4)[0, 3]
        assert 0.75 < circ < 1.1, (r, circ)
    m = np.zeros((60, 60), np.uint8)
    m[10:12, 5:45] = 1
    assert measure_blobs(m, (0, 0), np.zeros(2), min_area=0, max_blobs=4)[0, 3] < 0.35


def test_widening_lets_a_zoomed_ball_through(shapes):
    """After misses the gates widen: a ball 3.5x the target area passes at widen 1.5, not at 1."""
    m = np.zeros((100, 100), np.uint8)
    cv2.circle(m, (50, 50), 6, 1, -1)  # area 113
    t = BlobTargets(area=113 / 3.5, circularity=0.9)
    assert reason_at(rows_for(m, t), 50, 50)[0] == "area_large"
    assert reason_at(rows_for(m, t, widen=1.5), 50, 50)[0] == "ok"


def test_nearest_accepted_blob_to_the_prediction_is_the_ball():
    m = np.zeros((100, 200), np.uint8)
    cv2.circle(m, (30, 50), 4, 1, -1)
    cv2.circle(m, (150, 50), 4, 1, -1)
    m[10:12, 90:130] = 1  # a bar nearer to the prediction, rejected
    rows = rows_for(m, BlobTargets(49.0, 0.9), predicted=(110.0, 15.0))
    i = nearest(rows, np.array([110.0, 15.0]))
    assert rows[i, 0] == pytest.approx(150.0)
    assert nearest(rows[:0], np.zeros(2)) == -1


def test_excess_blobs_keep_the_nearest():
    m = np.zeros((100, 400), np.uint8)
    for k in range(60):
        m[10 + (k // 30) * 40 : 13 + (k // 30) * 40, 5 + 12 * (k % 30) : 8 + 12 * (k % 30)] = 1
    rows = measure_blobs(m, (10, 20), np.array([15.0, 30.0]), min_area=2, max_blobs=8)
    assert len(rows) == 60
    measured = rows[:, 5] == 0
    assert measured.sum() == 8 and (rows[~measured, 5] == REASONS.index("excess")).all()
    d = np.hypot(rows[:, 0] - 15.0, rows[:, 1] - 30.0)
    assert d[measured].max() <= d[~measured].min()
    assert np.isnan(rows[~measured, 3]).all()


def test_targets_follow_a_zoom_geometrically():
    t = BlobTargets(100.0, 0.9)
    for _ in range(30):
        t = t.follow(400.0, 0.8, 0.3)
    assert t.area == pytest.approx(400.0, rel=1e-3)
    assert t.circularity == pytest.approx(0.8, abs=1e-3)
    half = BlobTargets(100.0, 0.9).follow(400.0, 0.9, 0.5)
    assert half.area == pytest.approx(200.0)  # geometric mean, not arithmetic
