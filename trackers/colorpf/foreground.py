"""A foreground cue multiplied into the colour likelihood (ours, ``likelihood.foreground``).

The background eq. (7) is built from (:mod:`~trackreplay.trackers.colorpf.reference`) also says,
on every later frame, which pixels differ from it
(:func:`~trackreplay.trackers.foreground.background.foreground_mask`, the reference's own threshold
and opening). Per particle the cue is a centre-surround contrast

    c = f_in - f_ring,

``f_in`` the foreground share of the box, ``f_ring`` that of the ring between the box and the box
scaled by sqrt(2) per axis (the ring has the box's area), and the particle's likelihood becomes
``L exp(foreground * c)``. A box on the target has foreground inside and background around it; a
box on the floor next to the target has little inside, and a box inside a large moving region has
as much around as inside, so ``c`` is flat there and the colour decides alone (a constant factor
cancels in the weights).

The cue is taken at each particle's **position** with the previous estimate's **size** (the same
box for every particle): a share of foreground, even against a ring, still favours boxes that shrink
onto the body (measured: with each particle's own size the synthetic boxes lost 5-7 px of height
and the background scene's AUC fell), so the size stays the colour's and eq. (9)'s.

Uniform pixel weights and two integral-image look-ups per box: the cost per particle is constant,
and the mask is made only over the union of the rings. The background is first scaled to the
frame's brightness (:func:`brightness_gain`: a uniform illumination step is not foreground). It
needs a static camera, as eq. (7) does: a frame that differs from the background over more than half
its area (:func:`scene_changed`: the camera moved) gets no cue, and without a background (no usable
one, or before the "early" median exists) there is none.

Where the background was resampled into the frame's view (``camera.compensate`` with a zoom, rotation
or sub-pixel shift; ``reference.registration_tolerance = "resampled"``), a pixel is foreground only
beyond the minimum / maximum of the background over its 3x3 neighbourhood (:func:`tolerance_band`,
:func:`tolerant_mask`): a background edge the measured transform misplaces by under a pixel is not
foreground. :func:`scene_changed` keeps the plain test.

The same mask also refines the estimate (``refine.mode = "foreground"``, :func:`foreground_region`):
the connected foreground components around the estimate, placed as the marked box was on its own
foreground (:func:`region_layout`), move the estimate when they are consistent with one target.
"""

from __future__ import annotations

import cv2
import numpy as np

from trackreplay.trackers.appearance.color import to_grey
from trackreplay.trackers.colorpf.camera import resamples
from trackreplay.trackers.colorpf.likelihood import box_corners
from trackreplay.trackers.foreground.background import foreground_mask
from trackreplay.trackers.median import median

RING_SCALE = float(np.sqrt(2.0))  # the outer box per axis: the ring has the box's own area


SCENE_STEP = 4  # the whole-frame statistics on every 4th pixel per axis
SCENE_CHANGED = 0.5  # the background no longer describes a frame that differs from it over more than this share


def brightness_gain(image: np.ndarray, background: np.ndarray) -> float:
    """The frame's brightness relative to the background: the median of the grey-level ratio
    image / background over the background's pixels brighter than 8 (every 4th pixel per axis). A
    uniform illumination change (§3.1's reason for H-S) scales every pixel alike; the target and
    other movers are a small part of the frame, so the median is the scene's."""
    gi, gb = to_grey(image[::SCENE_STEP, ::SCENE_STEP], "mean"), to_grey(background[::SCENE_STEP, ::SCENE_STEP], "mean")
    ok = gb > 8
    return median((gi[ok] / gb[ok]).reshape(-1)) if ok.any() else 1.0


Band = tuple[np.ndarray, np.ndarray]  # the background's 3x3 minimum and maximum (:func:`tolerance_band`)

_NEIGHBOURHOOD = np.ones((3, 3), np.uint8)


def tolerance_band(background: np.ndarray) -> Band:
    """The minimum and maximum of ``background`` over each pixel's 3x3 neighbourhood, per channel
    (``cv2.erode`` / ``cv2.dilate``; at the image's edge over the pixels inside it), for the
    registration-tolerant foreground test (``reference.registration_tolerance``, :func:`_mask`)."""
    return cv2.erode(background, _NEIGHBOURHOOD), cv2.dilate(background, _NEIGHBOURHOOD)


def registration_band(background: np.ndarray, transform: np.ndarray, mode: str) -> Band | None:
    """The :func:`tolerance_band` of ``background`` (already warped by ``transform`` into the frame's view)
    when ``mode`` is "resampled" and the warp resampled it (:func:`~.camera.resamples`: not a whole-pixel
    translation), else None: the plain test (``reference.registration_tolerance``)."""
    if mode == "resampled" and resamples(transform):
        return tolerance_band(background)
    return None


