"""golf.streak: the whole streak of which a measured blob is the bright end (known answers)."""

import numpy as np

from trackreplay.trackers.golf.blobs import ApparentMotion
from trackreplay.trackers.golf.config import BlobConfig
from trackreplay.trackers.golf.streak import whole_streak


def streak_hat(length=40, width=8, top=80.0, bottom=20.0, shape=(120, 60), at=(26, 30)):
    """A top-hat crop with a vertical streak ``width`` x ``length`` from row ``at[1]`` down, its
    top rows at ``top`` levels fading linearly to ``bottom``, on noise of 0-3 levels."""
    hat = np.random.default_rng(0).integers(0, 4, shape).astype(np.uint8)
    x0, y0 = at
    hat[y0:y0 + length, x0:x0 + width] = np.linspace(top, bottom, length).astype(np.uint8)[:, None]
    return hat


def blob_of(hat, level, box):
    x, y, w, h = box
    return hat[y:y + h, x:x + w] >= level


def test_the_bright_end_is_grown_to_the_whole_streak():
    hat = streak_hat()
    box = (26, 30, 8, 12)  # the top 12 rows, above 60 levels: what one threshold keeps
    pixels = blob_of(hat, 60, box)
    assert pixels.all()
    offset = (100, 200)  # the crop's top-left in the frame
    moving = ApparentMotion(np.array([0.0, 35.0]), 4.0)
    centre = whole_streak(lambda: hat, pixels, (box[0] + 100, box[1] + 200), offset, moving, 8.0, BlobConfig(), 1.0)
    assert centre is not None
    # the streak's centre (49.5 rows down the crop; its faintest rows, under 35 % of the blob's level,
    # are left out: 47.5), not the blob's (35.5)
    assert abs(centre[0] - (100 + 26 + 3.5)) < 0.01 and abs(centre[1] - (200 + 30 + 19.5)) <= 2.5


def test_no_growth_where_no_streak_is_expected_or_possible():
    hat = streak_hat()
    box = (26, 30, 8, 12)
    pixels = blob_of(hat, 60, box)
    corner = (box[0], box[1])
    cfg = BlobConfig()
    assert whole_streak(lambda: hat, pixels, corner, (0, 0), ApparentMotion(np.array([0.0, 3.0]), 1.0), 8.0, cfg, 1.0) is None  # slower than its diameter
    assert whole_streak(lambda: hat, pixels, corner, (0, 0), ApparentMotion(np.array([0.0, 12.0]), 0.5), 8.0, cfg, 1.0) is None  # longer than 12 px a frame makes
    assert whole_streak(lambda: hat, pixels, corner, (0, 0), ApparentMotion(np.array([35.0, 0.0]), 0.5), 8.0, cfg, 1.0) is None  # across the motion
    assert whole_streak(lambda: hat, pixels, corner, (0, 0), None, 8.0, cfg, 1.0) is None  # no prediction (lost)
    flat = streak_hat(top=80.0, bottom=80.0)  # already the whole streak: nothing to grow
    assert whole_streak(lambda: flat, blob_of(flat, 60, (26, 30, 8, 40)), corner, (0, 0),
                        ApparentMotion(np.array([0.0, 35.0]), 4.0), 8.0, cfg, 1.0) is None


def test_a_region_beside_the_ball_is_no_streak():
    """A review: on a repeated picture of a round ball the lagging prediction still expected a
    streak; the region grown into a bright patch beside the ball moved the measurement 20 px sideways.
    A streak lies along the motion: a region across it, or off to the side, is not taken."""
    hat = np.random.default_rng(0).integers(0, 4, (120, 80)).astype(np.uint8)
    hat[40:48, 30:38] = 80  # the round ball, 8 x 8
    hat[38:50, 38:60] = 30  # a fainter patch beside it (sand), 22 px to the right
    pixels = hat[40:48, 30:38] >= 60
    moving_down = ApparentMotion(np.array([0.0, 30.0]), 3.0)
    assert whole_streak(lambda: hat, pixels, (30, 40), (0, 0), moving_down, 8.0, BlobConfig(), 1.0) is None
    moving_right = ApparentMotion(np.array([30.0, 0.0]), 3.0)  # along the patch: that is a streak
    centre = whole_streak(lambda: hat, pixels, (30, 40), (0, 0), moving_right, 8.0, BlobConfig(), 1.0)
    assert centre is not None and centre[0] > 40
