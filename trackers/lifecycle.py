"""A track's life, shared by the trackers: started from a mark, held while unsupported, lost after N frames.

In the spirit of Stone Soup's initiator and time-based deleter (``stonesoup.initiator``,
``stonesoup.deleter.time.UpdateTimeStepsDeleter``): the tracker decides what *supports* its track on a
frame (a colour match, moving pixels, enough observation points, the ball's blob); this part counts the
frames in a row without support and says the row's status ("measured", "predicted", "lost"), and, once
lost, when a new match restarts the track. It holds no position: the tracker keeps its estimate.

API
---
``LifecycleConfig(lost_after, reacquire_frames=1)``
    The numbers, from each tracker's own config (built from its fields; this part never takes a whole
    tracker config). ``lost_after``: the track is lost on its ``lost_after``-th unsupported frame in a
    row (Stone Soup's ``time_steps_since_update = N`` deletes on the (N+1)-th: ``lost_after = N + 1``).
    ``reacquire_frames``: a lost track restarts after so many matching frames in a row, each within
    reach of the last (1: on the first match).
``TrackLife(config)`` — one track's life (mutable; one per track):
    ``start()`` the track starts (from a mark, or an initiator's group): no misses.
    ``supported() -> "measured"`` a frame that supports it: the misses are forgiven.
    ``held() -> "predicted"`` a frame held on a prediction: neither support nor a miss.
    ``missed() -> "predicted" | "lost"`` a frame without support: "lost" from the ``lost_after``-th in a row.
    ``lose() -> "lost"`` the track is dropped now (e.g. a time gap it cannot coast over), as on that miss.
    ``lost`` (property) True from the ``lost_after``-th miss in a row until a supported frame.
    ``misses`` the unsupported frames in a row.
    ``reacquiring(index, centre, reach) -> bool`` on a frame that matches: True while a lost track's
    match has not yet held on ``reacquire_frames`` consecutive frames (frame ``index``, each centre
    within ``reach`` per axis of the last); False when the track is not lost or the run is complete.
    ``TrackLife.merged(lives)`` the life of a track merged from several: the fewest misses.
``Run()`` — frames in a row of one kind (held on a prediction, placed by a region), bounded by a limit
    the caller gives at each check (it may change with the frame rate):
    ``count``; ``within(limit)`` (``limit`` None: unbounded); ``extend()``; ``reset()``.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

STATUS_MEASURED, STATUS_PREDICTED, STATUS_LOST = "measured", "predicted", "lost"


@dataclass(frozen=True)
class LifecycleConfig:
    """When a track is lost and when a lost one restarts (frames; see the module docstring)."""

    lost_after: int
    reacquire_frames: int = 1

    def __post_init__(self) -> None:
        if self.lost_after < 1 or self.reacquire_frames < 1:
            raise ValueError(f"lost_after and reacquire_frames must be >= 1, not {self.lost_after}, {self.reacquire_frames}")


class TrackLife:
    """One track's frames without support, and a lost track's run of new matches."""

    def __init__(self, config: LifecycleConfig) -> None:
        self.config = config
        self.misses = 0
        self._rematch: tuple[int, np.ndarray, int] | None = None  # lost: the last matching frame, centre, run

    @classmethod
    def merged(cls, lives: Iterable[TrackLife]) -> TrackLife:
        """A track made of several: as recently supported as the most recent of them (first one's config)."""
        lives = list(lives)
        life = cls(lives[0].config)
        life.misses = min(x.misses for x in lives)
        return life

    @property
    def lost(self) -> bool:
        return self.misses >= self.config.lost_after

    def start(self) -> None:
        self.misses = 0
        self._rematch = None

    def supported(self) -> str:
        self.misses = 0
        return STATUS_MEASURED

    def held(self) -> str:
        return STATUS_PREDICTED

    def missed(self) -> str:
        self.misses += 1
        return STATUS_LOST if self.lost else STATUS_PREDICTED

    def lose(self) -> str:
        self.misses = max(self.misses, self.config.lost_after)
        return STATUS_LOST

    def reacquiring(self, index: int, centre: np.ndarray, reach: np.ndarray) -> bool:
        """A lost track's match on frame ``index`` at ``centre``: True until it has held on
        ``reacquire_frames`` consecutive frames, each within ``reach`` (per axis) of the last."""
        if not self.lost:
            self._rematch = None
            return False
        last = self._rematch
        run = 1
        if last is not None and last[0] == index - 1 and bool(np.all(np.abs(centre - last[1]) <= reach)):
            run = last[2] + 1
        self._rematch = (index, np.copy(centre), run)
        if run < self.config.reacquire_frames:
            return True
        self._rematch = None
        return False


class Run:
    """Frames in a row of one kind (held, placed), bounded by a limit given at each check."""

    def __init__(self) -> None:
        self.count = 0

    def within(self, limit: int | None) -> bool:
        """True while fewer than ``limit`` frames are in the run (``None``: no bound)."""
        return limit is None or self.count < limit

    def extend(self) -> None:
        self.count += 1

    def reset(self) -> None:
        self.count = 0


__all__ = ["LifecycleConfig", "Run", "TrackLife", "STATUS_LOST", "STATUS_MEASURED", "STATUS_PREDICTED"]