def _channel_max(diff: np.ndarray) -> np.ndarray:
    if diff.ndim == 2:
        return diff
    channels = cv2.split(diff)
    out = channels[0]
    for c in channels[1:]:
        out = cv2.max(out, c)
    return out


def tolerant_mask(image: np.ndarray, band: Band, threshold: float, open_px: int) -> np.ndarray:
    """:func:`foreground_mask` with the background's 3x3 neighbourhood as tolerance: a pixel is
    foreground where some channel lies more than ``threshold`` below the band's minimum or above its
    maximum (registration-tolerant differencing: an edge of the background misplaced by under a pixel
    is inside the band). With ``low == high == background`` it is :func:`foreground_mask` exactly."""
    low, high = band
    outside = _channel_max(cv2.max(cv2.subtract(image, high), cv2.subtract(low, image)))  # uint8, saturated at 0
    mask = (outside > threshold).astype(np.uint8)
    if open_px > 1:
        mask = cv2.morphologyEx(mask, cv2.MORPH_OPEN, np.ones((open_px, open_px), np.uint8))
    return mask.astype(bool)


def _crop(band: Band | None, y0: int, y1: int, x0: int, x1: int) -> Band | None:
    return None if band is None else (band[0][y0:y1, x0:x1], band[1][y0:y1, x0:x1])


def _mask(image: np.ndarray, background: np.ndarray, threshold: float, open_px: int, gain: float,
          band: Band | None = None) -> np.ndarray:
    """:func:`foreground_mask` against the background scaled by ``gain`` (:func:`brightness_gain`); with
    ``band`` (:func:`tolerance_band` of the same background, cropped alike) :func:`tolerant_mask`
    against the band scaled by ``gain`` (a monotone scaling: the scaled band is the band of the scaled
    background, rounding included)."""
    if band is not None:
        if gain != 1.0:
            band = (cv2.convertScaleAbs(band[0], alpha=gain), cv2.convertScaleAbs(band[1], alpha=gain))
        return tolerant_mask(image, band, threshold, open_px)
    if gain != 1.0:
        background = cv2.convertScaleAbs(background, alpha=gain)
    return foreground_mask(image, background, threshold, open_px=open_px)


def scene_changed(image: np.ndarray, background: np.ndarray, threshold: float, gain: float) -> bool:
    """The frame differs from the brightness-matched background over more than half its area: the
    camera moved or the scene changed, so foreground says nothing about the target. On every 4th
    pixel per axis, without the opening (a share, not a mask)."""
    sub_i, sub_b = image[::SCENE_STEP, ::SCENE_STEP], background[::SCENE_STEP, ::SCENE_STEP]
    return float(_mask(sub_i, sub_b, threshold, 0, gain).mean()) > SCENE_CHANGED


def _sums(integral: np.ndarray, corners: np.ndarray) -> np.ndarray:
    x0, y0, x1, y1 = corners.T
    return integral[y1, x1] - integral[y0, x1] - integral[y1, x0] + integral[y0, x0]


def foreground_contrast(image: np.ndarray, background: np.ndarray, xy: np.ndarray, size: np.ndarray,
                        threshold: float, open_px: int, gain: float = 1.0, *,
                        band: Band | None = None) -> np.ndarray:
    """``f_in - f_ring`` (in [-1, 1]) for boxes of ``size`` ``(w, h)`` centred at each row of ``xy``
    (parts outside the image do not count; a box or ring wholly outside scores 0). ``band``: the
    registration-tolerant test (:func:`_mask`)."""
    xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    height, width = image.shape[:2]
    inner = np.column_stack([xy, np.broadcast_to(np.asarray(size, dtype=np.float64), xy.shape)])
    outer = inner.copy()
    outer[:, 2:] *= RING_SCALE
    c_in, c_out = box_corners(inner, width, height), box_corners(outer, width, height)
    x0, y0 = c_out[:, :2].min(axis=0)
    x1, y1 = c_out[:, 2:].max(axis=0)
    if x1 <= x0 or y1 <= y0:
        return np.zeros(len(xy))
    fg = _mask(image[y0:y1, x0:x1], background[y0:y1, x0:x1], threshold, open_px, gain, _crop(band, y0, y1, x0, x1))
    integral = cv2.integral(fg.astype(np.uint8))
    shift = np.array([x0, y0, x0, y0])
    s_in, s_out = _sums(integral, c_in - shift), _sums(integral, c_out - shift)
    a_in = np.prod(c_in[:, 2:] - c_in[:, :2], axis=1).astype(np.float64)
    a_ring = np.prod(c_out[:, 2:] - c_out[:, :2], axis=1).astype(np.float64) - a_in
    f_in = np.where(a_in > 0, s_in / np.maximum(a_in, 1.0), 0.0)
    f_ring = np.where(a_ring > 0, (s_out - s_in) / np.maximum(a_ring, 1.0), 0.0)
    return f_in - f_ring


