"""Background models of a fixed camera and the foreground they leave: what moved, pixel by pixel.

- :class:`MedianBackground` keeps up to ``capacity`` frames and answers their per-pixel median: a
  clean background as long as no object covers a pixel in half of the frames or more (frames
  before the target enters; or early frames through which it moves on).
- :func:`foreground_mask` thresholds the largest per-channel difference from a background and
  opens the result (drops isolated noisy pixels); :func:`largest_region` keeps one blob of it.

Deterministic: no random draw, and OpenCV's morphology gives the same bits on every run.
"""

from __future__ import annotations

import cv2
import numpy as np


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
        stack = np.stack(self._frames)
        return np.partition(stack, len(stack) // 2, axis=0)[len(stack) // 2]

    def clear(self) -> None:
        """Let the frames go (the model, once taken, is all a tracker keeps)."""
        self._frames = []


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
