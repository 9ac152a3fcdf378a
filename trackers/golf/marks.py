"""The boxes the user marked on the ball (``/annotations/init``): the LUTs' samples and the start.

The tracker remembers every marked box it has seen (the frame bundle carries all of the log's
marks on every frame, and this frame's own); it starts from the latest box marked at or before the
current frame (a replay from the log's start begins on the first marked frame; one that starts
later begins from the nearest earlier mark), preferring a label with "start" or "init".
Once its frame's image is seen, each box is placed on the ball it was drawn round (:mod:`.snap`);
the LUTs and the start use the placed box.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from trackreplay.schemas.records import InitRegion
from trackreplay.trackers.golf.config import SnapConfig
from trackreplay.trackers.golf.lut import region_key
from trackreplay.trackers.golf.snap import snap_to_ball


class Marks:
    """Marked boxes in the order first seen, each once."""

    def __init__(self, snap: SnapConfig | None = None, core: float = 1.0) -> None:
        self.regions: list[InitRegion] = []  # as drawn
        self._keys: set = set()
        self._snap, self._core = snap or SnapConfig(), core  # core: the ball samples' share of a box (LutConfig.core)
        self._placed: dict[tuple, InitRegion] = {}  # a drawn box's key -> the box placed on its ball
        self._log_marks: object = None  # the log's marks last remembered (remember_log)

    def __bool__(self) -> bool:
        return bool(self.regions)

    def remember(self, regions: Iterable[InitRegion]) -> None:
        for r in regions:
            key = region_key(r)
            if key not in self._keys:
                self._keys.add(key)
                self.regions.append(r)

    def remember_log(self, regions: Iterable[InitRegion]) -> None:
        """The log's marks: the frame bundle carries them on every frame as one tuple, remembered once."""
        if regions is not self._log_marks or not isinstance(regions, tuple):
            self.remember(regions)
            self._log_marks = regions

    def place(self, image: np.ndarray, index: int) -> None:
        """Place the boxes marked on frame ``index`` on the ball in that frame's ``image`` (each once)."""
        for r in self.regions:
            if r.frame == index and region_key(r) not in self._placed:
                self._placed[region_key(r)] = snap_to_ball(image, r, self._snap, self._core)

    def _as_placed(self, region: InitRegion) -> InitRegion:
        return self._placed.get(region_key(region), region)

    def on(self, index: int) -> list[InitRegion]:
        """The boxes marked on frame ``index`` (placed on the ball once :meth:`place` saw the frame)."""
        return [self._as_placed(r) for r in self.regions if r.frame == index]

    def start_region(self, index: int) -> InitRegion | None:
        """The box to start from at frame ``index`` (None: nothing marked yet)."""
        past = [r for r in self.regions if r.frame <= index]
        if not past:
            return None
        latest = max(r.frame for r in past)
        on_latest = [r for r in past if r.frame == latest]
        for r in on_latest:
            if any(word in r.label.lower() for word in ("start", "init")):
                return self._as_placed(r)
        return self._as_placed(on_latest[0])
