"""The reference histogram, §3.2: background subtraction at initialisation, then eq. (7).

``H_ref = (P_detect / P_square) H_target + ((P_square - P_detect) / P_square) H_back`` — the paper
prints ``P_detect - P_square`` in the second weight, which would make it negative; corrected in docs/papers.md §3
(the two weights sum to one, so ``H_ref`` stays normalised).

``P_detect`` are the marked box's foreground pixels (their histogram is ``H_target``), ``P_square``
the box's pixels, ``H_back`` the histogram of the **whole** background image. With
``likelihood.kernel`` (ours, on by default) / ``likelihood.parts`` (ours, off) the counts are kernel-weighted
and eq. (7) is applied per part: ``H_ref,p = a_p H_target,p + (1 - a_p) H_back`` with ``a_p`` the
(weighted) share of part ``p`` that the foreground covers.

Where the background comes from (:class:`BackgroundFrames`): the per-pixel median of the frames
before the marked one (``"before"``: the paper's background subtraction at initialisation, the
target not yet in the picture); or, when the log starts with the target already there, the median
of the first frames from the marked one on (``"early"``: a walking target leaves each pixel within
a few frames, so the median is the background again), the marked frame kept until then. With no
usable background the reference is the marked box's own histogram (target and its surroundings
inside the box, i.e. no separate ``H_back``), said once in a notice.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from trackreplay.trackers.appearance.histogram import image_part_histograms, index_histogram
from trackreplay.trackers.colorpf.camera import IDENTITY, apply, scale_of, warp
from trackreplay.trackers.colorpf.config import ReferenceConfig
from trackreplay.trackers.colorpf.likelihood import ColourModel, box_corners
from trackreplay.trackers.foreground.background import ExcludingMedianBackground, MedianBackground, foreground_mask


def mixed_reference(h_target: np.ndarray, h_back: np.ndarray, p_detect: float, p_square: float) -> np.ndarray:
    """Eq. (7) as corrected (docs/papers.md §3): ``(P_d / P_s) H_target + ((P_s - P_d) / P_s) H_back``."""
    if p_square <= 0 or not 0 <= p_detect <= p_square:
        raise ValueError(f"eq. (7) needs 0 <= P_detect <= P_square and P_square > 0, not {p_detect}, {p_square}")
    a = p_detect / p_square
    return a * np.asarray(h_target, dtype=np.float64) + (1.0 - a) * np.asarray(h_back, dtype=np.float64)


@dataclass(frozen=True, eq=False)
class Reference:
    """The reference and how it was made (flat histograms, ``model.parts * model.n_bins`` long)."""

    histogram: np.ndarray  # H_ref used by eq. (4)
    kind: str  # "mixed" (eq. 7) | "target" (H_target only) | "box" (the marked box's histogram: no background)
    background: str  # where the background came from: "before" | "early" | "none"
    h_target: np.ndarray
    h_back: np.ndarray  # zeros when there is no background
    p_detect: int
    p_square: int
    mask: np.ndarray  # (h, w) bool foreground of the marked box; (0, 0) without a background
    mask_offset: np.ndarray  # (2,) int: the box's top-left pixel


def box_reference(model: ColourModel, image: np.ndarray, box: np.ndarray) -> Reference:
    """No background: the marked box's own histogram."""
    h = _box_hist(model, image, box)
    x0, y0, x1, y1 = box
    return Reference(h, "box", "none", h, np.zeros_like(h), 0, int((x1 - x0) * (y1 - y0)),
                     np.zeros((0, 0), bool), np.array([x0, y0], dtype=np.int64))


def _box_hist(model: ColourModel, image: np.ndarray, box: np.ndarray) -> np.ndarray:
    x0, y0, x1, y1 = (int(v) for v in box)
    index = model.crop_index(image, x0, y0, x1, y1)
    return model.histograms(index, np.array([[0, 0, x1 - x0, y1 - y0]]), None)[0][0]


def subtract_and_mix(model: ColourModel, cfg: ReferenceConfig, image: np.ndarray, background: np.ndarray,
                     box: np.ndarray, source: str) -> tuple[Reference | None, str]:
    """Background subtraction in the marked box, then eq. (7) (or H_target alone for ``mode="target"``).

    Returns ``(None, why)`` when the background is unusable: the foreground fills less than
    ``min_fill`` of the box (the background still holds the target, or nothing is there) or more
    than ``max_fill`` (the background is not this scene's).
    """
    x0, y0, x1, y1 = (int(v) for v in box)
    fg = foreground_mask(image[y0:y1, x0:x1], background[y0:y1, x0:x1], cfg.threshold, open_px=cfg.open_px)
    p_square, p_detect = int(fg.size), int(fg.sum())
    fill = p_detect / max(p_square, 1)
    if not cfg.min_fill <= fill <= cfg.max_fill:
        return None, (f"the foreground fills {fill:.0%} of the marked box (usable: {cfg.min_fill:.0%}-"
                      f"{cfg.max_fill:.0%})")
    index = model.crop_index(image, x0, y0, x1, y1)
    lik = model.config
    h_target, w_fg, w_all = image_part_histograms(index, model.n_bins, kernel=lik.kernel, parts=lik.parts, mask=fg)
    whole = model.crop_index(background, 0, 0, background.shape[1], background.shape[0])
    h_back = index_histogram(whole, model.n_bins)  # the whole background
    if cfg.mode == "mixed":
        # eq. (7) per part with the (kernel-weighted) foreground share: uniform weights and one part
        # give the paper's P_detect / P_square exactly (sums of ones)
        h_ref = np.stack([mixed_reference(h_target[j], h_back, min(w_fg[j], w_all[j]), w_all[j])
                          if w_all[j] > 0 else h_back for j in range(lik.parts)])  # a loop over the parts
        kind = "mixed"
    else:
        h_ref, kind = h_target, "target"
    h_ref, h_target = np.asarray(h_ref).reshape(-1), np.asarray(h_target).reshape(-1)
    h_back = np.tile(h_back, lik.parts)  # the same background for every part
    return Reference(h_ref, kind, source, h_target, h_back, p_detect, p_square, fg,
                     np.array([x0, y0], dtype=np.int64)), ""


