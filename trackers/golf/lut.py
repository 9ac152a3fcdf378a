"""Colour lookup tables over (Y, Cb, Cr) that say "ball-like" per pixel (seed 000, §2.1).

A LUT is built from boxes the user marked around the ball: pixels of the ellipse inscribed in
the box are ball samples, the rest of the same frame (outside the box, grown a little) are
background samples. Both are histogrammed on a coarse colour grid, smoothed in colour space (so
colours near a ball colour count as ball too) and compared as pixel counts: a colour is ball
where ``lut_ball_weight`` times its ball count beats its background count. The coarse table is then expanded to the paper's
256 x 256 x 256 booleans, once, so a lookup is a single fancy index.

Two LUTs, "sky" and "ground", because the background differs so much above and below the
horizon. Which one a marked box trains is read from its label when it says so, otherwise from
the colour around the box (blue or bright grey -> sky). Each LUT keeps the luminance histogram
of the context around its boxes; at run time the search region's luminance histogram is split
between those contexts (nearest mean luminance) and the LUT owning most of it is applied.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import cv2
import numpy as np

from trackreplay.schemas.records import InitRegion
from trackreplay.trackers.golf.config import GolfConfig

LUT_NAMES = ("sky", "ground")
SKY_SCORE_THRESHOLD = 8.0  # (Cb - Cr) + (Y - 128)/4 of the context: blue sky ~ +50, grass ~ -10


def to_ycc(bgr: np.ndarray) -> np.ndarray:
    """BGR (or grey) uint8 -> (..., 3) uint8 in (Y, Cb, Cr) order, the LUT's axis order."""
    if bgr.ndim == 2:
        bgr = cv2.cvtColor(bgr, cv2.COLOR_GRAY2BGR)
    ycrcb = cv2.cvtColor(np.ascontiguousarray(bgr), cv2.COLOR_BGR2YCrCb)
    return ycrcb[..., [0, 2, 1]]


def flat_index(ycc: np.ndarray) -> np.ndarray:
    """Flat index ``Y*65536 + Cb*256 + Cr`` into a C-ordered 256^3 table."""
    y = ycc[..., 0].astype(np.int32)
    return (y << 16) | (ycc[..., 1].astype(np.int32) << 8) | ycc[..., 2].astype(np.int32)


def clip_box(x0: float, y0: float, x1: float, y1: float, width: int, height: int) -> tuple[int, int, int, int]:
    """Integer pixel box [x0, x1) x [y0, y1) clipped to the image."""
    a = int(np.clip(np.floor(x0), 0, width))
    b = int(np.clip(np.floor(y0), 0, height))
    c = int(np.clip(np.ceil(x1), 0, width))
    d = int(np.clip(np.ceil(y1), 0, height))
    return a, b, max(a, c), max(b, d)


def _ellipse_mask(h: int, w: int, cx: float, cy: float, rx: float, ry: float) -> np.ndarray:
    ys, xs = np.mgrid[0:h, 0:w]
    return ((xs + 0.5 - cx) / max(rx, 0.5)) ** 2 + ((ys + 0.5 - cy) / max(ry, 0.5)) ** 2 <= 1.0


@dataclass(frozen=True, eq=False)
class RegionSamples:
    """What one marked box contributes: ball and background colours, the context luminance."""

    name: str  # "sky" or "ground"
    ball: np.ndarray  # (n, 3) uint8 Y, Cb, Cr
    background: np.ndarray  # (m, 3) uint8
    context_y: np.ndarray  # (k,) uint8 luminance around the box
    sky_score: float


def sky_score(context_ycc: np.ndarray) -> float:
    c = context_ycc.reshape(-1, 3).astype(np.float64)
    if not len(c):
        return 0.0
    return float(np.mean(c[:, 1] - c[:, 2]) + 0.25 * (np.mean(c[:, 0]) - 128.0))


