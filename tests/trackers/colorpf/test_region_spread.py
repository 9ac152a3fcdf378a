"""The region's spread (refine.spread): sigma clipping drops detached fragments, keeps convex shapes whole."""

import cv2
import numpy as np
import pytest

from trackreplay.replay.core.config import config_from_dict
from trackreplay.schemas.errors import TrackreplayError
from trackreplay.trackers.colorpf.config import ColorPfConfig, RefineConfig
from trackreplay.trackers.colorpf.foreground import (IDENTITY, _spread, clipped_spread, foreground_region,
                                                     region_box, region_layout)

ESTIMATE = np.array([105.5, 94.0, 12.0, 28.0])
BODY = [105.5, 92.0, 11.95826074, 24.97999199]  # the 12 x 25 body alone (IDENTITY layout, after the 3x3 opening)


def _walker(foot: bool):
    """A 12 x 25 body (rows 80-104), with a 4 x 3 foot detached 13 rows below it (rows 118-120)."""
    background = np.full((200, 200, 3), 100, np.uint8)
    image = background.copy()
    image[80:105, 100:112] = 20
    if foot:
        image[118:121, 104:108] = 20  # feet over a white stripe: foreground apart from the body
    return image, background


def _region(image, background, spread):
    return foreground_region(image, background, ESTIMATE, 25.0, 3, 1.0, 0.6, IDENTITY, window=2.0, spread=spread)


def test_a_detached_fragment_does_not_stretch_the_clipped_region_box():
    body, why = _region(*_walker(False), "clipped")
    assert why == "" and np.allclose(body, BODY)
    stretched, why = _region(*_walker(True), "moments")  # the previous behaviour: the foot is in the spread
    assert why == "" and stretched[3] > 1.2 * BODY[3] and stretched[1] > BODY[1] + 1.0
    clipped, why = _region(*_walker(True), "clipped")
    assert why == "" and np.allclose(clipped, BODY)  # the foot (2.9-3.1 deviations below the centroid) is dropped


def _shapes():
    out = []
    for pts in ([(200, 20), (380, 380), (20, 380)], [(20, 20), (20, 380), (380, 380)], [(200, 10), (215, 390), (185, 390)],
                [(150, 20), (250, 20), (380, 380), (20, 380)]):
        for angle in (0.0, 17.0, 45.0):
            m = np.zeros((400, 400), np.uint8)
            cv2.fillConvexPoly(m, np.array(pts, np.int32), 1)
            out.append(cv2.warpAffine(m, cv2.getRotationMatrix2D((200, 200), angle, 0.8), (400, 400),
                                      flags=cv2.INTER_NEAREST).astype(bool))
    m = np.zeros((400, 400), np.uint8)
    cv2.ellipse(m, (200, 200), (150, 60), 30, 0, 360, 1, -1)
    out.append(m.astype(bool))
    m = np.zeros((30, 30), bool)
    m[4:26, 10:18] = True
    out.append(m)
    return out


@pytest.mark.parametrize("mask", _shapes())
def test_a_convex_shape_keeps_every_pixel(mask):
    # its profile along an axis is a concave density: no pixel beyond 2 sqrt(2) deviations (the triangle's)
    centre, sd = _spread(mask)
    ys, xs = np.nonzero(mask)
    assert max(np.abs(xs - centre[0]).max() / sd[0], np.abs(ys - centre[1]).max() / sd[1]) < 2 * np.sqrt(2) + 0.01
    clipped = clipped_spread(mask, 3.0)
    assert np.allclose(clipped[0], centre) and np.allclose(clipped[1], sd)


def test_moments_is_the_previous_spread_and_the_layout_is_measured_alike():
    mask = np.zeros((45, 12), bool)
    mask[:25] = True
    mask[38:41, 4:8] = True  # a detached fragment inside the marked box
    box = np.array([5.5, 20.0, 12.0, 45.0])
    centre, sd = _spread(mask)
    assert np.array_equal(region_layout(mask, np.zeros(2), box), np.concatenate([(box[:2] - centre) / sd, box[2:] / sd]))
    assert np.array_equal(region_layout(mask, np.zeros(2), box, "moments"), region_layout(mask, np.zeros(2), box))
    clipped = region_layout(mask, np.zeros(2), box, "clipped")
    assert clipped[3] > region_layout(mask, np.zeros(2), box)[3]  # the smaller clipped spread: a larger factor
    # whichever spread: the marked box is placed back on its own foreground exactly
    for spread in ("moments", "clipped"):
        layout = region_layout(mask, np.zeros(2), box, spread)
        assert np.allclose(region_box(mask, np.zeros(2), layout, spread), box)
    assert clipped_spread(np.zeros((4, 4), bool), 3.0) is None


def test_the_switch():
    assert RefineConfig().spread == "clipped" and RefineConfig().clip == 3.0
    with pytest.raises(TrackreplayError, match="invalid refine .*spread"):
        config_from_dict(ColorPfConfig, {"refine": {"spread": "iqr"}})
    with pytest.raises(TrackreplayError, match="invalid refine .*clip"):
        config_from_dict(ColorPfConfig, {"refine": {"clip": 0.0}})


def test_an_unknown_spread_is_refused() -> None:
    """A review: any other word measured by moments without a word."""
    with pytest.raises(ValueError, match="spread must be"):
        region_layout(np.ones((4, 4), bool), np.zeros(2), np.array([0.0, 0.0, 4.0, 4.0]), "clip")