class BackgroundFrames:
    """Collects the frames the background median is taken from, for a mark on frame ``start``.

    ``"before"`` keeps the last ``frames`` frames before ``start``; ``"early"`` the first ``frames``
    from ``start`` on; ``"auto"`` decides at ``start``: "before" when at least ``min_frames`` frames
    came before it, else "early". ``"none"``: no background.
    """

    def __init__(self, cfg: ReferenceConfig, start: int) -> None:
        self.cfg = cfg
        self.start = start
        self.source = cfg.background
        self._before: list[np.ndarray] = []
        self._early = ExcludingMedianBackground(cfg.frames, cfg.min_frames) if cfg.exclude > 0 else MedianBackground(cfg.frames)
        self._marked: np.ndarray | None = None  # reference.exclude: the marked box's corners (ready once it is free)
        self.early_count = 0
        self.frames = cfg.frames  # the median's window in this log's frames (set_frames)
        self._early_indices: list[int] = []  # the frame index of each early frame kept

    def set_frames(self, frames: int) -> None:
        """The median's window as ``frames`` of this log's frames (``reference.frames`` at the log's rate:
        colorpf.timing): the frames kept before the mark, and the early median's capacity while it collects."""
        self.frames = frames
        if not self._early.full:
            self._early.capacity = max(frames, len(self._early), 1)

    def offer(self, index: int, image: np.ndarray, transform: np.ndarray | None = None) -> None:
        """Every frame before the mark and, while "early" is collecting, after it; ``transform``
        (``camera.compensate``): the camera's motion since the marked frame (3x3), taken back so the
        median is of the marked frame's view."""
        if index < self.start:
            if self.source in ("before", "auto") and index >= self.start - self.frames:
                self._before.append(image)
        elif self.source == "early":
            back = None if transform is None or np.array_equal(transform, IDENTITY) else np.linalg.inv(transform)
            if self._early.add(image if back is None else warp(image, back)):
                self._early_indices.append(index)

    def at_start(self, image: np.ndarray) -> tuple[np.ndarray | None, str]:
        """At the marked frame: the background now (``"before"``), or None and the source to wait for."""
        cfg = self.cfg
        if self.source == "none":
            return None, "none"
        if self.source == "auto":
            self.source = "before" if len(self._before) >= cfg.min_frames else "early"
        if self.source == "before":
            frames, self._before = self._before[-self.frames:], []  # (the window known once the rate is)
            if len(frames) < cfg.min_frames:
                return None, "none"
            median = MedianBackground(len(frames))
            for f in frames:
                median.add(f)
            return median.model(), "before"
        if self._early.add(image):
            self._early_indices.append(self.start)
        return None, "early"

    def leave_out(self, box_xywh: np.ndarray, size: tuple[int, int], marked: np.ndarray | None = None,
                  transform: np.ndarray | None = None) -> None:
        """``reference.exclude``: the last offered frame's tracked box ``(x, y, w, h)`` in an image of
        ``size`` (width, height), times ``exclude`` per axis, left out of the early median
        (``marked``: the marked box's corners, on the marked frame). The background is then ready as
        soon as every pixel of the marked box has ``min_frames`` frames without the track there (the
        target has left it), at the latest after ``frames`` frames: it need not wait for the target to
        be gone from half of them."""
        if marked is not None:
            self._marked = marked
        if self.source == "early" and isinstance(self._early, ExcludingMedianBackground):
            box = np.asarray(box_xywh, dtype=np.float64).copy()
            box[2:4] *= self.cfg.exclude
            if transform is not None and not np.array_equal(transform, IDENTITY):
                # camera.compensate: in the marked frame's view, as the frame was added
                box[:2] = apply(np.linalg.inv(transform), box[:2])[0]
                box[2:4] /= scale_of(transform)
            self._early.leave_out(box_corners(box, *size)[0])

    @property
    def early_ready(self) -> bool:
        if self.source != "early":
            return False
        if isinstance(self._early, ExcludingMedianBackground) and self._marked is not None:
            return self._early.ready(self._marked)
        return self._early.full

    def early_frames(self) -> dict[int, np.ndarray]:
        """The frames the early median is taken over (the marked frame's view) by frame index (a frame the
        log skipped is not there); empty once the median is taken (:meth:`early_model` lets them go)."""
        return dict(zip(self._early_indices, self._early.frames)) if self.source == "early" else {}

    def early_model(self) -> np.ndarray | None:
        self.early_count = len(self._early)  # the frames the median was taken over
        model = self._early.model()
        self._early.clear()
        self.source = "used"
        return model


def marked_box(region_xywh: tuple[float, float, float, float], width: int, height: int) -> np.ndarray:
    """The marked box's integer corners ``x0, y0, x1, y1`` in the image."""
    return box_corners(np.array(region_xywh, dtype=np.float64), width, height)[0]
