"""Subtraction stereo's crops: found on the 4-px cell grid (specks dropped), one box per region or
silhouette-hugging bands, and the disparity they give against full-frame SGBM."""

from __future__ import annotations

import numpy as np
import pytest

from trackreplay.trackers.geometry.subtraction_stereo import (SgbmConfig, _cells, disparity_agreement, foreground_crops,
                                                            full_disparity, subtraction_stereo)


def _diamond(h=240, w=320, cx=170, cy=120, rx=40, ry=90):
    yy, xx = np.mgrid[0:h, 0:w]
    return np.abs(xx - cx) / rx + np.abs(yy - cy) / ry <= 1.0


def _covered(mask, crops, reach):
    """Every foreground pixel lies in a crop's kept rows, with ``reach`` columns of the crop to its left."""
    v, u = np.nonzero(mask)
    ok = np.zeros(len(v), bool)
    for x0, y0, x1, y1, c0, c1 in crops.tolist():
        ok |= (v >= c0) & (v < c1) & (u < x1) & ((u - reach >= x0) | (x0 == 0)) & (y0 <= c0) & (c1 <= y1)
    return ok.all()


def test_cells_count_foreground_exactly_and_drop_specks():
    mask = np.zeros((37, 53), bool)
    mask[3:20, 5:30] = True  # a region of 425 px
    mask[30, 50] = True  # a 1-px speck
    occ = _cells(mask, min_area=20)
    assert occ.shape == (10, 14)
    assert occ[1:5, 2:7].all() and not occ[7, 12]  # region kept, speck (cell row 7, col 12) dropped
    assert _cells(mask, min_area=1)[7, 12]


def test_box_crops_cover_every_region_with_the_disparity_reach():
    cfg = SgbmConfig()
    mask = _diamond() | _diamond(cx=60, cy=60, rx=15, ry=30)
    crops = foreground_crops(mask, cfg, margin=8)
    assert crops.shape[1] == 6 and (crops[:, 4] == crops[:, 1]).all() and (crops[:, 5] == crops[:, 3]).all()
    assert _covered(mask, crops, cfg.num_disparities)


def test_band_crops_hug_the_silhouette_and_still_cover_it():
    cfg = SgbmConfig()
    mask = _diamond()
    area = lambda c: int(((c[:, 2] - c[:, 0]) * (c[:, 3] - c[:, 1])).sum())  # noqa: E731
    box = foreground_crops(mask, cfg, margin=0)
    band = foreground_crops(mask, cfg, margin=0, band_px=16)
    assert len(band) > len(box)
    assert area(band) < 0.8 * area(box)  # a diamond fills half its box
    assert _covered(mask, band, cfg.num_disparities)
    kept = np.zeros(mask.shape, np.int64)  # kept rows of different crops never overlap on the foreground
    for x0, _, x1, _, c0, c1 in band.tolist():
        kept[c0:c1, x0:x1] += 1
    assert kept[mask].max() == 1


def test_band_crops_agree_with_full_frame_sgbm():
    rng = np.random.default_rng(3)
    h, w, d_bg, d_fg = 240, 320, 3, 11
    bg = np.kron(rng.integers(0, 255, (h // 2, w // 2 + 16)), np.ones((2, 2))).astype(np.uint8)
    fg = np.kron(rng.integers(0, 255, (h // 2, w // 2 + 16)), np.ones((2, 2))).astype(np.uint8)
    mask = _diamond(h, w)
    left = np.where(mask, fg[:, :w], bg[:, :w])
    right = bg[:, d_bg:d_bg + w].copy()
    rmask = np.roll(mask, -d_fg, axis=1)
    right[rmask] = fg[:, d_fg:d_fg + w][rmask]
    cfg = SgbmConfig()
    full = full_disparity(left, right, cfg)
    for band, margin in ((0, 8), (16, 4), (32, 0)):
        sub = subtraction_stereo(left, right, mask, cfg, margin=margin, band_px=band)
        within, _, n = disparity_agreement(sub.disparity, full, mask, 1.0)
        assert n > 0.9 * mask.sum() and within >= 0.98, (band, margin, within, n)
        assert np.nanmedian(sub.disparity[mask]) == d_fg
        assert np.isnan(sub.disparity[~mask]).all()
        assert sub.kept_rows is not None and len(sub.kept_rows) == len(sub.crops)


@pytest.mark.parametrize("margin", [0, 1, 5, 6, 7, 8, 11])
def test_band_crops_grow_a_rectangle_as_the_box_crop_does(margin):
    """Away from the image's edges a rectangle's band crops span exactly its box crop's columns
    (``margin`` and the disparity reach rounded up to the 4-px cells is not grown twice)."""
    cfg = SgbmConfig()
    mask = np.zeros((120, 200), bool)
    mask[40:80, 100:120] = True
    box = foreground_crops(mask, cfg, margin=margin)
    band = foreground_crops(mask, cfg, margin=margin, band_px=16)
    assert len(box) == 1 and len(band) >= 1
    assert (band[:, 0] == box[0, 0]).all() and (band[:, 2] == box[0, 2]).all()
