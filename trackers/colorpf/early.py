"""The "early" background without the target (ours, ``reference.exclude``).

When the log starts with the target in the picture, eq. (7)'s background is the per-pixel median of
the first frames from the mark on (:class:`~trackreplay.trackers.colorpf.reference.BackgroundFrames`):
a pixel's median is the background once the target has covered it in fewer than half of them, so it
waits for ``reference.frames`` frames whatever the target does. Here each frame's **tracked box**
(the marked box on the marked frame, then the estimate), scaled by ``exclude`` per axis, is left out
of the median: a pixel's background is the median of the frames in which the track was elsewhere,
and the background is ready as soon as every pixel of the marked box has ``min_samples`` such frames
(the target has left its marked box), at the latest after ``capacity`` frames. Until then the
reference is the marked box's own histogram, as before. Pixels the track covered on every frame so
far (where the target is now) take the plain median of all the frames.
"""

from __future__ import annotations

import numpy as np

from trackreplay.trackers.colorpf.likelihood import box_corners


class ExcludingMedian:
    """Frames with the box to leave out of each; the median over the frames that leave a pixel in."""

    def __init__(self, capacity: int, min_samples: int, exclude: float) -> None:
        if capacity < 1 or min_samples < 1 or exclude < 1:
            raise ValueError("ExcludingMedian needs capacity >= 1, min_samples >= 1, exclude >= 1")
        self.capacity, self.min_samples, self.exclude = capacity, min_samples, exclude
        self._frames: list[np.ndarray] = []
        self._boxes: list[np.ndarray | None] = []  # integer corners x0, y0, x1, y1 left out (None: the whole frame)

    def __len__(self) -> int:
        return len(self._frames)

    @property
    def full(self) -> bool:
        return len(self._frames) >= self.capacity

    def add(self, image: np.ndarray) -> bool:
        """Keep ``image`` (a copy) while there is room; its box is unknown (all left out) until :meth:`leave_out`."""
        if self.full:
            return False
        self._frames.append(np.array(image, copy=True))
        self._boxes.append(None)
        return True

    def leave_out(self, box_xywh: np.ndarray) -> None:
        """The last frame's tracked box ``(x, y, w, h)`` (centre, size): it and ``exclude`` times it per axis are left out."""
        if not self._frames:
            return
        height, width = self._frames[-1].shape[:2]
        box = np.asarray(box_xywh, dtype=np.float64).copy()
        box[2:4] *= self.exclude
        self._boxes[-1] = box_corners(box, width, height)[0]

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
        """Per pixel the median (the upper middle value, as ``MedianBackground``) of the frames that
        leave it in; of all the frames where none does. uint8, the frames' shape; None before any frame.
        The plain median (``np.partition``) everywhere, then one ``np.sort`` over only the pixels some
        frames leave out (the track's corridor)."""
        if not self._frames:
            return None
        stack = np.stack(self._frames)  # (F, H, W[, C])
        height, width = stack.shape[1:3]
        median = np.partition(stack, len(stack) // 2, axis=0)[len(stack) // 2]
        out = self._inside(0, 0, width, height)  # (F, H, W)
        some = out.any(axis=0) & ~out.all(axis=0)  # left out of some frames, not of all
        if not some.any():
            return median
        left_out = out[:, some]  # (F, n)
        values = stack[:, some].astype(np.uint16)  # (F, n[, C])
        if values.ndim == 3:
            left_out = left_out[..., None]
        ranked = np.sort(np.where(left_out, np.uint16(256), values), axis=0)  # left-out values last
        k = ((~out[:, some]).sum(axis=0) // 2).reshape(1, -1, *([1] * (values.ndim - 2)))
        median[some] = np.take_along_axis(ranked, np.broadcast_to(k, (1, *values.shape[1:])), axis=0)[0]
        return median

    def clear(self) -> None:
        self._frames, self._boxes = [], []
