"""Typed, immutable Python records mirroring the log's protobuf messages.

Trackers and the replay layer work with these, never with protobuf objects; the
``to_pb``/``from_pb`` pairs are the only place the two meet.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from google.protobuf.timestamp_pb2 import Timestamp

from trackreplay.schemas import messages as m

_OPTIONAL_GT_FIELDS = ("x", "y", "w", "h", "X", "Y", "Z", "vx", "vy", "visible", "group")


def timestamp(t_ns: int) -> Timestamp:
    """A protobuf Timestamp for an integer nanosecond time."""
    return Timestamp(seconds=t_ns // 1_000_000_000, nanos=t_ns % 1_000_000_000)


def t_ns_of(ts: Timestamp) -> int:
    return ts.seconds * 1_000_000_000 + ts.nanos


@dataclass(frozen=True)
class PtzReading:
    """Pan/tilt in degrees and raw zoom/focus lens values at time ``t_ns``."""

    t_ns: int
    pan: float
    tilt: float
    zoom: float
    focus: float

    def to_pb(self) -> m.PtzEncoders:
        return m.PtzEncoders(
            timestamp=timestamp(self.t_ns), pan=self.pan, tilt=self.tilt, zoom=self.zoom, focus=self.focus
        )

    @classmethod
    def from_pb(cls, pb) -> PtzReading:
        return cls(t_ns_of(pb.timestamp), pb.pan, pb.tilt, pb.zoom, pb.focus)


@dataclass(frozen=True)
class LensEntry:
    zoom: float
    focus: float
    fx: float
    fy: float
    cx: float
    cy: float


@dataclass(frozen=True)
class LensTable:
    """Zoom/focus encoder values -> pinhole intrinsics, plus the camera's world position."""

    width: int
    height: int
    entries: tuple[LensEntry, ...]
    camera_position: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def to_pb(self, t_ns: int = 0) -> m.LensTable:
        x, y, z = self.camera_position
        return m.LensTable(
            timestamp=timestamp(t_ns),
            width=self.width,
            height=self.height,
            camera_x=x,
            camera_y=y,
            camera_z=z,
            entries=[m.LensEntry(zoom=e.zoom, focus=e.focus, fx=e.fx, fy=e.fy, cx=e.cx, cy=e.cy) for e in self.entries],
        )

    @classmethod
    def from_pb(cls, pb) -> LensTable:
        entries = tuple(LensEntry(e.zoom, e.focus, e.fx, e.fy, e.cx, e.cy) for e in pb.entries)
        return cls(pb.width, pb.height, entries, (pb.camera_x, pb.camera_y, pb.camera_z))


@dataclass(frozen=True)
class GroundTruthObject:
    """One object's truth in one frame; ``None`` means absent (not zero)."""

    id: int
    x: float | None = None
    y: float | None = None
    w: float | None = None
    h: float | None = None
    X: float | None = None
    Y: float | None = None
    Z: float | None = None
    vx: float | None = None
    vy: float | None = None
    visible: bool | None = None
    group: int | None = None

    def to_pb(self) -> m.GroundTruthObject:
        pb = m.GroundTruthObject(id=self.id)
        for name in _OPTIONAL_GT_FIELDS:
            value = getattr(self, name)
            if value is not None:
                setattr(pb, name, value)
        return pb

    @classmethod
    def from_pb(cls, pb) -> GroundTruthObject:
        values = {name: getattr(pb, name) if pb.HasField(name) else None for name in _OPTIONAL_GT_FIELDS}
        return cls(id=pb.id, **values)


@dataclass(frozen=True)
class GroundTruthFrame:
    frame: int
    t_ns: int
    objects: tuple[GroundTruthObject, ...] = field(default_factory=tuple)

    def to_pb(self) -> m.GroundTruthFrame:
        return m.GroundTruthFrame(
            timestamp=timestamp(self.t_ns),
            frame=self.frame,
            t_ns=self.t_ns,
            objects=[o.to_pb() for o in self.objects],
        )

    @classmethod
    def from_pb(cls, pb) -> GroundTruthFrame:
        return cls(pb.frame, pb.t_ns, tuple(GroundTruthObject.from_pb(o) for o in pb.objects))


@dataclass(frozen=True)
class InitRegion:
    """A box the user marked: centre ``(x, y)``, size ``(w, h)`` in pixels, on ``frame``."""

    frame: int
    t_ns: int
    x: float
    y: float
    w: float
    h: float
    label: str = "target"

    def to_pb(self) -> m.InitRegion:
        return m.InitRegion(
            frame=self.frame, t_ns=self.t_ns, x=self.x, y=self.y, w=self.w, h=self.h, label=self.label
        )

    @classmethod
    def from_pb(cls, pb) -> InitRegion:
        return cls(pb.frame, pb.t_ns, pb.x, pb.y, pb.w, pb.h, pb.label)


def init_annotations_pb(regions: tuple[InitRegion, ...] | list[InitRegion], t_ns: int) -> m.InitAnnotations:
    return m.InitAnnotations(timestamp=timestamp(t_ns), regions=[r.to_pb() for r in regions])