def neighbour_shares(image: np.ndarray, background: np.ndarray, estimate: np.ndarray, threshold: float,
                     open_px: int, gain: float = 1.0, *, band: Band | None = None) -> np.ndarray:
    """Foreground share of the boxes of the estimate's size one width to its left and right and one
    height above and below it (4,), in that order (a box wholly outside the image: 0).

    The status uses it (``ColorPfConfig.neighbour_check``): when a neighbour holds more foreground
    than the marked box did (``P_detect / P_square`` of eq. 7), the estimate sits on or against a
    moving region larger than the target (another walker, a passing car), where colour cannot say
    which part is the target. ``band``: the registration-tolerant test (:func:`_mask`)."""
    x, y, w, h = (float(v) for v in estimate[:4])
    xy = np.array([[x - w, y], [x + w, y], [x, y - h], [x, y + h]])
    height, width = image.shape[:2]
    corners = box_corners(np.column_stack([xy, np.broadcast_to([w, h], xy.shape)]), width, height)
    x0, y0 = corners[:, :2].min(axis=0)
    x1, y1 = corners[:, 2:].max(axis=0)
    if x1 <= x0 or y1 <= y0:
        return np.zeros(4)
    fg = _mask(image[y0:y1, x0:x1], background[y0:y1, x0:x1], threshold, open_px, gain, _crop(band, y0, y1, x0, x1))
    integral = cv2.integral(fg.astype(np.uint8))
    c = corners - np.array([x0, y0, x0, y0])
    area = np.prod(c[:, 2:] - c[:, :2], axis=1).astype(np.float64)
    return np.where(area > 0, _sums(integral, c) / np.maximum(area, 1.0), 0.0)



REGION_CONTEXT = 4.0  # the mask for the region refinement is made over the estimate's box x 4 per axis


