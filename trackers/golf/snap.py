"""A marked box placed on the ball it was drawn around (ours).

The LUTs learn the ball's colours from the ellipse inscribed in a marked box and the background's
from outside it, and the track starts at the box's centre with the ball's size read inside it
(seed 000 §2.3). That asks a user for a box that fits the ball to a pixel. Boxes drawn by hand do
not: on a real iron shot a box 3 px off (a 22 px box round a 19 px ball) or 1.6x too large put
grass into the ball's samples, the ball merged with the turf in the silhouette, and the track was
never measured at all.

So each mark is first placed on its ball: in a window twice the box, pixels brighter than the
window's surroundings (the luminance outside the box, its median plus half the way to the box's
brightest pixel, and at least ``min_contrast`` levels) form blobs; the one holding the box's
brightest pixel places the box when it is compact and ball-shaped (fill and aspect), lies inside
the drawn box's window without touching the window's edge, and its centre is within the drawn box:
the box moves to its centroid (unless that is within ``keep_px`` of the drawn centre) and, when the
ellipse the ball's samples come from is larger than the blob (a loose box), takes the blob's size. Otherwise the box stays as drawn: a ball darker than
its surroundings, a box on nothing bright, or a bright thing larger than the window.
"""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np

from trackreplay.schemas.records import InitRegion
from trackreplay.trackers.appearance.color import to_ycrcb
from trackreplay.trackers.geometry.box import centre_box, clip_box
from trackreplay.trackers.golf.config import SnapConfig


def snap_to_ball(image: np.ndarray, region: InitRegion, cfg: SnapConfig, core: float = 1.0) -> InitRegion:
    """``region`` moved and sized onto the bright ball inside it (unchanged when none qualifies);
    ``core``: the share of the box whose inscribed ellipse gives the ball's samples (``LutConfig.core``)."""
    if not cfg.enabled:
        return region
    height, width = image.shape[:2]
    x0, y0, x1, y1 = clip_box(*centre_box(region.x, region.y, cfg.window * region.w, cfg.window * region.h), width, height)
    if x1 - x0 < 3 or y1 - y0 < 3:
        return region
    luma = to_ycrcb(image[y0:y1, x0:x1])[..., 0].astype(np.float32)
    bx0, by0, bx1, by1 = clip_box(*centre_box(region.x, region.y, region.w, region.h), width, height)
    inside = np.zeros(luma.shape, bool)
    inside[by0 - y0:by1 - y0, bx0 - x0:bx1 - x0] = True
    if not inside.any() or inside.all():
        return region
    level = float(np.median(luma[~inside]))
    peak_at = np.flatnonzero(inside.ravel())[int(np.argmax(luma[inside]))]
    peak = float(luma.ravel()[peak_at])
    if peak - level < cfg.min_contrast:
        return region
    bright = (luma > level + max(cfg.level * (peak - level), 0.5 * cfg.min_contrast)).astype(np.uint8)
    _, labels, stats, centroids = cv2.connectedComponentsWithStats(bright, connectivity=8)
    py, px = divmod(int(peak_at), luma.shape[1])
    k = int(labels[py, px])  # the blob holding the box's brightest pixel
    if k == 0:
        return region
    bx, by, bw, bh, area = (int(v) for v in stats[k])
    touches = bx == 0 or by == 0 or bx + bw == luma.shape[1] or by + bh == luma.shape[0]
    # frame pixels, edge convention of a marked box (its centre is x + w / 2): a pixel centre is at +0.5
    cx, cy = float(centroids[k, 0]) + x0 + 0.5, float(centroids[k, 1]) + y0 + 0.5
    within = abs(cx - region.x) <= region.w / 2 and abs(cy - region.y) <= region.h / 2
    if (touches or area < cfg.min_area_px or area < cfg.min_fill * bw * bh
            or max(bw, bh) > cfg.max_aspect * min(bw, bh) or not within):
        return region
    # A box's integer corners put its centre within half a pixel: a box drawn that well stays where
    # it is. A box whose core (the ball samples' ellipse, ``core`` of it) is larger than the ball
    # gives grass to the ball's samples and a ball too large to the gate: it becomes the ball's
    # bounding box. A tight one is kept as drawn (a dim, shaded side is still the ball).
    if abs(cx - region.x) <= cfg.keep_px and abs(cy - region.y) <= cfg.keep_px:
        cx, cy = region.x, region.y
    loose = core * min(region.w, region.h) > max(bw, bh) + cfg.slack_px
    w, h = (float(bw), float(bh)) if loose else (region.w, region.h)
    if (cx, cy, w, h) == (region.x, region.y, region.w, region.h):
        return region
    return dataclasses.replace(region, x=cx, y=cy, w=w, h=h)