def region_samples(image: np.ndarray, region: InitRegion, config: GolfConfig) -> RegionSamples:
    """Ball, background and context samples of one marked box on its frame's image."""
    height, width = image.shape[:2]
    scale = height / config.reference_height
    ycc = to_ycc(image)
    x0, y0, x1, y1 = clip_box(region.x - region.w / 2, region.y - region.h / 2,
                              region.x + region.w / 2, region.y + region.h / 2, width, height)
    box = ycc[y0:y1, x0:x1]
    core = _ellipse_mask(y1 - y0, x1 - x0, region.x - x0, region.y - y0,
                         config.lut_core * region.w / 2, config.lut_core * region.h / 2)
    ball = box[core]

    gw, gh = region.w * config.lut_background_margin, region.h * config.lut_background_margin
    gx0, gy0, gx1, gy1 = clip_box(region.x - gw / 2, region.y - gh / 2, region.x + gw / 2, region.y + gh / 2, width, height)
    s = max(1, config.lut_background_stride)
    keep = np.ones((height, width), bool)
    keep[gy0:gy1, gx0:gx1] = False
    background = ycc[::s, ::s][keep[::s, ::s]]

    half = max(config.lut_context * max(region.w, region.h), config.search_min_px * scale) / 2
    cx0, cy0, cx1, cy1 = clip_box(region.x - half, region.y - half, region.x + half, region.y + half, width, height)
    ctx_keep = keep[cy0:cy1, cx0:cx1]
    context = ycc[cy0:cy1, cx0:cx1][ctx_keep]
    score = sky_score(context)
    label = region.label.lower()
    if "sky" in label:
        name = "sky"
    elif "ground" in label or "grass" in label:
        name = "ground"
    else:
        name = "sky" if score > SKY_SCORE_THRESHOLD else "ground"
    return RegionSamples(name, ball, background, context[:, 0].copy(), score)


def _coarse_hist(samples: np.ndarray, bin_: int) -> np.ndarray:
    q = 256 // bin_
    c = samples.reshape(-1, 3).astype(np.int64) // bin_
    return np.bincount((c[:, 0] * q + c[:, 1]) * q + c[:, 2], minlength=q**3).astype(np.float64).reshape(q, q, q)


def smooth3(values: np.ndarray, sigma: float) -> np.ndarray:
    """Separable Gaussian smoothing of a 3-D array (zero outside)."""
    if sigma <= 0:
        return values
    r = int(np.ceil(3 * sigma))
    k = np.exp(-0.5 * (np.arange(-r, r + 1) / sigma) ** 2)
    k /= k.sum()
    out = values
    for axis in range(3):
        acc = np.zeros_like(out)
        n = out.shape[axis]
        for off, wgt in zip(range(-r, r + 1), k):
            src = [slice(None)] * 3
            dst = [slice(None)] * 3
            if off >= 0:
                src[axis], dst[axis] = slice(0, n - off), slice(off, n)
            else:
                src[axis], dst[axis] = slice(-off, n), slice(0, n + off)
            acc[tuple(dst)] += wgt * out[tuple(src)]
        out = acc
    return out


def expand_table(coarse: np.ndarray, bin_: int) -> np.ndarray:
    """Coarse (q, q, q) booleans -> the 256^3 table (each coarse cell repeated bin_^3 times)."""
    if bin_ == 1:
        return np.ascontiguousarray(coarse)
    q = coarse.shape[0]
    big = np.broadcast_to(coarse[:, None, :, None, :, None], (q, bin_, q, bin_, q, bin_))
    return np.ascontiguousarray(big).reshape(256, 256, 256)


def decide(ball_hist: np.ndarray, background_hist: np.ndarray, config: GolfConfig) -> np.ndarray:
    """Coarse decision on pixel *counts* (not densities): a colour is ball where the smoothed
    ball count, times ``lut_ball_weight``, beats the smoothed background count.

    Counts keep the prior: a marked ball has a few dozen pixels, its frame a million, so a colour
    that clouds or white lines share with the ball stays background unless the ball dominates it.
    ``lut_ball_weight`` trades that (misses) against false alarms; background counts are scaled
    back up by the sampling stride.
    """
    ball = smooth3(ball_hist, config.lut_smooth_bins)
    back = smooth3(background_hist, config.lut_smooth_bins) * config.lut_background_stride**2
    return (config.lut_ball_weight * ball > back) & (ball > config.lut_min_count)


