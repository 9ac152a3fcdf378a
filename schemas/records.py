"""Typed, immutable Python records mirroring the log's protobuf messages.

Trackers and the replay layer work with these, never with protobuf objects; the
``to_pb``/``from_pb`` pairs are the only place the two meet.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from google.protobuf.timestamp_pb2 import Timestamp

from trackreplay.schemas import messages as m

_OPTIONAL_GT_FIELDS = ("x", "y", "w", "h", "X", "Y", "Z", "vx", "vy", "visible", "group")
# Record attribute -> protobuf field. World coordinates are ``world_x``… in the schema (``X`` and
# ``x`` collide under protobuf's JSON names); logs written before the rename call them X, Y, Z
# (same field numbers), and a log is decoded with the schema it carries, so both are read.
_GT_PB_NAMES = {"X": "world_x", "Y": "world_y", "Z": "world_z"}


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
        """Raises ValueError for a value that is not a finite number."""
        reading = cls(t_ns_of(pb.timestamp), pb.pan, pb.tilt, pb.zoom, pb.focus)
        for name in ("pan", "tilt", "zoom", "focus"):
            if not math.isfinite(getattr(reading, name)):
                raise ValueError(f"{name} is {getattr(reading, name)}, not a finite number")
        return reading


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
        """Raises ValueError for an empty table, a non-finite value or a focal length that is not positive."""
        entries = tuple(LensEntry(e.zoom, e.focus, e.fx, e.fy, e.cx, e.cy) for e in pb.entries)
        if not entries:
            raise ValueError("the lens table has no entries")
        for k, e in enumerate(entries):
            values = (e.zoom, e.focus, e.fx, e.fy, e.cx, e.cy)
            if not all(math.isfinite(v) for v in values) or e.fx <= 0 or e.fy <= 0:
                raise ValueError(f"lens table entry {k} ({', '.join(f'{v:g}' for v in values)}) needs finite values and fx, fy > 0")
        position = (pb.camera_x, pb.camera_y, pb.camera_z)
        if not all(math.isfinite(v) for v in position):
            raise ValueError("the lens table's camera position is not finite")
        return cls(pb.width, pb.height, entries, position)


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
                setattr(pb, _GT_PB_NAMES.get(name, name), value)
        return pb

    @classmethod
    def from_pb(cls, pb) -> GroundTruthObject:
        fields = pb.DESCRIPTOR.fields_by_name
        values = {}
        for name in _OPTIONAL_GT_FIELDS:
            pb_name = _GT_PB_NAMES.get(name, name)
            pb_name = pb_name if pb_name in fields else name  # a log written before the rename
            values[name] = getattr(pb, pb_name) if pb.HasField(pb_name) else None
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
        """Raises ValueError for a box that is not finite or not of positive size."""
        region = cls(pb.frame, pb.t_ns, pb.x, pb.y, pb.w, pb.h, pb.label)
        if not all(math.isfinite(v) for v in (region.x, region.y, region.w, region.h)) or region.w <= 0 or region.h <= 0:
            raise ValueError(f"the box on frame {region.frame} (centre {region.x:g},{region.y:g}, size {region.w:g}x{region.h:g}) "
                             "is not a finite box of positive size")
        return region


def init_annotations_pb(regions: tuple[InitRegion, ...] | list[InitRegion], t_ns: int) -> m.InitAnnotations:
    return m.InitAnnotations(timestamp=timestamp(t_ns), regions=[r.to_pb() for r in regions])
