"""Background models of a fixed camera and the foreground they leave: what moved, pixel by pixel.

- :class:`MedianBackground` keeps up to ``capacity`` frames and answers their per-pixel median: a
  clean background as long as no object covers a pixel in half of the frames or more (frames
  before the target enters; or early frames through which it moves on).
- :func:`foreground_mask` thresholds the largest per-channel difference from a background and
  opens the result (drops isolated noisy pixels); :func:`largest_region` keeps one blob of it.

Deterministic: no random draw, and OpenCV's morphology gives the same bits on every run.
"""

from __future__ import annotations

from functools import lru_cache

import cv2
import numpy as np


@lru_cache(maxsize=None)
def sorting_network(n: int) -> tuple[tuple[int, int], ...]:
    """Batcher's odd-even merge sort on ``n`` items as comparators ``(i, j)``, ``i < j`` (the smaller
    value goes to ``i``): the network of the next power of two without the comparators that touch an
    index from ``n`` on (padding taken as the largest value: those never move anything)."""
    size = 1
    while size < n:
        size *= 2
    pairs = []
    p = 1
    while p < size:
        k = p
        while k >= 1:
            for j in range(k % p, size - k, 2 * k):
                for i in range(min(k, size - j - k)):
                    if (i + j) // (2 * p) == (i + j + k) // (2 * p) and i + j + k < n:
                        pairs.append((i + j, i + j + k))
            k //= 2
        p *= 2
    return tuple(pairs)


def sort_frames(stack: np.ndarray) -> np.ndarray:
    """``np.sort(stack, axis=0)``: the frames (first axis) sorted per element by a sorting network of
    whole-frame ``np.minimum``/``np.maximum`` (contiguous, vectorised passes; numpy's sort along the
    first axis walks the memory with a stride, ~15x slower on 25 frames). Values only: equal values
    are indistinguishable, so the result is the same array."""
    rows = _sorted_rows(np.array(stack, order="C", copy=True))
    return np.stack(rows) if rows else np.array(stack, copy=True)


def _sorted_rows(stack: np.ndarray) -> list[np.ndarray]:
    """:func:`sort_frames`'s frames, sorted in place in ``stack`` (C-ordered, the caller's to overwrite) and
    one spare frame, as a list (not stacked again: a median reads one or a few of them)."""
    rows = list(stack)
    spare = np.empty_like(rows[0]) if rows else None
    for i, j in sorting_network(len(rows)):
        np.minimum(rows[i], rows[j], out=spare)
        np.maximum(rows[i], rows[j], out=rows[j])
        rows[i], spare = spare, rows[i]
    return rows


def _largest(dtype: np.dtype) -> np.generic:
    """The largest value of ``dtype`` (infinity for a float)."""
    return np.iinfo(dtype).max if np.issubdtype(dtype, np.integer) else dtype.type(np.inf)