def luminance_hist(y: np.ndarray, bins: int) -> np.ndarray:
    """Normalised luminance histogram of uint8 values (``bins`` divides 256)."""
    flat = np.asarray(y, dtype=np.uint8).ravel()
    if not flat.size:
        return np.zeros(bins)
    counts = np.bincount(flat >> int(np.log2(256 // bins)), minlength=bins).astype(np.float64)
    return counts / flat.size


@dataclass(frozen=True, eq=False)
class ColourLut:
    """One 256^3 boolean table (axes Y, Cb, Cr) and the luminance histogram it was built in."""

    name: str
    table: np.ndarray
    reference_hist: np.ndarray
    regions: int

    def lookup(self, ycc: np.ndarray) -> np.ndarray:
        """Boolean mask of ball-like pixels: one fancy index into the table."""
        return self.table.reshape(-1)[flat_index(ycc)]


@dataclass
class LutSet:
    """The sky and ground LUTs, built up as marked frames arrive (mutable, owned by one tracker)."""

    config: GolfConfig
    luts: dict[str, ColourLut] = field(default_factory=dict)
    _ball: dict[str, np.ndarray] = field(default_factory=dict)
    _background: dict[str, np.ndarray] = field(default_factory=dict)
    _context: dict[str, np.ndarray] = field(default_factory=dict)
    _count: dict[str, int] = field(default_factory=dict)
    consumed: set = field(default_factory=set)  # keys of regions already added
    _labels: np.ndarray | None = None  # luminance -> LUT index, rebuilt when the LUTs change

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(n for n in LUT_NAMES if n in self.luts)

    def add(self, image: np.ndarray, regions: Sequence[InitRegion]) -> list[RegionSamples]:
        """Add the marked boxes of one image and rebuild the LUTs they touch."""
        cfg = self.config
        touched: list[str] = []
        added = []
        for region in regions:
            samples = region_samples(image, region, cfg)
            if not len(samples.ball):
                continue
            added.append(samples)
            name = samples.name
            q = 256 // cfg.lut_bin
            self._ball.setdefault(name, np.zeros((q, q, q)))
            self._background.setdefault(name, np.zeros((q, q, q)))
            self._context.setdefault(name, np.zeros(cfg.lut_hist_bins))
            self._ball[name] += _coarse_hist(samples.ball, cfg.lut_bin)
            self._background[name] += _coarse_hist(samples.background, cfg.lut_bin)
            self._context[name] += luminance_hist(samples.context_y, cfg.lut_hist_bins)
            self._count[name] = self._count.get(name, 0) + 1
            if name not in touched:
                touched.append(name)
        for name in touched:
            coarse = decide(self._ball[name], self._background[name], cfg)
            ref = self._context[name] / max(self._context[name].sum(), 1e-12)
            self.luts[name] = ColourLut(name, expand_table(coarse, cfg.lut_bin), ref, self._count[name])
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
        centres = (np.arange(self.config.lut_hist_bins) + 0.5) * (256 / self.config.lut_hist_bins)
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
        another scores ``lut_switch_margin`` more. Returns the name and the scores in
        ``LUT_NAMES`` order (NaN for a LUT not built yet).
        """
        scores = np.full(len(LUT_NAMES), np.nan)
        if not self.luts:
            return "", scores
        if self._labels is None:
            self._labels = self.luminance_labels()
        flat = np.asarray(y, dtype=np.uint8).ravel()
        counts = np.bincount(flat, minlength=256).astype(np.float64)
        total = max(counts.sum(), 1.0)
        for i, name in enumerate(LUT_NAMES):
            if name in self.luts:
                scores[i] = float(counts[self._labels == i].sum() / total)
        if not flat.size:
            return (current if current in self.luts else self.names[0]), scores
        best = LUT_NAMES[int(np.nanargmax(scores))]
        if current in self.luts and best != current:
            if scores[LUT_NAMES.index(best)] < scores[LUT_NAMES.index(current)] + self.config.lut_switch_margin:
                best = current
        return best, scores


def build_luts(images_and_regions: Iterable[tuple[np.ndarray, Sequence[InitRegion]]], config: GolfConfig | None = None) -> LutSet:
    """Pure helper: a :class:`LutSet` from ``(image, regions marked on it)`` pairs."""
    luts = LutSet(config or GolfConfig())
    for image, regions in images_and_regions:
        luts.add(image, regions)
        luts.consumed.update(region_key(r) for r in regions)
    return luts


def region_key(region: InitRegion) -> tuple:
    """Identity of a marked box (so a box is added to the LUTs once)."""
    return (region.frame, region.x, region.y, region.w, region.h, region.label)
