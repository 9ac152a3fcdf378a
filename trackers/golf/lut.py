"""The golf tracker's two colour LUTs, "sky" and "ground", and the switch between them (seed 000, §2.1).

The table itself is the shared 256³ colour LUT (:mod:`trackreplay.trackers.appearance.lut`, axes
Y, Cb, Cr). What is golf's:

- **samples from a marked box** (:func:`region_samples`): ball pixels are the ellipse inscribed in
  the box (shrunk by ``core``), background pixels the rest of the same frame outside the box grown
  by ``background_margin`` (every ``background_stride``-th pixel), and the *context* is the
  luminance around the box;
- **sky or ground**: which LUT a box trains is read from its label when it says so, otherwise
  from the colour around the box (blue or bright grey -> sky);
- **the switch** (:meth:`GolfLuts.choose`): each LUT keeps the luminance histogram of the context
  around its boxes; at run time the search region's luminance histogram is split between those
  contexts (nearest mean luminance) and the LUT owning most of it is applied, with hysteresis.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import cv2
import numpy as np

from trackreplay.schemas.records import InitRegion
from trackreplay.trackers.appearance.color import to_ycbcr, to_ycrcb
from trackreplay.trackers.appearance.histogram import colour_histogram, level_counts
from trackreplay.trackers.appearance.lut import ColourCounts, ColourLut, coarse_counts, coarse_index, two_class_table
from trackreplay.trackers.geometry.box import centre_box, clip_box
from trackreplay.trackers.golf.config import LutConfig

SKY, GROUND = "sky", "ground"
LUT_NAMES = (SKY, GROUND)
SKY_SCORE_THRESHOLD = 8.0  # (Cb - Cr) + (Y - 128)/4 of the context: blue sky ~ +50, grass ~ -10


def _ellipse_mask(h: int, w: int, cx: float, cy: float, rx: float, ry: float) -> np.ndarray:
    return _ellipse_r2(h, w, cx, cy, rx, ry) <= 1.0


def _ellipse_r2(h: int, w: int, cx: float, cy: float, rx: float, ry: float) -> np.ndarray:
    """Each pixel's squared normalised distance from the ellipse's centre (<= 1: inside it)."""
    ys, xs = np.mgrid[0:h, 0:w]
    return ((xs + 0.5 - cx) / max(rx, 0.5)) ** 2 + ((ys + 0.5 - cy) / max(ry, 0.5)) ** 2


def luminance_hist(y: np.ndarray, bins: int) -> np.ndarray:
    """Normalised luminance histogram of uint8 values (``bins`` divides 256)."""
    return colour_histogram(np.asarray(y, dtype=np.uint8).reshape(-1, 1), [bins], [(0.0, 256.0)])


@dataclass(frozen=True, eq=False)
class RegionSamples:
    """What one marked box contributes: ball and background colours, the context luminance."""

    name: str  # "sky" or "ground"
    ball: np.ndarray  # (n, 3) uint8 Y, Cb, Cr
    background: np.ndarray  # (m, 3) uint8
    context_y: np.ndarray  # (k,) uint8 luminance around the box
    sky_score: float
    ring: np.ndarray = field(default_factory=lambda: np.zeros((0, 3), np.uint8))  # (r, 3) uint8: the ball's own surroundings (:func:`ring_pixels`)
    centre_weight: np.ndarray | None = None  # (n,) each ball sample's weight in the ring test (1 at the centre, 0 at the rim)


def sky_score(context_ycc: np.ndarray) -> float:
    n = context_ycc.size // 3
    if not n:
        return 0.0
    if context_ycc.dtype == np.uint8:
        # The float64 means of integers are their exact integer sums divided once by the count
        # (every partial sum is an integer far below 2^53), so the same numbers come from int sums.
        # Summed channel by channel where they lie: a crop's (Y, Cb, Cr) are planes (to_ycbcr), which
        # a reshape to (N, 3) would copy.
        y, cb, cr = (int(context_ycc[..., i].sum(dtype=np.int64)) for i in range(3))
        return float((cb - cr) / n + 0.25 * (y / n - 128.0))
    c = context_ycc.reshape(-1, 3).astype(np.float64)
    return float(np.mean(c[:, 1] - c[:, 2]) + 0.25 * (np.mean(c[:, 0]) - 128.0))


def region_samples(image: np.ndarray, region: InitRegion, cfg: LutConfig, min_context_px: float) -> RegionSamples:
    """Ball, background and context samples of one marked box on its frame's image.

    ``min_context_px`` is the smallest context window (the smallest search region, frame pixels).
    """
    height, width = image.shape[:2]
    # The conversion is per pixel: each part is converted on its own (the box, the strided frame,
    # the context window) rather than the whole frame, the same values; the masks at those sizes.
    x0, y0, x1, y1 = clip_box(*centre_box(region.x, region.y, region.w, region.h), width, height)
    box = _ycbcr(image[y0:y1, x0:x1])
    r2 = _ellipse_r2(y1 - y0, x1 - x0, region.x - x0, region.y - y0, cfg.core * region.w / 2, cfg.core * region.h / 2)
    core = r2 <= 1.0
    ball = box[core]
    centre_weight = 1.0 - r2[core]  # Epanechnikov, 1 - r²: the rim, where a loose box holds the ground, weighs least

    gw, gh = region.w * cfg.background_margin, region.h * cfg.background_margin
    gx0, gy0, gx1, gy1 = clip_box(*centre_box(region.x, region.y, gw, gh), width, height)
    s = max(1, cfg.background_stride)
    # Every s-th pixel outside the guard box, in raster order (what a full-size mask's [::s, ::s]
    # picked): the rows above, the rows beside (left part, right part) and the rows below, copied as
    # blocks of OpenCV's interleaved (Y, Cr, Cb) rather than gathered by a mask, then put in
    # (Y, Cb, Cr) order; rows/columns i with i*s in the guard are ceil(g0/s)..ceil(g1/s)-1.
    strided = to_ycrcb(every_nth(image, s))
    r0, r1, c0, c1 = -(-gy0 // s), -(-gy1 // s), -(-gx0 // s), -(-gx1 // s)
    beside = np.concatenate([strided[r0:r1, :c0], strided[r0:r1, c1:]], axis=1)
    rows = np.concatenate([strided[:r0].reshape(-1, 3), beside.reshape(-1, 3), strided[r1:].reshape(-1, 3)])
    background = np.empty_like(rows)
    background[:, 0], background[:, 1], background[:, 2] = rows[:, 0], rows[:, 2], rows[:, 1]

    half = max(cfg.context * max(region.w, region.h), min_context_px) / 2
    cx0, cy0, cx1, cy1 = clip_box(*centre_box(region.x, region.y, 2 * half, 2 * half), width, height)
    around = _ycbcr(image[cy0:cy1, cx0:cx1])
    keep = np.ones(around.shape[:2], bool)
    keep[max(gy0 - cy0, 0):max(gy1 - cy0, 0), max(gx0 - cx0, 0):max(gx1 - cx0, 0)] = False
    context = around[keep]
    score = sky_score(context)
    label = region.label.lower()
    if "sky" in label:
        name = "sky"
    elif "ground" in label or "grass" in label:
        name = "ground"
    else:
        name = "sky" if score > SKY_SCORE_THRESHOLD else "ground"
    ring = ring_pixels(image, region, (gx0, gy0, gx1, gy1), cfg)
    return RegionSamples(name, ball, background, context[:, 0].copy(), score, ring, centre_weight)


def ring_pixels(image: np.ndarray, region: InitRegion, guard: tuple[int, int, int, int], cfg: LutConfig) -> np.ndarray:
    """The (Y, Cb, Cr) pixels of the ring round a marked box: inside the box grown by ``ring_margin``,
    outside the ``guard`` box (the box grown by ``background_margin``). What the ball will be seen
    against; (0, 3) when the ring is off (``ring_margin <= background_margin``) or outside the picture."""
    if cfg.ring_margin <= cfg.background_margin:
        return np.zeros((0, 3), np.uint8)
    height, width = image.shape[:2]
    rx0, ry0, rx1, ry1 = clip_box(*centre_box(region.x, region.y, region.w * cfg.ring_margin, region.h * cfg.ring_margin),
                                  width, height)
    around = _ycbcr(image[ry0:ry1, rx0:rx1])
    keep = np.ones(around.shape[:2], bool)
    gx0, gy0, gx1, gy1 = guard
    keep[max(gy0 - ry0, 0):max(gy1 - ry0, 0), max(gx0 - rx0, 0):max(gx1 - rx0, 0)] = False
    return around[keep]


def every_nth(image: np.ndarray, s: int) -> np.ndarray:
    """``image[::s, ::s]``, contiguous. When ``s`` is a power of two dividing both sides, OpenCV's
    nearest-neighbour resize picks exactly those pixels (source ``s x`` for target ``x``: the scale
    is a power of two, exact in floating point), ~7x faster than numpy's copy of a strided view."""
    if s == 1:
        return image
    h, w = image.shape[:2]
    if s & (s - 1) == 0 and h % s == 0 and w % s == 0:
        return cv2.resize(image, (w // s, h // s), interpolation=cv2.INTER_NEAREST)
    return np.ascontiguousarray(image[::s, ::s])


def _ycbcr(pixels: np.ndarray) -> np.ndarray:
    """``to_ycbcr`` of a crop, ``(h, w, 3)`` zeros for an empty one (OpenCV converts no empty image)."""
    if pixels.size == 0:
        return np.zeros(pixels.shape[:2] + (3,), np.uint8)
    return to_ycbcr(pixels)


def region_key(region: InitRegion) -> tuple:
    """Identity of a marked box (so a box is added to the LUTs once)."""
    return (region.frame, region.x, region.y, region.w, region.h, region.label)


@dataclass(frozen=True, eq=False)
class NamedLut:
    """One of the two LUTs and the luminance histogram of the context it was built in."""

    name: str
    lut: ColourLut
    reference_hist: np.ndarray
    regions: int

    @property
    def table(self) -> np.ndarray:
        return self.lut.table

    def lookup(self, ycc: np.ndarray) -> np.ndarray:
        return self.lut.lookup(ycc)


class GolfLuts:
    """The sky and ground LUTs, built up as marked frames arrive (mutable, owned by one tracker).

    ``min_context_px`` is the smallest context window in pixels of a ``reference_height`` frame
    (scaled per image like every pixel parameter).
    """

    def __init__(self, config: LutConfig, min_context_px: float, reference_height: int) -> None:
        self.config = config
        self.min_context_px = min_context_px
        self.reference_height = reference_height
        self.luts: dict[str, NamedLut] = {}
        self._counts: dict[str, ColourCounts] = {}
        self._ring_colours: dict[str, np.ndarray] = {}  # per LUT: colours of the rings round its boxes (:func:`separable_from_ring`)
        self._context: dict[str, np.ndarray] = {}
        self._count: dict[str, int] = {}
        self.consumed: set = set()  # keys of regions already added
        self._labels: np.ndarray | None = None  # luminance -> LUT index, rebuilt when the LUTs change
        self._label_levels: list[tuple[int, np.ndarray]] = []  # per built LUT: its index and the luminances labelled so
        self._learned: dict[str, tuple[int, float]] = {}  # per LUT: boxes learned from the track, last ball area

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(n for n in LUT_NAMES if n in self.luts)

    def lut(self, name: str) -> ColourLut | None:
        """The table called ``name``, None if not built (yet)."""
        named = self.luts.get(name)
        return None if named is None else named.lut

    def samples(self, image: np.ndarray, region: InitRegion) -> RegionSamples:
        scale = image.shape[0] / self.reference_height
        return region_samples(image, region, self.config, self.min_context_px * scale)

    def start_names(self, image: np.ndarray, region: InitRegion) -> tuple[str, str]:
        """Whether the start box is over "sky" or "ground", and the LUT to start with (that one if
        built, else any built one, else "")."""
        name = self.samples(image, region).name
        return name, name if name in self.luts else (self.names[0] if self.names else "")

    def learn(self, image: np.ndarray, regions: Sequence[InitRegion]) -> None:
        """Add the boxes marked on ``image`` that were not added before (each box once)."""
        fresh = [r for r in regions if region_key(r) not in self.consumed]
        if fresh:
            self.add(image, fresh)
            self.consumed.update(region_key(r) for r in fresh)

    def learn_from_track(self, image: np.ndarray, region: InitRegion, area: float, context_ycc: np.ndarray) -> str:
        """Add a confidently measured ball (``region`` around it, ``area`` px) to the LUT of the
        background it is over (read from ``context_ycc``, the search region's pixels, as for a
        mark) when that LUT does not exist yet or the ball's area changed by ``learn_area_factor``
        since it last learned from the track (zoom), at most ``learn_max`` times per LUT.
        Returns the LUT name learned into, or "" (nothing learned)."""
        label = region.label.lower()
        if "sky" in label:
            name = "sky"
        elif "ground" in label or "grass" in label:
            name = "ground"
        elif all(self._settled(n, area) for n in LUT_NAMES):  # nothing to learn whichever it is over
            return ""
        else:
            name = "sky" if sky_score(context_ycc) > SKY_SCORE_THRESHOLD else "ground"
        count, last = self._learned.get(name, (0, 0.0))
        if self._settled(name, area):
            return ""
        if name in self.luts and last == 0.0:  # built from marks only: remember the area, learn on a zoom change
            self._learned[name] = (count, max(area, 1e-6))
            return ""
        # the box is the measured blob's: tight by construction, nothing of the ring in it to keep out
        added = self.add(image, [InitRegion(region.frame, region.t_ns, region.x, region.y, region.w, region.h, name)],
                         ring=False)
        if not added:
            return ""
        self._learned[name] = (count + 1, max(area, 1e-6))
        return name

    def _settled(self, name: str, area: float) -> bool:
        """LUT ``name`` exists and learns nothing from a ball of ``area`` px: it learned ``learn_max``
        boxes from the track, or the ball's area is within ``learn_area_factor`` of the last one."""
        cfg = self.config
        count, last = self._learned.get(name, (0, 0.0))
        return name in self.luts and (count >= cfg.learn_max or (last > 0 and abs(np.log(max(area, 1e-6) / last)) < np.log(cfg.learn_area_factor)))

    def add(self, image: np.ndarray, regions: Sequence[InitRegion], ring: bool = True) -> list[RegionSamples]:
        """Add the marked boxes of one image and rebuild the LUTs they touch; ``ring``: keep the colours
        of the ring round each box out of its ball's (:func:`separable_from_ring`; a user's box may be
        loose, or hold the ball's shaded side)."""
        cfg = self.config
        touched: list[str] = []
        added = []
        for region in regions:
            samples = self.samples(image, region)
            if not len(samples.ball):
                continue
            added.append(samples)
            name = samples.name
            ball, ring_colours = separable_from_ring(samples, cfg) if ring else (samples.ball, None)
            self._counts.setdefault(name, ColourCounts(cfg.bin)).add(ball, samples.background)
            if ring_colours is not None:
                self._ring_colours[name] = self._ring_colours.get(name, False) | ring_colours
            self._context.setdefault(name, np.zeros(cfg.hist_bins))
            self._context[name] += luminance_hist(samples.context_y, cfg.hist_bins)
            self._count[name] = self._count.get(name, 0) + 1
            if name not in touched:
                touched.append(name)
        for name in touched:
            lut = self._counts[name].lut(smooth=cfg.smooth_bins, foreground_weight=cfg.ball_weight,
                                         min_count=cfg.min_count, background_scale=cfg.background_stride**2)
            if name in self._ring_colours:
                lut = ColourLut(np.ascontiguousarray(lut.coarse & ~self._ring_colours[name]), lut.bin)
            ref = self._context[name] / max(self._context[name].sum(), 1e-12)
            self.luts[name] = NamedLut(name, lut, ref, self._count[name])
        if touched:
            self._labels = None
        return added

    def luminance_labels(self) -> np.ndarray:
        """For each luminance 0..255, the index (into ``LUT_NAMES``) of the LUT whose context it fits.

        Each LUT's context histogram gives the mean luminance around its boxes; a luminance
        belongs to the LUT with the nearest mean (so the split is the midpoint between sky and
        ground). A sky that grows brighter or darker across the frame, or dark trees below it,
        still sort to the right side; a plain histogram intersection with the narrow contexts of
        a few marked boxes would see no overlap at all there.
        """
        centres = (np.arange(self.config.hist_bins) + 0.5) * (256 / self.config.hist_bins)
        levels = np.arange(256, dtype=np.float64)
        best = np.full(256, -1, np.int64)
        best_d = np.full(256, np.inf)
        for i, name in enumerate(LUT_NAMES):
            lut = self.luts.get(name)
            if lut is None:
                continue
            d = np.abs(levels - float(lut.reference_hist @ centres))
            better = d < best_d
            best[better], best_d[better] = i, d[better]
        return best

    def choose(self, y: np.ndarray, current: str) -> tuple[str, np.ndarray]:
        """The LUT for a search region from its luminance histogram, with hysteresis.

        The score of a LUT is the fraction of the region's pixels whose luminance fits that
        LUT's context best (see :meth:`luminance_labels`); the current LUT is kept unless
        another scores ``switch_margin`` more. Returns the name and the scores in
        ``LUT_NAMES`` order (NaN for a LUT not built yet).
        """
        scores = np.full(len(LUT_NAMES), np.nan)
        if not self.luts:
            return "", scores
        if self._labels is None:
            self._labels = self.luminance_labels()
            self._label_levels = [(i, np.flatnonzero(self._labels == i)) for i, name in enumerate(LUT_NAMES) if name in self.luts]
        y = np.asarray(y, dtype=np.uint8)
        # The pixels per LUT: the region's luminance counts summed over each LUT's levels, the same
        # integers (exact in float64 below 2^53) as counting the pixels' labels, divided by the same total.
        per_lut = np.bincount(self._labels, weights=level_counts(y), minlength=len(LUT_NAMES)).tolist()
        total = max(float(y.size), 1.0)
        for i, _ in self._label_levels:
            scores[i] = float(per_lut[i] / total)
        if not y.size:
            return (current if current in self.luts else self.names[0]), scores
        best = LUT_NAMES[_nanargmax(scores)]
        if current in self.luts and best != current:
            if scores[LUT_NAMES.index(best)] < scores[LUT_NAMES.index(current)] + self.config.switch_margin:
                best = current
        return best, scores


def separable_from_ring(samples: RegionSamples, cfg: LutConfig) -> tuple[np.ndarray, np.ndarray | None]:
    """The ball samples whose colours stand out from the ring round their box, and the colours of the
    ring that the ball's must not take (None: every sample stands out, or there is no ring).

    Round a ball, the ball and its surroundings are about equally likely a priori (the ring is a few
    times the box's area, not the picture's ~10^3 times), so the whole frame's prior (``ball_weight``)
    does not apply there: a colour the ring holds more densely than the ball's samples is what the ball
    lies on (its shaded underside matching the carpet under it, the grass inside a loose box); learned
    as ball, it joins the ball to its surroundings in every silhouette. Such samples are dropped, and
    since the ball's colours then border the ring's, the ring's colours are kept out of the LUT too
    (the smoothed counts of the colours kept would otherwise reach them). The ball's density weighs each
    sample by :attr:`RegionSamples.centre_weight` (a loose box's rim holds the ground); both densities
    are smoothed as the LUT's counts are. The ring starts at the guard (``background_margin``), so a box
    down to 1/1.5 of the ball leaves the ball out of it. A box well inside a larger ball (a quarter of the
    VOT ball) kept every sample: its ring is more of the ball, no denser in the box's own colours.
    A box whose samples all fall to the ring keeps them too (as learned before; the spill check judges it)."""
    ball, ring = samples.ball, samples.ring
    if not len(ball) or not len(ring):
        return ball, None
    q = 256 // cfg.bin
    cells = coarse_index(ball.reshape(-1, 3), cfg.bin)
    core = np.bincount(cells, weights=samples.centre_weight, minlength=q**3).reshape(q, q, q)
    n_core, n_ring = float(core.sum()), float(len(ring))
    if n_core <= 0:
        return ball, None
    around = coarse_counts(ring, cfg.bin)
    stands_out = two_class_table(core, around, smooth=cfg.smooth_bins, foreground_weight=n_ring, min_count=0.0,
                                 background_scale=n_core).reshape(-1)[cells]
    if stands_out.all() or not stands_out.any():
        return ball, None
    ring_colours = two_class_table(around, core, smooth=cfg.smooth_bins, foreground_weight=n_core, min_count=0.0,
                                   background_scale=n_ring)
    return ball[stands_out], ring_colours


def _nanargmax(values: np.ndarray) -> int:
    """``np.nanargmax`` of a short vector with at least one number (the first of equal maxima)."""
    best, top = -1, 0.0
    for i, v in enumerate(values.tolist()):
        if v == v and (best < 0 or v > top):
            best, top = i, v
    return best


def build_luts(images_and_regions: Iterable[tuple[np.ndarray, Sequence[InitRegion]]], config: LutConfig | None = None,
               min_context_px: float = 64.0, reference_height: int = 1080) -> GolfLuts:
    """Pure helper: :class:`GolfLuts` from ``(image, regions marked on it)`` pairs."""
    luts = GolfLuts(config or LutConfig(), min_context_px, reference_height)
    for image, regions in images_and_regions:
        luts.add(image, regions)
        luts.consumed.update(region_key(r) for r in regions)
    return luts
