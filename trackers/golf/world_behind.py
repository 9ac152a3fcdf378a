"""The world behind the ball (ours): a blob that does not stand out from the recent pictures is no ball in play.

Without a pose in the log the tracker cannot tell a white thing that stays put (a pale spot on a
floor, a line, a cap) from the ball by its colour: on a wide-angle badminton rally it measured a
spot on the floor for 170 frames at confidence 1.0 (docs/ball_corpus.md). What tells them apart is
motion: the world behind a ball in play is what the last few pictures saw at that place while the
ball was elsewhere. So the tracker keeps the last ``frames`` pictures (their luminance) and takes,
over the search region, the per-pixel median of those of the same view: the world behind. A picture
is of the same view when, over small copies (long side 256 px), its median pixel changed by at most
``max_change`` grey levels (a camera that panned, a hand-held one, a cut: not used). A blob stands out when the median, over its bounding box, of ``|Y - world|``
reaches ``noise_sigmas`` robust σ of that difference over the region (σ never below what rounding two
pictures to grey levels leaves, and at least one grey level). A blob that does not is refused like
still scenery (:mod:`.scenery`, reason ``still``): the track says "predicted", then "lost", rather than
"measured" on the floor.

The check only ever refuses; it never finds. It says nothing (every blob passes) when fewer than
``min_frames`` of the kept pictures are of the same view, or when the frame has a pose (the encoders' own machinery handles a turning camera:
:func:`.silhouette.moving_silhouette`). A ball at rest (teed, landed) is refused too: at rest it
cannot be told from scenery by one camera, and "lost" is the honest answer there.
"""

from __future__ import annotations

import dataclasses
import math
from collections import deque
from dataclasses import dataclass

import cv2
import numpy as np

from trackreplay.trackers.appearance.color import to_grey
from trackreplay.trackers.foreground.blobs import Blobs
from trackreplay.trackers.golf.config import WorldBehindConfig

SMALL_SIDE = 256  # the long side of the copies compared to tell a fixed view (px)
ROUNDING_SIGMA = math.sqrt(2.0 / 12.0)  # a difference of two values each rounded to whole grey levels


@dataclass(frozen=True)
class _Picture:
    index: int
    grey: np.ndarray  # full-size luminance (uint8)
    small: np.ndarray  # float32 copy, long side SMALL_SIDE
    step: float  # full-size pixels per small pixel


@dataclass(frozen=True, eq=False)
class WorldBehindCrop:
    """The world behind one search region: the recent pictures of the same view and the difference
    from their median a blob must reach."""

    y: np.ndarray  # (h, w) luminance of the region
    offset: tuple[int, int]  # the region's top-left in the frame
    seen: tuple[np.ndarray, ...]  # full-size luminance of each recent picture of the same view
    threshold: float = 0.0  # grey levels
    resting: tuple[float, float, float] | None = None  # (x, y, radius): where a ball that has not moved yet rests

    def stack(self, rows: slice, cols: slice) -> np.ndarray:
        """(n, h, w) the usable pictures' pixels behind ``y[rows, cols]``."""
        x0, y0 = self.offset
        return np.stack([grey[y0:, x0:][rows, cols] for grey in self.seen])

    def difference(self, rows: slice, cols: slice) -> np.ndarray:
        """|Y - world| over ``y[rows, cols]``, the world the per-pixel median of the usable pictures."""
        return np.abs(self.y[rows, cols].astype(np.float32) - np.median(self.stack(rows, cols), axis=0))

    def still(self, blobs: Blobs, asked: np.ndarray) -> np.ndarray:
        """(K,) bool: of the blobs ``asked`` about, those whose bounding box, in median, does not stand
        out from the world behind it (the others: False). A blob where a ball marked at rest still lies
        (:attr:`resting`) is not asked about: it waits to be struck. A ball that came to rest after it
        moved is asked about like anything else: one camera cannot tell it from scenery."""
        out = np.zeros(len(blobs), bool)
        if self.resting is not None:
            x, y, radius = self.resting
            c = np.asarray(blobs.centroid, float).reshape(-1, 2)
            asked = asked & (np.hypot(c[:, 0] - x, c[:, 1] - y) > radius)
        h, w = self.y.shape
        bbox = np.asarray(blobs.bbox, np.int64).reshape(-1, 4)
        for k in np.flatnonzero(asked):
            x0, y0, bw, bh = bbox[k]
            c0, r0 = max(int(x0) - self.offset[0], 0), max(int(y0) - self.offset[1], 0)
            c1, r1 = min(int(x0) + int(bw) - self.offset[0], w), min(int(y0) + int(bh) - self.offset[1], h)
            if c1 > c0 and r1 > r0:
                out[k] = float(np.median(self.difference(slice(r0, r1), slice(c0, c1)))) < self.threshold
        return out

    def noise_sigma(self) -> float:
        """The robust σ of |Y - world| over the region (on at most ~4096 of its pixels, evenly spread),
        never below what rounding to grey levels leaves."""
        h, w = self.y.shape
        stride = max(int(math.sqrt(self.y.size / 4096.0)), 1)
        sample = self.difference(slice(0, h, stride), slice(0, w, stride))
        return max(1.4826 * float(np.median(sample)), ROUNDING_SIGMA)


