"""The colour likelihood of a box, eqs. (4)-(5): Swain's intersection with the reference, then exp(k S²).

Pixels become bin indices once per frame (only inside the union of the particles' boxes), then all
N box histograms are counted together (:meth:`ColourModel.histograms`). ``"hs"`` bins H and S only (§3.1:
a uniform brightness change leaves them alone); ``"hsv"`` is Pérez et al.'s H-S + V histogram, the
paper's comparison in Table 1; ``"gradient"`` (ours, for pictures without hue) bins the grey level of
flat pixels and the gradient direction of edges (:mod:`~trackreplay.trackers.appearance.gradient`).

Two switches of ours weigh the pixels with an Epanechnikov kernel (``likelihood.kernel``, on by
default; ``"uniform"`` is the paper) and split the box into bands (``likelihood.parts``, off by
default), each with its own histogram
(:func:`~trackreplay.trackers.appearance.histogram.box_part_histograms`); :func:`mean_shift` refines
an estimate with the same histograms. A histogram here is flat, ``parts * n_bins`` long.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from trackreplay.trackers.appearance.color import HSV_RANGES, to_hsv
from trackreplay.trackers.appearance.gradient import grey_gradient_index
from trackreplay.trackers.appearance.histogram import box_part_histograms, hs_index, hs_v_index, kernel_and_part
from trackreplay.trackers.colorpf.config import LikelihoodConfig


@dataclass(frozen=True)
class ColourModel:
    """Which bins a BGR pixel falls in; ``n_bins`` in all. ``edge_min``: ``"gradient"`` only, the Sobel
    magnitude from which a pixel is an edge (set once at the mark, so every histogram bins alike)."""

    config: LikelihoodConfig
    edge_min: float = 1.0
    # box_part_histograms' buffers, kept between the frames of one tracker (the same numbers, fewer page faults)
    scratch: dict[str, np.ndarray] = field(default_factory=dict, compare=False, repr=False)
    # the last bin-index crop made (:meth:`crop_index`): the picture it is of, its corners, the index
    recent: list[tuple[np.ndarray, tuple[int, int, int, int], np.ndarray]] = field(default_factory=list, compare=False,
                                                                                    repr=False)

    @property
    def shape(self) -> tuple[int, ...]:
        """The histogram's shape for display: (T, T) for "hs", (T*T + T,) for "hsv"; with parts > 1
        the parts stacked: (parts T, T) and (parts, T*T + T)."""
        t, p = self.config.bins, self.config.parts
        if self.config.histogram == "hs":
            return (p * t, t)
        return (self.n_bins,) if p == 1 else (p, self.n_bins)

    @property
    def n_bins(self) -> int:
        """Bins of one part's histogram."""
        t = self.config.bins
        if self.config.histogram == "gradient":
            return t + self.config.orientations
        return t * t if self.config.histogram == "hs" else t * t + t

    @property
    def parts(self) -> int:
        return self.config.parts

    def histograms(self, index: np.ndarray, boxes: np.ndarray, max_pixels: int | None) -> tuple[np.ndarray, np.ndarray]:
        """(K, parts * n_bins) histograms of integer boxes ``x0, y0, x1, y1`` in a bin-index image."""
        cfg = self.config
        h, n = box_part_histograms(index, boxes, self.n_bins, kernel=cfg.kernel, parts=cfg.parts, max_pixels=max_pixels,
                                   scratch=self.scratch)
        return h.reshape(len(h), -1), n

    def similarity(self, hists: np.ndarray, reference: np.ndarray) -> np.ndarray:
        """Eq. (4) per histogram (rows of ``hists``): Swain's intersection, per part, and with parts
        their geometric mean ``(prod_p S_p)^(1/parts)``."""
        p = self.config.parts
        hists = np.asarray(hists, dtype=np.float64)
        per_part = np.minimum(hists.reshape(*hists.shape[:-1], p, self.n_bins),
                              np.asarray(reference, dtype=np.float64).reshape(p, self.n_bins)).sum(axis=-1)
        if p == 1:
            return per_part[..., 0]
        return np.prod(per_part, axis=-1) ** (1.0 / p)

    def index(self, bgr: np.ndarray) -> np.ndarray:
        """Bin index per pixel (int32, the image's shape without channels)."""
        cfg = self.config
        if cfg.histogram == "gradient":
            return grey_gradient_index(bgr, cfg.bins, cfg.orientations, self.edge_min)[0]
        hsv = to_hsv(bgr)
        if cfg.histogram == "hs":
            return hs_index(hsv, (cfg.bins, cfg.bins), HSV_RANGES)[0]
        return hs_v_index(hsv, (cfg.bins,) * 3, HSV_RANGES, s_min=cfg.s_min, v_min=cfg.v_min)[0]

    def crop_index(self, image: np.ndarray, x0: int, y0: int, x1: int, y1: int) -> np.ndarray:
        """:meth:`index` of ``image[y0:y1, x0:x1]``; ``"gradient"`` reads one pixel more on each side where
        the image has it, so a crop's edge pixels have the derivatives they have in the whole frame. A crop within
        the last one made of the same picture (the estimate's box in the particles' union, the particles' union in
        a scan's) is cut from it: every pixel's bin is its own (``"gradient"``: a pixel's derivatives read its
        3x3 neighbours, which the larger crop holds or the picture's edge bounds alike)."""
        if self.recent:
            picture, (a0, b0, a1, b1), index = self.recent[0]
            if picture is image and a0 <= x0 and b0 <= y0 and x1 <= a1 and y1 <= b1:
                return index[y0 - b0:y1 - b0, x0 - a0:x1 - a0]
        index = self._crop_index(image, x0, y0, x1, y1)
        self.recent[:] = [(image, (int(x0), int(y0), int(x1), int(y1)), index)]
        return index

    def _crop_index(self, image: np.ndarray, x0: int, y0: int, x1: int, y1: int) -> np.ndarray:
        if self.config.histogram != "gradient":
            return self.index(image[y0:y1, x0:x1])
        height, width = image.shape[:2]
        a0, b0, a1, b1 = max(x0 - 1, 0), max(y0 - 1, 0), min(x1 + 1, width), min(y1 + 1, height)
        cfg = self.config
        return grey_gradient_index(image[b0:b1, a0:a1], cfg.bins, cfg.orientations, self.edge_min,
                                   (x0 - a0, y0 - b0, a1 - x1, b1 - y1))[0]

    def pooled_similarity(self, hists: np.ndarray, reference: np.ndarray) -> np.ndarray:
        """Intersection of the parts' mean histogram with the reference's: the colours regardless of
        where in the box they are (= :meth:`similarity` with one part). The status uses it (a target
        seen at a wrong scale moves its colours between the bands, and the confidence should not say
        "lost" for that); the particles' weights use :meth:`similarity`."""
        p = self.config.parts
        if p == 1:
            return self.similarity(hists, reference)
        hists = np.asarray(hists, dtype=np.float64)
        mean_h = hists.reshape(*hists.shape[:-1], p, self.n_bins).mean(axis=-2)
        mean_r = np.asarray(reference, dtype=np.float64).reshape(p, self.n_bins).mean(axis=0)
        return np.minimum(mean_h, mean_r).sum(axis=-1)

    def likelihood(self, similarity: np.ndarray) -> np.ndarray:
        """Eq. (5): ``L = exp(k S²)``."""
        return np.exp(self.config.k * np.asarray(similarity, dtype=np.float64) ** 2)

    def similarity_for(self, likelihood: float) -> float:
        """The intersection S at which eq. (5) reaches ``likelihood`` (e.g. l = 25 -> 0.40)."""
        return float(np.sqrt(np.log(likelihood) / self.config.k))


