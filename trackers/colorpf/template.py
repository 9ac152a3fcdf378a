"""A layout (template) cue multiplied into the colour likelihood (ours, ``likelihood.template``).

A colour histogram has no spatial layout: a dark walker and a dark car behind it score alike. The
cue is the normalised cross-correlation (``cv2.TM_CCOEFF_NORMED``: zero-mean, unit-norm, so it
ignores a uniform gain and offset) of a small grey template of the target against the frame at each
particle's box, and the particle's likelihood becomes ``L exp(template * max(NCC, 0))``.

Vectorised as the foreground cue is: every particle is taken at its **position** with the previous
estimate's **size** (one box size for all), so one ``cv2.matchTemplate`` over the window covering all
particles' boxes gives the NCC of every position, read at each particle's centre. Both the window and
the template are first scaled so that the template's longer side is at most ``template_side`` pixels
(a walker close to the camera costs no more than a far one). A particle whose box leaves the image
scores 0 (no layout evidence).

The template is the marked box's grey pixels (:class:`TemplateModel`). ``template_mask`` says which of
them count: "foreground", eq. (7)'s foreground mask of the marked box (the target's own pixels; the
whole box until a background exists), "kernel", the Epanechnikov weights, or "none", the whole box
(whose background — a horizon line, a floor edge — then moves with the box and biases the match).

Opt-in (``likelihood.template = 0`` by default): no setting measured met the bar for a default
(docs/colorpf.md, "Layout (template) cue" and "Issue 7: what was tried").
"""

from __future__ import annotations

import cv2
import numpy as np

from trackreplay.trackers.appearance.color import to_grey


TEMPLATE_SIDE = 48  # the stored template is at most this many pixels on its longer side


def epanechnikov(w: int, h: int) -> np.ndarray:
    """max(1 - r^2, 0) over a w x h grid, r in half-widths / half-heights from the centre."""
    u = (np.arange(w, dtype=np.float32) + 0.5) / w * 2.0 - 1.0
    v = (np.arange(h, dtype=np.float32) + 0.5) / h * 2.0 - 1.0
    return np.maximum(1.0 - u[None, :] ** 2 - v[:, None] ** 2, 0.0).astype(np.float32)


class TemplateModel:
    """The target's grey template: the marked box's pixels (corners ``x0, y0, x1, y1``), scaled to at
    most ``TEMPLATE_SIDE`` px on its longer side, and the weights of its pixels (None: all alike)."""

    def __init__(self, image: np.ndarray, corners: np.ndarray, mask: str) -> None:
        x0, y0, x1, y1 = (int(v) for v in corners)
        w, h = x1 - x0, y1 - y0
        s = min(1.0, TEMPLATE_SIDE / max(w, h, 1))
        self.wh = (max(int(round(w * s)), 3), max(int(round(h * s)), 3))
        self.mode = mask
        self.template: np.ndarray | None = None
        self.weights: np.ndarray | None = epanechnikov(*self.wh) if mask == "kernel" else None
        if w >= 3 and h >= 3:
            self.template = cv2.resize(to_grey(image[y0:y1, x0:x1], "mean"), self.wh, interpolation=cv2.INTER_AREA)

    def set_foreground(self, fg: np.ndarray) -> None:
        """``template_mask = "foreground"``: eq. (7)'s foreground mask of the marked box (its pixels)."""
        if self.mode == "foreground" and fg.size and fg.any():
            self.weights = cv2.resize(fg.astype(np.float32), self.wh, interpolation=cv2.INTER_AREA)

    def blend(self, image: np.ndarray, box: np.ndarray, rate: float) -> None:
        """T <- (1 - rate) T + rate (the box's pixels), when the box is wholly inside the image."""
        if self.template is None or rate <= 0:
            return
        height, width = image.shape[:2]
        x, y, w, h = (float(v) for v in box[:4])
        x0, y0 = int(np.floor(x - w / 2 + 0.5)), int(np.floor(y - h / 2 + 0.5))
        x1, y1 = int(np.floor(x + w / 2 + 0.5)), int(np.floor(y + h / 2 + 0.5))
        if x0 < 0 or y0 < 0 or x1 > width or y1 > height or x1 - x0 < 3 or y1 - y0 < 3:
            return
        c = cv2.resize(to_grey(image[y0:y1, x0:x1], "mean"), self.wh, interpolation=cv2.INTER_AREA)
        self.template = (1.0 - rate) * self.template + rate * c


def template_scores(image: np.ndarray, template: np.ndarray, xy: np.ndarray, size: np.ndarray,
                    max_side: int = 24, weights: np.ndarray | None = None) -> np.ndarray:
    """NCC (``TM_CCOEFF_NORMED``, in [-1, 1]) of ``template`` (pixel ``weights``, None: uniform)
    resized to ``size`` (w, h) against the frame at boxes of that size centred at each row of ``xy``;
    0 for a box not wholly inside the image. Image window and template are scaled so the template's
    longer side is at most ``max_side``."""
    xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    out = np.zeros(len(xy))
    height, width = image.shape[:2]
    w, h = float(size[0]), float(size[1])
    s = min(1.0, max_side / max(w, h))
    tw, th = max(int(round(w * s)), 3), max(int(round(h * s)), 3)
    lo = xy - np.array([w, h]) / 2.0  # the boxes' top-left edges (pixel i covers [i - 0.5, i + 0.5))
    inside = (lo[:, 0] >= -0.5) & (lo[:, 1] >= -0.5) & (lo[:, 0] + w <= width + 0.5) & (lo[:, 1] + h <= height + 0.5)
    if not inside.any():
        return out
    x0 = max(int(np.floor(lo[inside, 0].min() + 0.5)), 0)
    y0 = max(int(np.floor(lo[inside, 1].min() + 0.5)), 0)
    x1 = min(int(np.ceil(lo[inside, 0].max() + 0.5 + w)) + 1, width)
    y1 = min(int(np.ceil(lo[inside, 1].max() + 0.5 + h)) + 1, height)
    window = to_grey(image[y0:y1, x0:x1], "mean")
    if s < 1.0:
        window = cv2.resize(window, (max(int(round((x1 - x0) * s)), 1), max(int(round((y1 - y0) * s)), 1)),
                            interpolation=cv2.INTER_AREA)
    if window.shape[0] < th or window.shape[1] < tw:
        return out
    t = cv2.resize(template.astype(np.float32), (tw, th), interpolation=cv2.INTER_AREA)
    m = None
    if weights is not None:
        m = cv2.resize(weights.astype(np.float32), (tw, th), interpolation=cv2.INTER_AREA)
    r = cv2.matchTemplate(window, t, cv2.TM_CCOEFF_NORMED, mask=m)
    r = np.clip(np.nan_to_num(r, nan=0.0, posinf=0.0, neginf=0.0), -1.0, 1.0)
    # the response at each box's top-left (scaled window pixels), bilinear between the map's samples
    u = np.clip((lo[inside, 0] + 0.5 - x0) * s, 0.0, r.shape[1] - 1.0)
    v = np.clip((lo[inside, 1] + 0.5 - y0) * s, 0.0, r.shape[0] - 1.0)
    c0, r0 = np.floor(u).astype(np.int64), np.floor(v).astype(np.int64)
    c1, r1 = np.minimum(c0 + 1, r.shape[1] - 1), np.minimum(r0 + 1, r.shape[0] - 1)
    fu, fv = u - c0, v - r0
    out[inside] = ((1 - fv) * ((1 - fu) * r[r0, c0] + fu * r[r0, c1]) + fv * ((1 - fu) * r[r1, c0] + fu * r[r1, c1]))
    return out
