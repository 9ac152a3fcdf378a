"""What the golf tracker carries from one frame to the next, in small named pieces.

- :class:`PreviousFrame`: the frame before (its pose, index, time and picture);
- :class:`BallLook`: what the ball looks like (§2.1's blob targets, the LUT picking it out, the
  marked ball's size) and the pixel scale that follows from it;
- :class:`Sightings`: the frames the ball was measured on since the track (re)started;
- :class:`FrameView`: this frame against the one before (per frame: the pose change, whether the
  samples follow it, whether the operator's camera follows the ball).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from trackreplay.trackers.frame import Frame
from trackreplay.trackers.geometry.ptz import PtzCamera, pose_homography
from trackreplay.trackers.golf.blobs import BlobTargets
from trackreplay.trackers.golf.reinit import ReinitPolicy
from trackreplay.trackers.golf.seen_before import LastSighting


@dataclass(frozen=True, eq=False)
class PreviousFrame:
    """The frame before this one (all None before the first)."""

    camera: PtzCamera | None = None
    index: int | None = None
    t_ns: int | None = None
    image: np.ndarray | None = None

    @classmethod
    def of(cls, frame: Frame) -> PreviousFrame:
        return cls(frame.camera, frame.index, frame.t_ns, frame.image)


@dataclass
class BallLook:
    """What the ball looks like: the blob gate's targets (§2.1, set from past ball regions; None
    before the first mark), the LUT that picks it out, and the last mark's ball diameter measured
    from its silhouette (0: not measured, a box may be drawn loose)."""

    targets: BlobTargets | None = None
    lut_name: str = ""
    marked_diameter: float = 0.0

    def scale(self, height: int, reference_height: int, reference_ball_px: float) -> float:
        """The factor on every pixel parameter: the frame's height over ``reference_height``, or the
        ball's diameter over ``reference_ball_px`` when that is larger. The parameters were set on
        balls 14-16 px across at 1080 lines; a ball larger than that for its frame (a close camera, a
        portrait clip turned on its side, a crop) moves and blurs as many of its own diameters a frame
        as the reference ball does, so its gates and speeds grow with it. The diameter is the marked
        ball's, then the targets' as the ball flies off and shrinks, never more than the marked one (a
        blob that grows may be the ball merged with something white)."""
        by_height = height / reference_height
        if not self.marked_diameter or self.targets is None or reference_ball_px <= 0:
            return by_height
        return max(by_height, min(self.marked_diameter, self.targets.diameter) / reference_ball_px)


@dataclass
class Sightings:
    """The frames the ball was measured on since the track (re)started."""

    count: int = 0
    last_step: tuple[int, float, float] | None = None  # frame, x, y of the last one (None: no step of the ball's since)
    last: LastSighting | None = None  # the frame it was last measured on (:mod:`.seen_before`)
    first: tuple[float, float] | None = None  # where it was first measured since the (re)start
    moved: bool = False  # measured more than a diameter from there since

    def restart(self) -> None:
        """A mark re-anchors the track: nothing seen since."""
        self.count, self.last_step, self.last, self.first, self.moved = 0, None, None, None, False

    def add(self, index: int, x: float, y: float, sighting: LastSighting) -> None:
        self.count += 1
        self.last_step = (index, x, y)
        self.last = sighting
        if self.first is None:
            self.first = (x, y)
        self.moved = self.moved or math.hypot(x - self.first[0], y - self.first[1]) > sighting.diameter

    def resting(self, index: int) -> tuple[float, float, float] | None:
        """(x, y, diameter) of the ball measured on the frame before ``index`` when it has not moved
        since it was first measured (a ball marked at rest, waiting to be struck); else None."""
        last = self.last
        if self.moved or self.last_step is None or last is None or self.last_step[0] != index - 1:
            return None
        return self.last_step[1], self.last_step[2], last.diameter


@dataclass(frozen=True, eq=False)
class FrameView:
    """This frame against the frame before: the pose change between them (None: a pose is missing),
    whether the samples move with it (``compensated``), and whether the operator's camera follows
    the ball (:meth:`ReinitPolicy.follows`, asked once a frame: only a measurement changes its answer)."""

    frame: Frame
    previous: PreviousFrame
    pose_change: np.ndarray | None
    compensated: bool
    policy: ReinitPolicy

    @classmethod
    def of(cls, frame: Frame, previous: PreviousFrame, policy: ReinitPolicy, compensate: bool) -> FrameView:
        """``compensate``: the samples live in camera-independent directions (a started track with
        ``particles.compensate_camera_motion``), so they move with the pose change when there is one."""
        camera, before = frame.camera, previous.camera
        change = pose_homography(before, camera) if camera is not None and before is not None else None
        return cls(frame, previous, change, compensate and change is not None, policy)

    @property
    def camera(self) -> PtzCamera | None:
        return self.frame.camera

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) px."""
        height, width = self.frame.image.shape[:2]
        return width, height

    @functools.cached_property
    def follows(self) -> bool:
        width, height = self.size
        return self.policy.follows(self.camera, self.previous.camera, width, height, self.pose_change)
