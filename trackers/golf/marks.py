"""The boxes the user marked on the ball (``/annotations/init``): the LUTs' samples and the start.

The tracker remembers every marked box it has seen (the frame bundle carries all of the log's
marks on every frame, and this frame's own); it starts from the latest box marked at or before the
current frame (a replay from the log's start begins on the first marked frame; one that starts
later begins from the nearest earlier mark), preferring a label with "start" or "init".
"""

from __future__ import annotations

from collections.abc import Iterable

from trackreplay.schemas.records import InitRegion
from trackreplay.trackers.golf.lut import region_key


class Marks:
    """Marked boxes in the order first seen, each once."""

    def __init__(self) -> None:
        self.regions: list[InitRegion] = []
        self._keys: set = set()

    def __bool__(self) -> bool:
        return bool(self.regions)

    def remember(self, regions: Iterable[InitRegion]) -> None:
        for r in regions:
            key = region_key(r)
            if key not in self._keys:
                self._keys.add(key)
                self.regions.append(r)

    def on(self, index: int) -> list[InitRegion]:
        """The boxes marked on frame ``index``."""
        return [r for r in self.regions if r.frame == index]

    def start_region(self, index: int) -> InitRegion | None:
        """The box to start from at frame ``index`` (None: nothing marked yet)."""
        past = [r for r in self.regions if r.frame <= index]
        if not past:
            return None
        latest = max(r.frame for r in past)
        on_latest = [r for r in past if r.frame == latest]
        for r in on_latest:
            if any(word in r.label.lower() for word in ("start", "init")):
                return r
        return on_latest[0]