def box_corners(states: np.ndarray, width: int, height: int) -> np.ndarray:
    """(N, 4) integer ``x0, y0, x1, y1`` of the boxes ``(x, y, w, h)`` (centre, size), clipped to
    the image (a box wholly outside becomes empty). Pixel ``i`` covers ``[i - 0.5, i + 0.5)``."""
    s = np.asarray(states, dtype=np.float64).reshape(-1, 4)
    half = s[:, 2:4] / 2.0
    lo = np.floor(s[:, :2] - half + 0.5)
    hi = np.floor(s[:, :2] + half + 0.5)
    limit = np.array([width, height], dtype=np.float64)
    # np.clip(v, 0, limit) is minimum(maximum(v, 0), limit) (NaN kept), without np.clip's wrapper (called ~7x a frame)
    out = np.empty((len(s), 4), dtype=np.int64)
    lo = np.minimum(np.maximum(lo, 0.0), limit)
    out[:, :2] = lo
    out[:, 2:] = np.minimum(np.maximum(np.maximum(hi, lo), 0.0), limit)
    return out


@dataclass(frozen=True, eq=False)
class Measurement:
    """Every particle's histogram score this frame."""

    similarity: np.ndarray  # (N,) S, eq. (4)
    likelihood: np.ndarray  # (N,) L, eq. (5)
    pixels: np.ndarray  # (N,) pixels counted per box (0: the box left the image)