def _spread(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """Centroid ``(x, y)`` (pixel centres) and standard deviation per axis of a bool mask's pixels."""
    m = cv2.moments(mask.astype(np.uint8), binaryImage=True)
    if m["m00"] <= 0:
        return None
    centre = np.array([m["m10"], m["m01"]]) / m["m00"]
    sd = np.sqrt(np.maximum(np.array([m["mu20"], m["mu02"]]) / m["m00"], 1.0 / 12.0))  # one pixel: 1/sqrt(12)
    return centre, sd


CLIP_ROUNDS = 8  # sigma clipping: at most this many rounds (each drops pixels; it stops when none goes)


def clipped_spread(mask: np.ndarray, clip: float) -> tuple[np.ndarray, np.ndarray] | None:
    """Centroid and standard deviation per axis (as :func:`_spread`) of the mask's pixels within ``clip``
    standard deviations of their centroid on both axes, the centroid and deviations re-measured over the
    pixels kept until no more go (sigma clipping, at most :data:`CLIP_ROUNDS` rounds). None when the
    mask is empty.

    A convex shape of uniform density keeps every pixel when ``clip`` > 2 sqrt(2) = 2.83: its profile
    along an axis is a concave density, and none reaches further from its mean than the triangle's,
    2 sqrt(2) deviations (a rectangle's 1.73, an ellipse's 2). A few pixels detached far from the body
    (feet over road stripes) go, and no longer stretch the spread the layout turns into a size."""
    ys, xs = np.nonzero(mask)
    if xs.size == 0:
        return None
    xy = np.column_stack([xs, ys]).astype(np.float64)
    keep = np.ones(len(xy), dtype=bool)
    centre, sd = _spread_of(xy)
    for _ in range(CLIP_ROUNDS):
        inside = (np.abs(xy - centre) <= clip * sd).all(axis=1)
        if np.array_equal(inside, keep) or not inside.any():
            break
        keep = inside
        centre, sd = _spread_of(xy[keep])
    return centre, sd


def _spread_of(xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Centroid and standard deviation per axis of pixel coordinates ``(n, 2)`` (one pixel: 1/sqrt(12))."""
    centre = xy.mean(axis=0)
    return centre, np.sqrt(np.maximum(((xy - centre) ** 2).mean(axis=0), 1.0 / 12.0))


def measured_spread(mask: np.ndarray, spread: str, clip: float) -> tuple[np.ndarray, np.ndarray] | None:
    """Centroid and standard deviations of a mask's pixels as ``refine.spread`` says: "moments" over
    all of them (:func:`_spread`), "clipped" by :func:`clipped_spread`. None when the mask is empty."""
    if spread == "clipped":
        return clipped_spread(mask, clip)
    if spread == "moments":
        return _spread(mask)
    raise ValueError(f"spread must be 'moments' or 'clipped', not {spread!r}")


def region_layout(mask: np.ndarray, offset: np.ndarray, box: np.ndarray, spread: str = "moments",
                  clip: float = 3.0) -> np.ndarray | None:
    """Where the marked box lies relative to its foreground, ``(u_x, u_y, s_x, s_y)``: box centre =
    foreground centroid + u * its standard deviation, box size = s * the standard deviation, per axis
    (a box wholly foreground: 0, 0, sqrt(12), sqrt(12)). ``mask`` is eq. (7)'s foreground of the marked
    box (its top-left pixel at ``offset``), ``box`` the marked box ``(x, y, w, h)``. None when the mask
    is empty. Moments, not the bounding box: a few pixels of the target that differ from the floor on
    one frame and not on another (legs over a zebra crossing) move them little. ``spread`` "clipped"
    (``refine.spread``): measured as the later regions are, by :func:`clipped_spread`."""
    measured = measured_spread(mask, spread, clip)
    if measured is None:
        return None
    centre, sd = measured
    centre = centre + np.asarray(offset, np.float64)
    box = np.asarray(box, np.float64)
    return np.concatenate([(box[:2] - centre) / sd, box[2:4] / sd])


IDENTITY = np.array([0.0, 0.0, np.sqrt(12.0), np.sqrt(12.0)])


def region_box(region: np.ndarray, offset: np.ndarray, layout: np.ndarray, spread: str = "moments",
               clip: float = 3.0) -> np.ndarray:
    """The target's box ``(x, y, w, h)`` placed on a non-empty region mask (its top-left pixel at
    ``offset``) by ``layout`` (:func:`region_layout`) from the region's centroid and standard deviations
    (``refine.spread``): "moments", over all its pixels; "clipped", :func:`clipped_spread`."""
    centre, sd = measured_spread(region, spread, clip)
    layout = np.asarray(layout, np.float64)
    return np.concatenate([centre + np.asarray(offset, np.float64) + layout[:2] * sd, layout[2:4] * sd])


def foreground_region(image: np.ndarray, background: np.ndarray, estimate: np.ndarray, threshold: float,
                      open_px: int, gain: float, mark_share: float, layout: np.ndarray = IDENTITY, *,
                      window: float = 1.5, factor: float = 2.0, min_part: float = 0.01,
                      band: Band | None = None, spread: str = "moments",
                      clip: float = 3.0) -> tuple[np.ndarray | None, str]:
    """The target's box ``(x, y, w, h)`` from the foreground region the estimate sits on, or None and
    why not (``refine.mode = "foreground"``, ours).

    The foreground mask (as for the cue) over the estimate's box times :data:`REGION_CONTEXT` per axis,
    its 8-connected components (``cv2.connectedComponentsWithStats``). A component larger than the
    target could be (reaching the context's edge where that is not the image's, or a bounding box of
    more than ``factor`` times the box's area: a passing car, a shadow's edge) is not part of the
    region. The others with most of their pixels, and at least ``min_part`` of the box's area, inside
    the box times ``window`` (per axis) make the region (their whole extent: a head apart from the
    body). The target's box is placed on the region's centroid and standard deviations as the marked
    box was on its own foreground (``layout``, :func:`region_layout`: a part of the target the colour
    of the floor behind it, dark legs on a dark road, is not foreground at the mark either). It is
    taken only when it is consistent with one target:

    - each side within ``sqrt(factor)`` of the estimate box's (either way);
    - the region's foreground share of it within ``factor`` of the marked box's ``mark_share``
      (P_detect / P_square of eq. 7, either way);
    - the neighbour check's condition: none of the four boxes of the estimate's size beside it holds
      more foreground than ``mark_share``.

    ``band``: the registration-tolerant test (:func:`_mask`). ``spread``, ``clip``: how the region's
    centroid and deviations are measured (:func:`region_box`; ``refine.spread``, ``refine.clip``).
    """
    x, y, w, h = (float(v) for v in np.asarray(estimate, dtype=np.float64)[:4])
    height, width = image.shape[:2]
    context = tuple(int(v) for v in box_corners(np.array([x, y, w * REGION_CONTEXT, h * REGION_CONTEXT]),
                                                 width, height)[0])
    cx0, cy0, cx1, cy1 = context
    if cx1 <= cx0 or cy1 <= cy0 or w <= 0 or h <= 0:
        return None, "outside the image"
    fg = _mask(image[cy0:cy1, cx0:cx1], background[cy0:cy1, cx0:cx1], threshold, open_px, gain,
               _crop(band, cy0, cy1, cx0, cx1))
    region, why = _target_parts(fg, context, (width, height), np.array([x, y, w, h]), window, factor, min_part)
    if region is None:
        return None, why
    box = region_box(region, np.array([cx0, cy0]), layout, spread, clip)
    why = _inconsistent(box, fg, region, context, (width, height), np.array([w, h]), factor, mark_share)
    return (None, why) if why else (box, "")


def _target_parts(fg: np.ndarray, context: tuple[int, ...], size: tuple[int, int], estimate: np.ndarray,
                  window: float, factor: float, min_part: float) -> tuple[np.ndarray | None, str]:
    """:func:`foreground_region`'s region in the context's mask ``fg`` (corners ``context`` in the picture
    of ``size``): the components not larger than the target could be with most of their pixels, and at
    least ``min_part`` of the box's area, inside the estimate's box times ``window``; or None and why not."""
    x, y, w, h = (float(v) for v in estimate)
    (cx0, cy0, cx1, cy1), (width, height) = context, size
    n, labels, stats, _ = cv2.connectedComponentsWithStats(fg.astype(np.uint8), connectivity=8)
    if n <= 1:
        return None, "no foreground"
    shift = np.array([cx0, cy0, cx0, cy0])
    left, top = stats[:, cv2.CC_STAT_LEFT], stats[:, cv2.CC_STAT_TOP]
    right, bottom = left + stats[:, cv2.CC_STAT_WIDTH], top + stats[:, cv2.CC_STAT_HEIGHT]
    large = (((left == 0) & (cx0 > 0)) | ((top == 0) & (cy0 > 0)) | ((right == cx1 - cx0) & (cx1 < width))
             | ((bottom == cy1 - cy0) & (cy1 < height))
             | (stats[:, cv2.CC_STAT_WIDTH] * stats[:, cv2.CC_STAT_HEIGHT] > factor * w * h))
    wx0, wy0, wx1, wy1 = box_corners(np.array([x, y, w * window, h * window]), width, height)[0] - shift
    counts = np.bincount(labels[wy0:wy1, wx0:wx1].ravel(), minlength=n)
    part = (counts >= min_part * w * h) & (2 * counts >= stats[:, cv2.CC_STAT_AREA]) & ~large
    part[0] = False  # the background label
    if not part.any():
        return None, "no region of the target's size" if (counts[1:] > 0).any() else "no foreground"
    return part[labels], ""


def _inconsistent(box: np.ndarray, fg: np.ndarray, region: np.ndarray, context: tuple[int, ...],
                  size: tuple[int, int], wh: np.ndarray, factor: float, mark_share: float) -> str:
    """Why the region's ``box`` is not one target's (:func:`foreground_region`'s three tests; "" when it is);
    ``wh``: the estimate's width and height."""
    (cx0, cy0, cx1, cy1), (width, height) = context, size
    w, h = float(wh[0]), float(wh[1])
    ratio = box[2:4] / np.array([w, h])
    if not ((ratio >= 1.0 / np.sqrt(factor)) & (ratio <= np.sqrt(factor))).all():
        return "size"
    # the region's pixels in the target's box, and the four boxes of the estimate's size beside it
    bx, by = box[0], box[1]
    xy = np.array([[bx, by], [bx - w, by], [bx + w, by], [bx, by - h], [bx, by + h]])
    sides = np.vstack([box[2:4], np.broadcast_to([w, h], (4, 2))])
    corners = box_corners(np.column_stack([xy, sides]), width, height) - np.array([cx0, cy0, cx0, cy0])
    c = np.clip(corners, 0, [cx1 - cx0, cy1 - cy0, cx1 - cx0, cy1 - cy0])
    c[:, 2:] = np.maximum(c[:, 2:], c[:, :2])
    areas = np.prod(c[:, 2:] - c[:, :2], axis=1).astype(np.float64)
    own = _sums(cv2.integral(region.astype(np.uint8)), c[:1])[0] / max(areas[0], 1.0)
    if not mark_share / factor <= own <= mark_share * factor:
        return "share"
    beside = np.where(areas[1:] > 0, _sums(cv2.integral(fg.astype(np.uint8)), c[1:]) / np.maximum(areas[1:], 1.0), 0.0)
    if beside.max() > mark_share:
        return "against a larger region"
    return ""
