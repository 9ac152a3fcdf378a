"""Still scenery (ours): white things that stay put while the ball is seen elsewhere.

A blob found at the same place (within ``still_px``) on two consecutive frames, on a frame where
the ball was measured more than a diameter away from it, is scenery: a cap, a sign, a flower in
the tree line. It stays scenery for as long as a blob is found there on every following frame
(pose changes followed when the log has them; "there": the blob's bounding box, grown by
``still_px``, holds the point, as a blob cut by the search region's edge moves its centroid), and
the blob gate refuses it (reason ``still``):
a white thing that stayed put while the ball was seen moving elsewhere is not the ball. Found on
a real shot played mirrored: the ball, faint in front of trees, was missed for one frame and the
nearest look-alike in the gate was a flower seen in the same place on the frames before, 32 px
behind the ball's path; it was measured, and the track stayed on the flower bed.

The ball itself never becomes scenery (it is the measured blob); nothing is added on a frame
where the ball was not measured (the tracker does not know where it is), and a new mark clears
it all (the user says where the ball is). A camera that moves without a pose in the log moves
the scenery in the image, so none is kept: the check only ever refuses, it never finds.
"""

from __future__ import annotations

import numpy as np

from trackreplay.trackers.foreground.blobs import Blobs
from trackreplay.trackers.geometry.homography import apply_homography


class Scenery:
    """The scenery points (in the latest frame's pixels) and the last frame's blobs."""

    def __init__(self, still_px: float) -> None:
        self.still_px = still_px  # at the reference height; 0: off
        self.points = np.zeros((0, 2))
        self._previous = np.zeros((0, 2))
        self._previous_index: int | None = None

    def reset(self) -> None:
        self.points = np.zeros((0, 2))
        self._previous = np.zeros((0, 2))
        self._previous_index = None

    def follow_camera(self, H: np.ndarray | None) -> None:
        """Carry the points and the last frame's blobs into this frame's pose (``H``: last pose ->
        this one; None: no pose, the pixels stay)."""
        if H is None:
            return
        if len(self.points):
            self.points = apply_homography(H, self.points)
        if len(self._previous):
            self._previous = apply_homography(H, self._previous)

    def add(self, point: np.ndarray) -> None:
        """A point known to be scenery (a blob refused as ``seen_before``: it was beside the ball before
        the loss): refused like the others while a blob still sits on it (``still_px`` 0: off, as the rest)."""
        if self.still_px <= 0:
            return
        self.points = np.concatenate([self.points, np.asarray(point, float).reshape(1, 2)])

    def on_scenery(self, blobs: Blobs, scale: float) -> np.ndarray:
        """(K,) bool: the blobs that sit on a scenery point."""
        return _holds(blobs.bbox, self.points, self.still_px * scale).any(axis=1)

    def update(self, index: int, blobs: Blobs, look_alike: np.ndarray, ball: tuple[float, float] | None, diameter: float,
               scale: float) -> None:
        """After frame ``index``: keep the points a blob still sits on; when the ball was measured at
        ``ball``, add the ``look_alike`` blobs (those the gate would take for the ball) whose centroid
        stayed (within ``still_px``) since the last frame, more than a diameter from it. (A still speck
        the gate refuses anyway is no scenery: it would only refuse the ball passing over it.)"""
        if self.still_px <= 0:
            return
        radius = self.still_px * scale
        centroids = np.asarray(blobs.centroid, float).reshape(-1, 2)
        kept = self.points[_holds(blobs.bbox, self.points, radius).any(axis=0)] if len(self.points) else self.points[:0]
        if ball is not None and self._previous_index == index - 1 and len(centroids):
            still = _near(centroids, self._previous, radius)
            away = np.hypot(centroids[:, 0] - ball[0], centroids[:, 1] - ball[1]) > diameter + radius
            fresh = centroids[still & away & np.asarray(look_alike, bool) & ~_near(centroids, kept, radius)]
            kept = np.concatenate([kept, fresh])
        self.points = kept
        self._previous, self._previous_index = centroids.copy(), index


def _holds(bbox: np.ndarray, points: np.ndarray, margin: float) -> np.ndarray:
    """(K, n) bool: bounding box ``k`` (x0, y0, w, h; pixel rows/columns), grown by ``margin``, holds point ``j``."""
    b = np.asarray(bbox, float).reshape(-1, 4)
    p = np.asarray(points, float).reshape(-1, 2)
    x0, y0 = b[:, 0:1] - 0.5 - margin, b[:, 1:2] - 0.5 - margin  # pixel centres at integers: a pixel spans +-0.5
    x1, y1 = b[:, 0:1] + b[:, 2:3] - 0.5 + margin, b[:, 1:2] + b[:, 3:4] - 0.5 + margin
    return (x0 <= p[None, :, 0]) & (p[None, :, 0] <= x1) & (y0 <= p[None, :, 1]) & (p[None, :, 1] <= y1)


def _near(a: np.ndarray, b: np.ndarray, radius: float) -> np.ndarray:
    """(len(a),) bool: each row of ``a`` within ``radius`` of some row of ``b``."""
    a = np.asarray(a, float).reshape(-1, 2)
    if not len(a) or not len(b):
        return np.zeros(len(a), bool)
    d2 = (a[:, None, 0] - b[None, :, 0]) ** 2 + (a[:, None, 1] - b[None, :, 1]) ** 2
    return (d2 <= radius * radius).any(axis=1)