def measure(model: ColourModel, image: np.ndarray, states: np.ndarray, reference: np.ndarray) -> Measurement:
    """Eqs. (4)-(5) for every particle box ``(x, y, w, h)`` against the reference histogram."""
    height, width = image.shape[:2]
    corners = box_corners(states, width, height)
    x0, y0 = corners[:, :2].min(axis=0)
    x1, y1 = corners[:, 2:].max(axis=0)
    if x1 <= x0 or y1 <= y0:  # every box is outside the image
        n = len(corners)
        zero = np.zeros(n)
        return Measurement(zero, model.likelihood(zero), np.zeros(n, dtype=np.int64))
    index = model.crop_index(image, x0, y0, x1, y1)  # only the union of the boxes is converted
    local = corners - np.array([x0, y0, x0, y0])
    hists, pixels = model.histograms(index, local, model.config.max_pixels)
    similarity = model.similarity(hists, reference)
    return Measurement(similarity, model.likelihood(similarity), pixels)


def box_histogram(model: ColourModel, image: np.ndarray, state: np.ndarray) -> np.ndarray:
    """The histogram of one box ``(x, y, w, h)`` (e.g. the estimate), flat, zeros if outside."""
    height, width = image.shape[:2]
    x0, y0, x1, y1 = box_corners(state, width, height)[0]
    if x1 <= x0 or y1 <= y0:
        return np.zeros(model.parts * model.n_bins)
    index = model.crop_index(image, x0, y0, x1, y1)
    return model.histograms(index, np.array([[0, 0, x1 - x0, y1 - y0]]), model.config.max_pixels)[0][0]


def mean_shift(model: ColourModel, image: np.ndarray, state: np.ndarray, reference: np.ndarray,
               iterations: int) -> tuple[np.ndarray, float]:
    """Comaniciu et al.'s mean shift from ``state`` ``(x, y, w, h)`` (size kept): each step moves the
    centre to the mean of the box's pixels weighted by ``sqrt(q_u / p_u)`` (``q`` the reference,
    ``p`` the box's histogram, ``u`` the pixel's bin, per part; the kernel's support only) and is kept
    only when it raises S.
    Returns the refined state and its S. Each step counts every pixel of the box (not sampled to
    ``likelihood.max_pixels``: one box, a few steps) as one vectorised block; the loop is over the
    iterations.
    """
    height, width = image.shape[:2]
    state = np.asarray(state, dtype=np.float64).copy()
    q = np.asarray(reference, dtype=np.float64).reshape(model.parts, model.n_bins)
    # one bin-index image covering every box the steps can reach (a box's half size around the start)
    ux0, uy0, ux1, uy1 = box_corners(np.array([state[0], state[1], 2 * state[2], 2 * state[3]]), width, height)[0]
    best_s, best_state = -1.0, state.copy()
    if ux1 <= ux0 or uy1 <= uy0:
        return state, 0.0
    index = model.crop_index(image, ux0, uy0, ux1, uy1)
    for i in range(iterations + 1):
        x0, y0, x1, y1 = box_corners(state, width, height)[0]
        if x1 <= x0 or y1 <= y0 or x0 < ux0 or y0 < uy0 or x1 > ux1 or y1 > uy1:
            break
        local = np.array([[x0 - ux0, y0 - uy0, x1 - ux0, y1 - uy0]])
        hist = model.histograms(index, local, None)[0][0].reshape(model.parts, model.n_bins)
        s = float(model.similarity(hist.reshape(-1), q))
        if i > 0 and s <= best_s:  # the step did not help: keep the previous position
            break
        best_s, best_state = s, state.copy()
        if i == iterations:
            break
        bins = index[y0 - uy0:y1 - uy0, x0 - ux0:x1 - ux0]
        dy, dx = np.arange(y1 - y0)[:, None] + 0.5, np.arange(x1 - x0)[None, :] + 0.5
        kern, part = kernel_and_part(dy, dx, y1 - y0, x1 - x0, model.config.kernel, model.parts)
        p = hist[part, bins]
        # the Epanechnikov profile's derivative is constant on its support: the step is the mean of
        # the support's pixels weighted by sqrt(q/p) alone (Comaniciu et al. 2003, eq. 13)
        w = (kern > 0) * np.where(p > 0, np.sqrt(q[part, bins] / np.where(p > 0, p, 1.0)), 0.0)
        total = w.sum()
        if total <= 0:
            break
        cx = x0 + float((w * dx).sum() / total)
        cy = y0 + float((w * dy).sum() / total)
        if abs(cx - state[0]) < 0.25 and abs(cy - state[1]) < 0.25:
            break
        state[0], state[1] = cx, cy
    return best_state, max(best_s, 0.0)
