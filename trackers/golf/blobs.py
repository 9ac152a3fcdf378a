"""Blob gating: which foreground blobs may be the ball (seed 000, §2.1).

The silhouette's blobs (:func:`trackreplay.trackers.foreground.blobs.measure_blobs`: centroid,
area, circularity, box) are compared with *target* values of area and circularity; blobs far from
them are dropped. The targets follow the blobs selected as the ball in past frames (an exponential
moving average of log-area and circularity), so a zoom change is followed; the area gate widens
while the ball is missed. Among the survivors the one nearest to the predicted position is the
ball; all survivors' centroids are the particle filter's observation ``z_t``.

Shape is gated on *roundness*: the blob's circularity ``4 pi A / P^2`` divided by the circularity a
digitised disc of the same area scores (:func:`disc_circularity`). The raw measure is biased for
small digital shapes (a single pixel scores 1.27, a 5-pixel plus 0.9, a 30-pixel disc 0.85), so a
target that followed raw circularity climbed above 1 on tiny blobs and then rejected real discs;
roundness is about 1 for a disc of every size and below 1 for streaks and fragments.

Roundness alone lets through anything mildly oval (it must, for motion streaks), such as a cup's
white liner or a cap seen obliquely. So the shape is also checked against the *motion* (ours): a
ball of the blob's own width moving ``v`` px/frame smears, at most, into a streak of length
``|v|`` along ``v`` (exposure at most one frame). :func:`streak_excess` compares the blob's pixel
covariance with the covariance such a streak can have, ``(λ_minor + s²) I + (L²/12) u uᵀ`` with
``L`` the speed plus ``streak_sigmas`` of its uncertainty; a blob longer than that, or elongated
across the motion, is rejected ("elongated"): a slow ball is round, a fast one is long only along
its path.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass

import numpy as np

from trackreplay.trackers.foreground.blobs import Blobs, measure_blobs, nearest
from trackreplay.trackers.golf.config import BlobConfig

DISC_RADII = np.arange(0.5, 60.0, 0.25)
DISC_CENTRES = ((0.0, 0.0), (0.5, 0.5), (0.5, 0.0))


@functools.lru_cache(maxsize=1)
def _disc_table() -> tuple[np.ndarray, np.ndarray]:
    """(area, circularity) of digitised discs, radius 0.5 to 60 px, measured as blobs are.

    Every disc has a tile of its own in one mask (a row of tiles per radius, each tile's border
    empty: no two discs touch), measured in one :func:`measure_blobs` call: a blob's area and
    contour are its own wherever it lies, so each disc scores what it scores alone (a tile whose
    disc is empty or in pieces is left out, as it was alone); the medians per area are the
    middle values of the sorted circularities (``np.median``'s, the mean of the two middle ones)."""
    sides = [2 * (int(np.ceil(r)) + 2) + 1 for r in DISC_RADII]
    width = len(DISC_CENTRES) * max(sides)
    mask = np.zeros((sum(sides), width), np.uint8)
    tops = np.cumsum([0] + sides[:-1])
    for r, side, top in zip(DISC_RADII, sides, tops.tolist()):  # a loop over radii, each strip built whole
        n = side // 2
        ys, xs = np.mgrid[-n:n + 1, -n:n + 1]
        for j, (cx, cy) in enumerate(DISC_CENTRES):
            mask[top:top + side, j * side:(j + 1) * side] = (((xs - cx) ** 2 + (ys - cy) ** 2) <= r * r).astype(np.uint8)
    blobs = measure_blobs(mask, moments=False)
    row = np.searchsorted(tops, blobs.bbox[:, 1], side="right") - 1
    tile = row * len(DISC_CENTRES) + blobs.bbox[:, 0] // np.asarray(sides)[row]
    alone = np.bincount(tile, minlength=len(sides) * len(DISC_CENTRES))[tile] == 1
    areas, circs = blobs.area[alone], blobs.circularity[alone]
    order = np.lexsort((circs, areas))
    areas, circs = areas[order], circs[order]
    levels, first, count = np.unique(areas, return_index=True, return_counts=True)
    return levels, (circs[first + (count - 1) // 2] + circs[first + count // 2]) / 2.0


def disc_circularity(area: np.ndarray) -> np.ndarray:
    """Circularity a digitised disc of ``area`` px scores (interpolated; 1.27 for one pixel)."""
    levels, circ = _disc_table()
    return np.interp(np.asarray(area, dtype=np.float64), levels, circ)


def roundness(blobs: Blobs) -> np.ndarray:
    """(K,) circularity relative to a disc of the same area (about 1 for a disc; NaN where not measured).

    Kept on the (frozen) ``blobs`` after the first call, read-only: the gate, the validator and
    the targets all ask for the same blobs' roundness."""
    value = blobs.__dict__.get("_roundness")
    if value is None:
        value = blobs.circularity / disc_circularity(blobs.area)
        value.flags.writeable = False
        object.__setattr__(blobs, "_roundness", value)
    return value


REASONS = ("ok", "tiny", "area_small", "area_large", "circularity", "excess", "elongated", "still")
OK, TINY, AREA_SMALL, AREA_LARGE, CIRCULARITY, EXCESS, ELONGATED, STILL = range(len(REASONS))


@dataclass(frozen=True)
class ApparentMotion:
    """The ball's expected motion in the image this frame: velocity (px/frame) and the 1-σ
    uncertainty of each component (px/frame)."""

    velocity: np.ndarray
    sigma: float


def streak_excess(blobs: Blobs, motion: ApparentMotion, cfg: BlobConfig, scale: float) -> np.ndarray:
    """(K,) how far each blob's extent exceeds what a ball of its width moving with ``motion`` can
    smear into: the square root of the largest generalised eigenvalue of ``C`` against the allowed
    covariance ``A`` (1 = exactly as long as allowed; NaN where the shape was not measured)."""
    cov = blobs.covariance
    c11, c22, c12 = cov[:, 0], cov[:, 1], cov[:, 2]
    half = np.hypot(0.5 * (c11 - c22), c12)  # blobs.axes: the minor axis is their mean less this
    speed = float(np.hypot(*motion.velocity))
    u = np.asarray(motion.velocity, float) / speed if speed > 0 else np.zeros(2)
    unsure = cfg.streak_sigmas * motion.sigma
    along = speed + unsure
    slack = (cfg.streak_slack_px * scale) ** 2
    extra = (along * along - unsure * unsure) / 12.0
    ux, uy = float(u[0]), float(u[1])
    da11, da22, a12 = extra * ux * ux, extra * uy * uy, extra * ux * uy
    spare = unsure * unsure / 12.0  # an unknown component may point anywhere
    out = []
    # Blob by blob in Python floats: the same IEEE operations in the same order as the vector form
    # (a few blobs: numpy's per-call cost was most of it); np.hypot stays numpy's.
    for s11, s22, s12, h in zip(c11.tolist(), c22.tolist(), c12.tolist(), half.tolist()):
        iso = 0.5 * (s11 + s22) - h + slack + spare
        a11, a22 = iso + da11, iso + da22
        det_a = a11 * a22 - a12 * a12
        if det_a == 0.0:  # numpy's division by zero (inf, NaN) rather than Python's exception
            return _streak_excess_vector(c11, c22, c12, half, slack, spare, da11, da22, a12)
        b = a11 * s22 + a22 * s11 - 2.0 * a12 * s12  # det(C - rA) = det_a r² - b r + det_c
        det_c = s11 * s22 - s12 * s12
        root = math.sqrt(max(b * b - 4.0 * det_a * det_c, 0.0))  # max keeps a NaN, as np.maximum
        out.append((b + root) / (2.0 * det_a))
    return np.sqrt(np.array(out, dtype=np.float64).reshape(-1))


def _streak_excess_vector(c11, c22, c12, half, slack, spare, da11, da22, a12) -> np.ndarray:
    """:func:`streak_excess`'s vector form (a degenerate allowed covariance: numpy's inf and NaN)."""
    iso = 0.5 * (c11 + c22) - half + slack + spare
    a11, a22 = iso + da11, iso + da22
    det_a = a11 * a22 - a12 * a12
    b = a11 * c22 + a22 * c11 - 2.0 * a12 * c12
    det_c = c11 * c22 - c12 * c12
    root = np.sqrt(np.maximum(b * b - 4.0 * det_a * det_c, 0.0))
    return np.sqrt((b + root) / (2.0 * det_a))


@dataclass(frozen=True)
class BlobTargets:
    """Target area (px) and roundness (circularity relative to a disc, :func:`roundness`) that
    candidates are gated against."""

    area: float
    circularity: float  # roundness: about 1 for a disc of any size

    @property
    def diameter(self) -> float:
        """Diameter (px) of a disc of the target area."""
        return 2.0 * math.sqrt(self.area / math.pi)

    def follow(self, area: float, circularity: float, rate: float, shrink_rate: float | None = None) -> BlobTargets:
        """EMA towards a newly selected ball blob (log domain for the area: zoom is multiplicative;
        ``circularity`` is the blob's roundness, so the target stays near 1 for real discs); the
        area at ``shrink_rate`` instead when the blob is smaller (``BlobConfig.target_shrink_rate``)."""
        area_rate = shrink_rate if shrink_rate is not None and area < self.area else rate
        log_area = (1 - area_rate) * np.log(self.area) + area_rate * np.log(max(area, 1e-6))
        return BlobTargets(float(np.exp(log_area)), float((1 - rate) * self.circularity + rate * circularity))

    def zoomed(self, ratio: float) -> BlobTargets:
        """The same ball after a zoom that multiplies areas by ``ratio``."""
        return BlobTargets(self.area * ratio, self.circularity)


@dataclass(frozen=True, eq=False)
class GatedBlobs:
    """The blob stage's intermediates: every blob, why it was kept or dropped, and the ball."""

    blobs: Blobs
    reason: np.ndarray  # (K,) int64 index into REASONS
    selected: int  # the ball's row, -1 if none
    targets: np.ndarray  # (2,) target area (px) and circularity the gate used
    widen: float  # area-gate widening after misses
    reasons: tuple[str, ...] = REASONS

    @property
    def accepted(self) -> np.ndarray:
        return self.reason == OK

    @property
    def candidates(self) -> np.ndarray:
        """(M, 2) centroids of the accepted blobs: the observation ``z_t`` of eq. (2)."""
        return self.blobs.centroid[self.accepted]

    @classmethod
    def empty(cls) -> GatedBlobs:
        return cls(Blobs.empty(), np.zeros(0, np.int64), -1, np.full(2, np.nan), 1.0)


def find_blobs(mask: np.ndarray, offset: tuple[int, int], predicted: np.ndarray, cfg: BlobConfig, scale: float, *,
               moments: bool = True) -> Blobs:
    """The silhouette's blobs; shapes measured for the ``max_blobs`` nearest to the prediction
    (their covariance only with ``moments``: only the motion check reads it)."""
    return measure_blobs(mask, offset, min_area=cfg.min_area_px * scale * scale, max_measured=cfg.max_blobs, near=predicted,
                         moments=moments)


def start_targets(mask: np.ndarray, offset: tuple[int, int], near: np.ndarray, cfg: BlobConfig, scale: float) -> BlobTargets | None:
    """Targets from the marked ball's own silhouette: its biggest measured blob, roundness
    clamped to [0.6, 1]; None when the silhouette has no measured blob."""
    blobs = find_blobs(mask, offset, near, cfg, scale)
    measured = np.flatnonzero(blobs.measured)
    if not measured.size:
        return None
    biggest = measured[int(np.argmax(blobs.area[measured]))]
    return BlobTargets(float(blobs.area[biggest]), float(min(max(roundness(blobs)[biggest], 0.6), 1.0)))


def spills_over(mask: np.ndarray, offset: tuple[int, int], centre: tuple[float, float], size: tuple[float, float],
                slack_px: float = 4.0) -> bool:
    """What the LUT picks out at a marked box of ``size`` (w, h) round ``centre`` (``mask``: a crop
    well beyond twice the box, top-left ``offset``) is wider or taller than twice the box (+
    ``slack_px`` of blur): the box was not drawn round a ball the colours tell apart (a 400 px box on
    grass: a 356 000 px "ball"). The blob taken: the biggest whose box holds the centre, else the nearest."""
    blobs = measure_blobs(mask, offset, moments=False)
    if not len(blobs.area):
        return False
    b = blobs.bbox.astype(np.float64)
    holds = (b[:, 0] <= centre[0]) & (centre[0] <= b[:, 0] + b[:, 2]) & (b[:, 1] <= centre[1]) & (centre[1] <= b[:, 1] + b[:, 3])
    if holds.any():  # the biggest blob whose box holds the mark's centre (a flood's centroid may lie anywhere)
        k = int(np.flatnonzero(holds)[np.argmax(blobs.area[holds])])
    else:
        k = int(np.argmin(np.hypot(blobs.centroid[:, 0] - centre[0], blobs.centroid[:, 1] - centre[1])))
    w, h = float(b[k, 2]), float(b[k, 3])
    return w > 2.0 * size[0] + slack_px or h > 2.0 * size[1] + slack_px


def shape_tolerance(area: np.ndarray, cfg: BlobConfig, scale: float) -> np.ndarray:
    """The roundness tolerance for blobs of ``area`` px: ``circularity_tolerance``, widened as
    ``sqrt(shape_area_px / area)`` below ``shape_area_px`` (a shape read from a few pixels is noisy:
    its perimeter is a handful of steps). ``scale`` is unused: the noise is in the pixel count."""
    reliable = cfg.shape_area_px  # pixels, not scaled: the noise is in the pixel count
    return cfg.circularity_tolerance * np.maximum(1.0, np.sqrt(reliable / np.maximum(np.asarray(area, float), 1.0)))


def gate(blobs: Blobs, targets: BlobTargets, cfg: BlobConfig, scale: float, *, widen: float = 1.0,
         motion: ApparentMotion | None = None) -> np.ndarray:
    """The reason code of each blob (``OK`` = accepted).

    ``tiny`` below ``min_area_px``; ``excess`` when not measured (beyond ``max_blobs``). Area passes
    when ``(target+s)/tol' <= area+s <= (target+s)*tol'`` with ``log tol' = widen * log tol`` and
    ``s = area_slack_px`` (which keeps a 1-2 px ball from failing against a 3 px target);
    roundness passes when ``roundness >= target - circularity_tolerance`` (shape does not change with zoom);
    with a ``motion``, ``elongated`` when :func:`streak_excess` exceeds ``1 + streak_tolerance``.
    """
    if not len(blobs):
        return np.full(0, OK, np.int64)
    # Blob by blob in Python floats (a few blobs: numpy's per-call cost was most of it): the same
    # values and comparisons as the vector form; the logs stay numpy's, on the same arrays.
    area = blobs.area
    slack = cfg.area_slack_px * scale * scale
    lim = float(widen * np.log(cfg.area_tolerance))
    ratio = np.log((area + slack) / (targets.area + slack)).tolist()
    min_area, reliable, tolerance = cfg.min_area_px * scale * scale, cfg.shape_area_px, cfg.circularity_tolerance
    circularity, target = targets.circularity, -lim
    measured = blobs.circularity.tolist()
    excess = None
    reason = []
    for i, (a, c, r, rnd) in enumerate(zip(area.tolist(), measured, ratio, roundness(blobs).tolist())):
        if a < min_area:
            reason.append(TINY)
        elif not math.isfinite(c):
            reason.append(EXCESS)
        elif r > lim:  # before "small", as the vector form's later assignment won
            reason.append(AREA_LARGE)
        elif r < target:
            reason.append(AREA_SMALL)
        elif not rnd >= circularity - tolerance * max(1.0, math.sqrt(reliable / max(a, 1.0))):  # shape_tolerance
            reason.append(CIRCULARITY)
        elif motion is not None:
            if excess is None:
                excess = streak_excess(blobs, motion, cfg, scale).tolist()
            reason.append(ELONGATED if excess[i] > 1.0 + cfg.streak_tolerance else OK)
        else:
            reason.append(OK)
    return np.array(reason, np.int64)


def select_ball(mask: np.ndarray, offset: tuple[int, int], predicted: np.ndarray, targets: BlobTargets, misses: int,
                cfg: BlobConfig, scale: float, *, lost: bool = False, motion: ApparentMotion | None = None) -> GatedBlobs:
    """Blobs of the silhouette, gated (widened by ``misses``, ``widen_lost`` once the track is lost;
    shape against ``motion`` when it is known), and the accepted one nearest ``predicted``."""
    widen = cfg.widen_lost if lost else min(1.0 + cfg.widen_per_miss * misses, cfg.widen_max)
    blobs = find_blobs(mask, offset, predicted, cfg, scale, moments=motion is not None)
    reason = gate(blobs, targets, cfg, scale, widen=widen, motion=motion)
    selected = nearest(blobs.centroid, reason == OK, predicted)
    return GatedBlobs(blobs, reason, selected, np.array([targets.area, targets.circularity]), float(widen))


def refuse(gated: GatedBlobs, refused: np.ndarray, why: int, predicted: np.ndarray) -> GatedBlobs:
    """The same gate with the accepted blobs in ``refused`` given reason ``why`` (e.g. ``STILL``:
    :mod:`.scenery`), and the ball chosen again among the rest."""
    refused = refused & gated.accepted
    if not refused.any():
        return gated
    reason = np.where(refused, why, gated.reason)
    return dataclasses.replace(gated, reason=reason, selected=nearest(gated.blobs.centroid, reason == OK, predicted))