class MedianBackground:
    """The per-pixel median of the first ``capacity`` frames it is given (later ones are ignored)."""

    def __init__(self, capacity: int = 30) -> None:
        if capacity < 1:
            raise ValueError(f"a median background needs capacity >= 1, not {capacity}")
        self.capacity = capacity
        self._frames: list[np.ndarray] = []

    def __len__(self) -> int:
        return len(self._frames)

    @property
    def full(self) -> bool:
        return len(self._frames) >= self.capacity

    @property
    def frames(self) -> tuple[np.ndarray, ...]:
        """The frames kept so far, in the order added."""
        return tuple(self._frames)

    def add(self, image: np.ndarray) -> bool:
        """Keep ``image`` (a copy) while there is room; returns whether it was kept."""
        if self.full:
            return False
        if self._frames and image.shape != self._frames[0].shape:
            raise ValueError(f"background frames must share one shape: {image.shape} vs {self._frames[0].shape}")
        self._frames.append(np.array(image, copy=True))
        return True

    def model(self) -> np.ndarray | None:
        """The per-pixel median (uint8, the frames' shape; the upper middle value for an even
        count, so it is always one of the observed values), or None before any frame."""
        if not self._frames:
            return None
        return _sorted_rows(np.stack(self._frames))[len(self._frames) // 2].copy()

    def clear(self) -> None:
        """Let the frames go (the model, once taken, is all a tracker keeps)."""
        self._frames = []


class ExcludingMedianBackground(MedianBackground):
    """A :class:`MedianBackground` whose frames each leave a box out: per pixel the median of the
    frames that leave it in, so a target moving through the first frames is not in the background
    once it has left a place (the plain median waits for it to be gone from half of the frames).

    Each added frame leaves out its whole area until :meth:`leave_out` names its box. A pixel left
    out of every frame takes the plain median of all of them."""

    def __init__(self, capacity: int = 30, min_samples: int = 1) -> None:
        super().__init__(capacity)
        if min_samples < 1:
            raise ValueError(f"an excluding median needs min_samples >= 1, not {min_samples}")
        self.min_samples = min_samples
        self._boxes: list[np.ndarray | None] = []  # integer corners x0, y0, x1, y1 left out (None: the whole frame)

    def add(self, image: np.ndarray) -> bool:
        kept = super().add(image)
        if kept:
            self._boxes.append(None)
        return kept

    def leave_out(self, corners: np.ndarray) -> None:
        """The last added frame leaves out the pixels ``x0 <= x < x1, y0 <= y < y1`` (integer ``corners``)."""
        if self._boxes:
            self._boxes[-1] = np.asarray(corners, dtype=np.int64).reshape(4)

    def _inside(self, x0: int, y0: int, x1: int, y1: int) -> np.ndarray:
        """(frames, y1 - y0, x1 - x0) bool: the pixel lies in the frame's left-out box."""
        xs, ys = np.arange(x0, x1), np.arange(y0, y1)
        b = np.array([[-1, -1, -1, -1] if c is None else c for c in self._boxes], dtype=np.int64)
        unknown = np.array([c is None for c in self._boxes])
        in_x = ((xs >= b[:, :1]) & (xs < b[:, 2:3])) | unknown[:, None]
        in_y = ((ys >= b[:, 1:2]) & (ys < b[:, 3:4])) | unknown[:, None]
        return in_y[:, :, None] & in_x[:, None, :]

    def ready(self, corners: np.ndarray) -> bool:
        """Every pixel in ``corners`` (x0, y0, x1, y1) has ``min_samples`` frames that leave it in (or the frames are full)."""
        if self.full:
            return True
        if not self._frames:
            return False
        x0, y0, x1, y1 = (int(v) for v in corners)
        if x1 <= x0 or y1 <= y0:
            return False
        samples = len(self._frames) - self._inside(x0, y0, x1, y1).sum(axis=0)
        return bool(samples.min() >= self.min_samples)

    def model(self) -> np.ndarray | None:
        """Per pixel the median (the upper middle value, as :meth:`MedianBackground.model`) of the
        frames that leave it in; of all the frames where none does. One :func:`sort_frames` of the
        frames with the left-out values last (and the plain median only where every frame leaves a pixel out); a
        pixel every frame leaves in reads the middle rank, the others theirs within the bounds of those left out."""
        if not self._frames:
            return None
        stack = np.stack(self._frames)  # (F, H, W[, C])
        height, width = stack.shape[1:3]
        out = self._inside(0, 0, width, height)  # (F, H, W)
        every = out.all(axis=0)  # left out of every frame: the plain median
        some = out.any(axis=0) & ~every  # left out of some frames, not of all
        if not some.any():
            return super().model()
        # the plain median of the pixels left out of every frame only (sorting just them: the same values)
        plain = sort_frames(stack[:, every])[len(self._frames) // 2] if every.any() else None
        # a left-out value becomes the dtype's largest: sorted, the kept values come first (a kept
        # value equal to it is the same number), so the k-th of the kept ones is the k-th of all; a
        # pixel no frame leaves out sorts its own values, its plain median
        stack[out] = _largest(stack.dtype)
        ranked = _sorted_rows(stack)
        k = (~out).sum(axis=0) // 2  # per pixel the rank of its median among the sorted values
        middle = len(self._frames) // 2  # a pixel every frame leaves in (most of them)
        median = ranked[middle].copy()
        ys, xs = np.nonzero(some.any(axis=1))[0], np.nonzero(some.any(axis=0))[0]  # the pixels of lower rank: bounds
        y0, y1, x0, x1 = int(ys[0]), int(ys[-1]) + 1, int(xs[0]), int(xs[-1]) + 1
        ranks = np.stack([r[y0:y1, x0:x1] for r in ranked[:middle + 1]])  # within those bounds only
        kk = k[y0:y1, x0:x1].reshape(1, y1 - y0, x1 - x0, *([1] * (stack.ndim - 3)))
        median[y0:y1, x0:x1] = np.take_along_axis(ranks, np.broadcast_to(kk, (1, *ranks.shape[1:])), axis=0)[0]
        if plain is not None:
            median[every] = plain
        return median

    def clear(self) -> None:
        super().clear()
        self._boxes = []


def difference(image: np.ndarray, background: np.ndarray) -> np.ndarray:
    """Largest absolute per-channel difference, uint8 (H, W)."""
    diff = cv2.absdiff(image, background)
    if diff.ndim == 2:
        return diff
    channels = cv2.split(diff)  # OpenCV's max: the same values as numpy's max over the channels, ~10x faster
    out = channels[0]
    for c in channels[1:]:
        out = cv2.max(out, c)
    return out


def foreground_mask(image: np.ndarray, background: np.ndarray, threshold: float = 25.0, *,
                    open_px: int = 3) -> np.ndarray:
    """Bool (H, W): pixels that differ from ``background`` by more than ``threshold`` grey levels
    in some channel, after a morphological opening with an ``open_px`` square (0 or 1: none)."""
    mask = (difference(image, background) > threshold).astype(np.uint8)
    if open_px > 1:
        mask = cv2.morphologyEx(mask, cv2.MORPH_OPEN, np.ones((open_px, open_px), np.uint8))
    return mask.astype(bool)


def largest_region(mask: np.ndarray) -> np.ndarray:
    """The largest 8-connected region of a bool mask (ties: the lowest label), or an empty mask."""
    n, labels, stats, _ = cv2.connectedComponentsWithStats(mask.astype(np.uint8), connectivity=8)
    if n <= 1:
        return np.zeros(mask.shape, dtype=bool)
    return labels == 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))


def bounding_rect(mask: np.ndarray) -> tuple[int, int, int, int] | None:
    """``(x0, y0, x1, y1)`` (half-open) around the True pixels, None when there are none."""
    ys, xs = np.nonzero(mask)
    if xs.size == 0:
        return None
    return int(xs.min()), int(ys.min()), int(xs.max()) + 1, int(ys.max()) + 1
