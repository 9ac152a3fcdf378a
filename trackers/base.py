"""What every tracker exchanges with the replay engine (docs/architecture.md §4 Tracker contract)."""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, Protocol

import numpy as np

from trackreplay.schemas.records import InitRegion
from trackreplay.trackers.frame import Frame
from trackreplay.trackers.smoothing import DEFAULT_SMOOTHING, SmoothingModel

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
            raise ValueError("a lost track state has no position (docs/architecture.md §5 Trajectory contract)")
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


NEEDS = ("", "mark", "stereo", "depth")
# A tracker's raw measurements of one step as smoother observation rows, keyed by the columns of
# ``trackreplay.replay.core.observations.OBS_SCHEMA`` without ``tracker`` and ``frame`` (the replay
# adds them): ``(intermediates, states, stereo rig or None, config as replayed) -> rows``.
ObservationRows = Callable[[Any, Sequence[TrackState], Any, Any], list[dict]]


@dataclass(frozen=True)
class TrackerSpec:
    """Everything the replay side knows about a tracker, declared once by the tracker: its package
    exports one as ``SPEC``, the registry (``trackreplay.replay.core.registry``) lists them, and a
    third-party tracker is added with ``registry.register(spec)``. Nothing else is read off the
    tracker class, its instances or its intermediates.
    """

    name: str
    config_cls: type
    tracker_cls: type
    # Its Rerun view: a module (or object) with ``blueprint(name)`` and ``log(rec, name, frame,
    # intermediates, states)``, or its dotted module name (views live in ``trackreplay.replay.views``,
    # which trackers do not import; the registry imports the name).
    view: Any
    # What it cannot start without: "" (nothing), "mark" (a marked box on a replayed frame), "stereo"
    # (a calibrated stereo pair), "depth" (a calibrated stereo pair, or one camera with a ground plane).
    # The replay refuses a log that lacks it before any frame is decoded.
    needs: str = ""
    mark_labels: tuple[str, ...] | None = None  # the mark labels it reads; None: every label
    # It follows one object: two different marks on a frame, neither labelled start/init, are refused.
    one_start_per_frame: bool = False
    # The frame the trajectory's X Y Z are in ("world": Z up, "camera"), read off the tracker after
    # the replay (it may depend on the log: groups is "world" when the log carries the rig's pose).
    position_frame: Callable[[Any], str | None] | None = None
    observations: ObservationRows | None = None  # raw measurements for the offline smoother
    extra_rows: Callable[[Any], list[dict]] | None = None  # a second table's rows from a step's intermediates
    notice: Callable[[Any], str] | None = None  # a change of mode in words, from a step's intermediates
    # The offline smoother's motion model, or a function of the config as replayed (None: the
    # defaults) that gives it: its tracks' noise may be the tracker's own filter's.
    smoothing: SmoothingModel | Callable[[Any], SmoothingModel] = DEFAULT_SMOOTHING
    # Tracks every object in view at once: evaluated with multi-object metrics (MOTA, IDF1), since the
    # single-object ones pair one track with one ground-truth object.
    multi_object: bool = False
    ball_flight: bool = False  # its tracks are a ball in flight: ``trackreplay flight`` fits them in 3-D

    def __post_init__(self) -> None:
        if not self.name or not self.name.isidentifier():
            raise ValueError(f"a tracker's name is a word (it names TOML tables and digests), not {self.name!r}")
        if self.needs not in NEEDS:
            raise ValueError(f"needs must be one of {NEEDS}, not {self.needs!r}")
        if self.mark_labels is not None and not self.mark_labels:
            raise ValueError("mark_labels: None (every label) or at least one label")

    def smoothing_model(self, config: Any = None) -> SmoothingModel:
        """The smoother's model for tracks replayed with ``config`` (None: the config's defaults)."""
        model = self.smoothing
        return model if isinstance(model, SmoothingModel) else model(config)
