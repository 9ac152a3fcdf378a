"""What every tracker exchanges with the replay engine (ARCHITECTURE.md ★ Replay contract)."""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, Protocol

import numpy as np

from trackreplay.schemas.records import InitRegion
from trackreplay.trackers.frame import Frame

Marked = Iterable[tuple[np.ndarray, Sequence[InitRegion]]]  # (image, regions marked on it) per marked frame

STATUSES = ("measured", "predicted", "interpolated", "lost")
POSITION_FIELDS = ("x", "y", "X", "Y", "Z", "dx", "dy", "dz")
# An intermediate's dataclass field with this metadata is what a drawn value is computed from on read
# (a camera, a model's constants), not a result: the replay digest and diff's per-field hashes skip it.
NOT_HASHED = {"digest": False}


@dataclass(frozen=True)
class TrackState:
    """One track's estimate in one frame (a row of the ★ trajectory table)."""

    track_id: int
    x: float | None = None
    y: float | None = None
    w: float | None = None
    h: float | None = None
    X: float | None = None
    Y: float | None = None
    Z: float | None = None
    dx: float | None = None
    dy: float | None = None
    dz: float | None = None
    vx: float | None = None
    vy: float | None = None
    status: str = "measured"
    confidence: float | None = None  # in [0, 1], where the tracker has one

    def __post_init__(self) -> None:
        if self.status not in STATUSES:
            raise ValueError(f"status must be one of {STATUSES}, not {self.status!r}")
        if self.status == "lost" and any(getattr(self, c) is not None for c in POSITION_FIELDS):
            raise ValueError("a lost track state has no position (ARCHITECTURE ★ trajectory table)")
        if self.confidence is not None and not 0.0 <= self.confidence <= 1.0:
            raise ValueError(f"confidence must be in [0, 1], not {self.confidence!r}")


class Tracker(Protocol):
    """A tracker is built from ``(config, rng)``, prepared once, then stepped once per frame.

    ``prepare`` receives every frame the log's init annotations mark, before the first step
    (the engine always calls it). After each ``step`` its ``intermediates`` hold that frame's
    inner results as plain numpy data (a frozen dataclass); the engine hashes them into the
    digest and, when a Rerun recording is on, hands them to the tracker's view.
    """

    name: ClassVar[str]
    intermediates: Any

    def __init__(self, config: Any, rng: np.random.Generator) -> None: ...

    def prepare(self, marked: Marked) -> None: ...

    def step(self, frame: Frame) -> list[TrackState]: ...


class TrackerBase(ABC):
    """The :class:`Tracker` protocol's defaults; trackers subclass it and override what they use."""

    name: ClassVar[str]
    intermediates: Any = None

    def prepare(self, marked: Marked) -> None:  # noqa: B027 (a default, not an abstract method)
        """Learn from the marked frames before the first step.

        Does nothing by design: most trackers start from the hints a frame carries when it
        arrives; one that must see every mark up front (the golf tracker's LUTs) overrides this.
        """

    @abstractmethod
    def step(self, frame: Frame) -> list[TrackState]:
        """This frame's track states; sets ``self.intermediates``."""
