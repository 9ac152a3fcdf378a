"""Was it there already? (ours): a jump confirmed after a loss must not be scenery.

A track confirmed after the ball was lost (:mod:`.validate`) is a blob seen on several frames in
a row. Scenery (:mod:`.scenery`) refuses white things that stayed put, but only those the search
region saw while the ball was measured. Once the ball is lost the search covers the middle of the
picture, and a white thing that was beside the ball all along (the cup's liner the ball dropped
into; a cloud puff the tilting camera brings into the middle) is new to it: found on three frames,
it is confirmed, and the track goes on on it with full confidence.

So, at a confirmation, the frame where the ball was last measured is looked at again: the confirmed
point is carried back into it (with encoders, through the pose change; without, through the view's
change measured from the two pictures, :mod:`..geometry.view_change`, or the same pixel), the
same LUT is applied around it, and if a blob covered that point then, more than a ball diameter
from where the ball was measured, the confirmed blob is that thing, not the ball
(verdict ``seen_before``). "That thing": a blob there at least as big as the confirmed one (within
the area tolerance) — the liner whole before, a piece of it now. A ball found again where it was last seen (at rest after an occlusion) is
not refused: it is its own blob there, as large as the ball was (within the area tolerance; a review:
on the broadcast approach turned 180°, after the ball dropped in, an 11 x 4 px piece of the liner just
beside where the ball of ~290 px was last seen was confirmed and measured on 7 of 19 frames). When the
view's change cannot be measured, a camera that moved moves the scenery in the picture: nothing is
found there and nothing is refused (the check only ever refuses).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from trackreplay.trackers.foreground.blobs import measure_blobs
from trackreplay.trackers.geometry.homography import apply_homography
from trackreplay.trackers.geometry.ptz import PtzCamera, pose_homography, zoom_area_ratio
from trackreplay.trackers.geometry.view_change import view_change
from trackreplay.trackers.golf.lut import GolfLuts
from trackreplay.trackers.golf.silhouette import box_silhouette


@dataclass(frozen=True, eq=False)
class LastSighting:
    """The frame where the ball was last measured: its picture, pose (None: no encoders), the ball's
    position and diameter there."""

    image: np.ndarray
    camera: PtzCamera | None
    ball: tuple[float, float]
    diameter: float
    area: float  # the ball's area there (px): what a ball found again in its place should about have


def where_the_ball_was(last: LastSighting, point: tuple[float, float], near_px: float) -> bool:
    """``point`` (the last sighting's pixels) lies within the ball's diameter (+ ``near_px``) of where it was measured."""
    return math.hypot(point[0] - last.ball[0], point[1] - last.ball[1]) <= last.diameter + near_px


def in_last_view(last: LastSighting, camera: PtzCamera | None, point: np.ndarray, area: float,
                 image: np.ndarray | None = None) -> tuple[float, float, float]:
    """``point`` (this frame's pixels) and a blob ``area`` there as the last sighting's picture saw them:
    through the pose change with encoders, else through the view's change measured from the two
    pictures (``image`` is this frame's), else as they are."""
    p = np.asarray(point, dtype=np.float64).reshape(1, 2)
    if camera is not None and last.camera is not None:
        p = apply_homography(pose_homography(camera, last.camera), p)
        area *= zoom_area_ratio(camera, last.camera)  # as big as it would have looked then
    elif image is not None:  # no encoders: the view's change from the picture itself, when it can be told
        moved = view_change(last.image, image)
        if moved is not None:
            back = np.linalg.inv(moved)
            p = apply_homography(back, p)
            area *= abs(float(np.linalg.det(back[:2, :2])))
    return float(p[0, 0]), float(p[0, 1]), area


def was_there_before(last: LastSighting, camera: PtzCamera | None, point: np.ndarray, area: float, luts: GolfLuts,
                     lut_name: str, near_px: float, area_tolerance: float, image: np.ndarray | None = None) -> bool:
    """Whether a blob at least ``area / area_tolerance`` px large covered ``point`` (this frame's
    pixels; its box grown by ``near_px``) in the last sighting's picture, under the LUT ``lut_name``,
    more than a ball diameter (+ ``near_px``) from the ball measured there."""
    if not lut_name or lut_name not in luts.names:
        return False
    x, y, area = in_last_view(last, camera, point, area, image)
    if not (math.isfinite(x) and math.isfinite(y)):
        return False
    if where_the_ball_was(last, (x, y), near_px) and area >= last.area / area_tolerance:
        return False  # the ball itself, found again where it was (as large as it was, within the tolerance)
    height, width = last.image.shape[:2]
    half = 2.0 * math.sqrt(max(area, 1.0)) + near_px
    x0, y0 = max(int(math.floor(x - half)), 0), max(int(math.floor(y - half)), 0)
    x1, y1 = min(int(math.ceil(x + half)) + 1, width), min(int(math.ceil(y + half)) + 1, height)
    if x1 - x0 < 2 or y1 - y0 < 2:
        return False
    _, offset, mask = box_silhouette(last.image, np.array([x0, y0, x1 - x0, y1 - y0]), luts, lut_name)
    blobs = measure_blobs(mask, offset, moments=False)
    if not len(blobs.area):
        return False
    b = blobs.bbox.astype(np.float64)  # x0, y0, w, h; pixel centres at integers
    covers = ((b[:, 0] - 0.5 - near_px <= x) & (x <= b[:, 0] + b[:, 2] - 0.5 + near_px)
              & (b[:, 1] - 0.5 - near_px <= y) & (y <= b[:, 1] + b[:, 3] - 0.5 + near_px))
    # as big as the confirmed blob or bigger: a piece of the cup's liner was the whole liner before the loss
    big_enough = blobs.area >= max(area, 1.0) / area_tolerance
    return bool((covers & big_enough).any())
