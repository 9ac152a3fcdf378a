"""Re-detection of a lost target over the whole picture (``[colorpf.redetect]``, ours; issue 31).

Once the track is "lost" the particle cloud has nothing to follow: it spreads by eq. (2)'s random walk
wherever it was when the colour stopped matching, and finds the target again only if the walk happens to
cross it (uav123_person12_1: the walker lost at frame ~41 was found again at four tracker seeds of five).
While lost, :func:`scan` scores a regular grid of boxes of the last supported size over the whole picture
against the reference histogram as built (eq. (4), the particles' vectorised histograms; no random draw:
the grid is fixed), and the tracker (``ColorPfTracker._redetect``) injects part of the cloud round the best
box when that box is a colour match by the confidence's own rule and the only one in the picture
(:func:`unique_best`), stands out from eq. (7)'s background where there is one, beats the cloud's own
estimate, and the mark's lead over the background exceeds the scanned scores' spread. The lost track is
then "measured" again only on the usual evidence (``reacquire_frames`` matches in a row, each near the
last; the neighbour and layout checks).
"""

from __future__ import annotations

import numpy as np

from trackreplay.trackers.colorpf.likelihood import ColourModel, measure


def grid(wh: np.ndarray, lo: np.ndarray, hi: np.ndarray, stride: float, max_boxes: int) -> np.ndarray:
    """(M, 4) boxes ``(x, y, w, h)`` of size ``wh`` whose centres step by ``stride`` times the box per axis
    from ``lo`` to ``hi`` (the centres' bounds per axis; ``hi < lo`` on an axis: the middle alone), the
    stride widened evenly until there are at most ``max_boxes``. Every centre within the bounds is then
    within half a stride of a box's: at stride 0.5 a quarter box per axis."""
    wh = np.maximum(np.asarray(wh, dtype=np.float64)[:2], 1.0)
    lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    mid = (lo + hi) / 2.0
    lo, hi = np.minimum(lo, mid), np.maximum(hi, mid)
    step = np.maximum(stride * wh, 1.0)
    counts = np.floor((hi - lo) / step).astype(np.int64) + 1
    while int(counts.prod()) > max_boxes:
        step *= 1.25
        counts = np.floor((hi - lo) / step).astype(np.int64) + 1
    xs = lo[0] + (hi[0] - lo[0] - (counts[0] - 1) * step[0]) / 2.0 + step[0] * np.arange(counts[0])
    ys = lo[1] + (hi[1] - lo[1] - (counts[1] - 1) * step[1]) / 2.0 + step[1] * np.arange(counts[1])
    cx, cy = np.meshgrid(xs, ys)
    n = cx.size
    return np.column_stack([cx.ravel(), cy.ravel(), np.full(n, wh[0]), np.full(n, wh[1])])


def scan(model: ColourModel, image: np.ndarray, reference: np.ndarray, wh: np.ndarray, stride: float,
         max_boxes: int) -> tuple[np.ndarray, np.ndarray]:
    """The grid's boxes over the whole picture (:func:`grid`; each box wholly inside where the picture allows)
    and each one's eq. (4) similarity to ``reference``."""
    height, width = image.shape[:2]
    size = np.array([width, height], dtype=np.float64)
    half = np.minimum(np.asarray(wh, dtype=np.float64)[:2] / 2.0, size / 2.0)
    boxes = grid(wh, half, size - half, stride, max_boxes)
    return boxes, measure(model, image, boxes, reference).similarity


def unique_best(boxes: np.ndarray, confidence: np.ndarray, threshold: float) -> int | None:
    """The index of the box with the highest confidence (the first in row order on a tie) when it reaches
    ``threshold`` and no box that does not overlap it does (its centre a box's width or height away): the one
    match in the picture. None otherwise: no match, or a look-alike elsewhere matches as well, and the scan
    cannot tell which is the target."""
    best = int(np.argmax(confidence))
    if confidence[best] < threshold:
        return None
    apart = np.any(np.abs(boxes[:, :2] - boxes[best, :2]) >= boxes[best, 2:4], axis=1)
    if apart.any() and float(confidence[apart].max()) >= threshold:
        return None
    return best


__all__ = ["grid", "scan", "unique_best"]