class WorldBehind:
    """The last pictures of a log without a pose, and the world behind a region of the next one."""

    def __init__(self, cfg: WorldBehindConfig) -> None:
        self.cfg = cfg
        self._pictures: deque[_Picture] = deque(maxlen=max(cfg.frames, 1))
        self._now: tuple[int, np.ndarray, np.ndarray] | None = None  # (frame index, grey, small) of the frame asked about

    def push(self, index: int, image: np.ndarray) -> None:
        """Keep frame ``index``'s picture (after the frame is tracked)."""
        if self.cfg.frames == 0:
            return
        grey, small, step = self._copies(index, image)
        self._pictures.append(_Picture(index, grey, small, step))
        self._now = None

    def _copies(self, index: int, image: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        """Frame ``index``'s luminance and its small copy (made once per frame)."""
        if self._now is not None and self._now[0] == index:
            grey, small = self._now[1], self._now[2]
        else:
            grey = to_grey(image)
            small = _small(grey, _step(grey))
            self._now = (index, grey, small)
        return grey, small, _step(grey)

    def behind(self, index: int, image: np.ndarray, y: np.ndarray, offset: tuple[int, int],
               resting: tuple[float, float, float] | None = None) -> WorldBehindCrop | None:
        """The world behind the region of frame ``index`` whose luminance is ``y`` (top-left ``offset``;
        ``resting``: :attr:`WorldBehindCrop.resting`); None: no judgement (too few pictures of the
        same view, or the region is empty)."""
        if self.cfg.frames == 0 or y.size == 0 or len(self._pictures) < self.cfg.min_frames:
            return None
        _, now, _ = self._copies(index, image)
        seen = tuple(p.grey for p in self._pictures if self._same_view(p, now))
        if len(seen) < self.cfg.min_frames:
            return None
        crop = WorldBehindCrop(y, offset, seen, resting=resting)
        return dataclasses.replace(crop, threshold=max(self.cfg.noise_sigmas * crop.noise_sigma(), 1.0))

    def _same_view(self, picture: _Picture, now: np.ndarray) -> bool:
        """Over the small copies, ``picture``'s median pixel changed by at most ``max_change`` grey levels."""
        return picture.small.shape == now.shape and float(np.median(np.abs(picture.small - now))) <= self.cfg.max_change


def _step(grey: np.ndarray) -> float:
    """Full-size pixels per pixel of the small copy."""
    return max(grey.shape) / SMALL_SIDE if max(grey.shape) > SMALL_SIDE else 1.0


def _small(grey: np.ndarray, step: float) -> np.ndarray:
    """The float32 copy the translation is measured on."""
    size = (max(int(round(grey.shape[1] / step)), 1), max(int(round(grey.shape[0] / step)), 1))
    return cv2.resize(grey, size, interpolation=cv2.INTER_AREA).astype(np.float32)
