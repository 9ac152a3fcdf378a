"""Import annotations (MOTChallenge, OTB) as per-frame ground truth.

Frames become 0-based (file frame 1 = recorded frame 0). Boxes become centre/size in
image pixels. MOTChallenge pixels are 1-based (top-left pixel (1, 1)) and become 0-based
(``x = bb_left - 1 + w/2``), the inverse of ``replay.export.write_mot``, so an exported
trajectory imports back unchanged. OTB boxes are 1-based too (the benchmark's MATLAB toolkit: the
top-left pixel is (1, 1)) and become 0-based the same way (``x = x_otb - 1 + w/2``), so a box marked
from the first row with ``x - 1, y - 1`` (as docs/colorpf_eval.py marks otb_crossing) is its truth.

- MOTChallenge (``frame,id,bb_left,bb_top,bb_width,bb_height,conf[,x,y,z]``, comma
  separated): rows whose ``conf`` is 0 are skipped (MOT ground truth's "ignore this entry").
  With 10 columns, ``x,y,z`` other than ``-1`` become ``X,Y,Z``. Every recorded frame gets a
  ground-truth message (possibly with no objects).
- OTB (``groundtruth_rect*.txt``: ``x,y,w,h`` per line, comma/tab/space separated, line k is
  frame k): a single object, id 1. A NaN or zero-size box means the target is absent:
  ``visible=False`` and no box. Frames past the last line get no message.
- VOT (``groundtruth.txt``: ``x1,y1,...,x4,y4`` per line, line k is frame k; a 4-value line is a
  rectangle ``x,y,w,h``): a single object, id 1, whose box is the polygon's axis-aligned bounding
  box (as the VOT toolkit bounds a region), coordinates as given (no 1-based shift, unlike OTB). A line of NaN,
  of zeros or a single number (the toolkit's special codes) means the target is absent.
- Point labels (``frame,visible,x,y[,...]`` with that header, 0-based frames, pixels; ``visible`` 0:
  no ball, ``x = y = -1``): a single object, id 1, with a centre and no box (``w = h = None``).
  Frames not listed are not labelled.
- TrackNet (``Label.csv``, ``*_ball.csv``: a header naming ``Frame`` (or ``file name``: the number in
  it), ``Visibility`` (or ``Ball``), ``X``, ``Y``, other columns ignored): visibility 0 = not visible,
  1/2/3 = visible (easily, hardly, occluded). Coordinates are pixels, or normalised to [0, 1] when
  every visible one is (then :meth:`GroundTruthTable.in_pixels` scales them by the image size,
  as ``record`` does with its first frame's).
- Reference points (``frame,x,y`` with that header, 0-based frames, pixels): the object's centre on
  the frames listed, visible; frames not listed are not labelled (not "invisible").
"""

from __future__ import annotations

import dataclasses
import math
import re
from dataclasses import dataclass
from pathlib import Path

from trackreplay.recorder.sources.base import CsvRows, read_text, require_file
from trackreplay.schemas.errors import SourceError
from trackreplay.schemas.records import GroundTruthObject

FORMATS = ("auto", "mot", "otb", "vot", "points", "tracknet", "reference")
OTB_ID = 1
POINT_ID = 1  # the one object of a VOT, point, TrackNet or reference file
_FRAME_NAMES = ("frame", "file name", "filename", "file")
_VISIBILITY_NAMES = ("visibility", "visible", "ball", "vis")
_X_NAMES = ("x", "x-coordinate", "x_coordinate")
_Y_NAMES = ("y", "y-coordinate", "y_coordinate")


@dataclass(frozen=True)
class GroundTruthTable:
    """Objects per 0-based frame. ``dense``: frames without rows still get an (empty) message."""

    path: str
    format: str
    frames: dict[int, tuple[GroundTruthObject, ...]]
    dense: bool
    normalised: bool = False  # centres are fractions of the image size (a TrackNet file): see in_pixels

    @property
    def last_frame(self) -> int:
        return max(self.frames, default=-1)

    def objects_at(self, frame: int) -> tuple[GroundTruthObject, ...] | None:
        found = self.frames.get(frame)
        if found is None and self.dense:
            return ()
        return found

    def in_pixels(self, width: int, height: int) -> GroundTruthTable:
        """The table in pixels of a ``width`` x ``height`` image (itself when already in pixels)."""
        if not self.normalised:
            return self

        def scaled(o: GroundTruthObject) -> GroundTruthObject:
            return o if o.x is None else dataclasses.replace(o, x=o.x * width, y=o.y * height)

        frames = {f: tuple(scaled(o) for o in objs) for f, objs in self.frames.items()}
        return dataclasses.replace(self, frames=frames, normalised=False)


def _split(text: str) -> list[str]:
    return [c for c in re.split(r"[,\t ]+", text.strip()) if c]


def _float(text: str, name: str, where: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise SourceError(f"{where}: {name} {text!r} is not a number") from None


def _header_format(cells: list[str]) -> str | None:
    """The point format a header row names, or None."""
    names = [c.strip().lower() for c in cells]
    if names[:4] == ["frame", "visible", "x", "y"]:
        return "points"
    if names == ["frame", "x", "y"]:
        return "reference"
    if names[0] in _FRAME_NAMES and any(n in _VISIBILITY_NAMES for n in names):
        return "tracknet"
    return None


def detect_format(path: Path) -> str:
    if path.name.lower().startswith("groundtruth_rect"):
        return "otb"
    for lineno, line in enumerate(read_text(path).splitlines(), 1):  # (\n, \r\n or an old Mac's \r)
        if line.strip():
            cells = _split(line)
            if not cells:
                raise SourceError(f"{path}:{lineno}: a line of separators only ({line.strip()!r}): no annotation to read")
            if not _is_number(cells[0]):
                fmt = _header_format(line.split(",") if "," in line else cells)
                if fmt is None:
                    raise SourceError(f"{path}:{lineno}: cannot tell the annotation format from the header {line.strip()!r}; "
                                      "pass --gt-format points|tracknet|reference")
                return fmt
            n = len(cells)
            if n == 8:
                return "vot"  # (four corners; MOTChallenge rows have 6, 7, 9 or 10 columns)
            if n >= 6:
                return "mot"
            if n == 4:
                return "otb"
            raise SourceError(f"{path}:{lineno}: cannot tell the annotation format from {n} columns; "
                              f"pass --gt-format {'|'.join(FORMATS[1:])}")
    raise SourceError(f"annotation file {path} is empty")


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def read_mot(path: Path) -> GroundTruthTable:
    frames: dict[int, list[GroundTruthObject]] = {}
    seen: set[tuple[int, int]] = set()
    for lineno, line in enumerate(read_text(path).splitlines(), 1):
        where = f"{path}:{lineno}"
        if not line.strip():
            continue
        cells = [c.strip() for c in line.strip().split(",")]
        if len(cells) < 6:
            raise SourceError(f"{where}: expected frame,id,bb_left,bb_top,bb_width,bb_height[,conf,x,y,z], got {len(cells)} columns")
        v = [_float(c, n, where) for c, n in zip(cells, ("frame", "id", "bb_left", "bb_top", "bb_width", "bb_height", "conf", "x", "y", "z"))]
        frame, oid = v[0], v[1]
        if frame != int(frame) or frame < 1:
            raise SourceError(f"{where}: frame {cells[0]!r} is not a 1-based frame number")
        if oid != int(oid):
            raise SourceError(f"{where}: id {cells[1]!r} is not an integer")
        if len(v) >= 7 and v[6] == 0:
            continue
        left, top, w, h = v[2:6]
        if not all(math.isfinite(a) for a in (left, top, w, h)) or w <= 0 or h <= 0:
            raise SourceError(f"{where}: box {left},{top},{w},{h} is not a finite box of positive size")
        key = (int(frame), int(oid))
        if key in seen:
            raise SourceError(f"{where}: id {int(oid)} appears twice in frame {int(frame)}")
        seen.add(key)
        X = Y = Z = None
        if len(v) == 10 and not (v[7] == v[8] == v[9] == -1):
            X, Y, Z = v[7:10]
        obj = GroundTruthObject(
            id=int(oid), x=left - 1 + w / 2, y=top - 1 + h / 2, w=w, h=h, X=X, Y=Y, Z=Z, visible=True
        )
        frames.setdefault(int(frame) - 1, []).append(obj)
    return GroundTruthTable(str(path), "mot", {f: tuple(sorted(o, key=lambda o: o.id)) for f, o in frames.items()}, dense=True)


def read_otb(path: Path) -> GroundTruthTable:
    frames: dict[int, tuple[GroundTruthObject, ...]] = {}
    frame = 0
    for lineno, line in enumerate(read_text(path).splitlines(), 1):
        where = f"{path}:{lineno}"
        if not line.strip():
            continue
        cells = _split(line)
        if len(cells) != 4:
            raise SourceError(f"{where}: expected x,y,w,h, got {len(cells)} values")
        x, y, w, h = (_float(c, n, where) for c, n in zip(cells, "xywh"))
        if w < 0 or h < 0:  # (0 or nan: OTB's "target absent"; a negative size is no box at all)
            raise SourceError(f"{where}: width and height must not be negative, got w={w:g}, h={h:g} "
                              "(0,0,0,0 or NaN marks a frame without the target)")
        nan = [math.isnan(a) for a in (x, y, w, h)]
        if any(math.isinf(a) for a in (x, y, w, h)) or (any(nan) and not all(nan)):
            raise SourceError(f"{where}: the box {','.join(cells)} is neither a box nor OTB's mark of an absent target "
                              "(NaN,NaN,NaN,NaN or a zero width and height)")
        if all(math.isfinite(a) for a in (x, y, w, h)) and w > 0 and h > 0:
            obj = GroundTruthObject(id=OTB_ID, x=x - 1 + w / 2, y=y - 1 + h / 2, w=w, h=h, visible=True)
        else:
            obj = GroundTruthObject(id=OTB_ID, visible=False)
        frames[frame] = (obj,)
        frame += 1
    if not frames:
        raise SourceError(f"annotation file {path} is empty")
    return GroundTruthTable(str(path), "otb", frames, dense=False)


def read_vot(path: Path) -> GroundTruthTable:
    frames: dict[int, tuple[GroundTruthObject, ...]] = {}
    frame = 0
    for lineno, line in enumerate(read_text(path).splitlines(), 1):
        where = f"{path}:{lineno}"
        if not line.strip():
            continue
        v = [_float(c, "coordinate", where) for c in _split(line)]
        box = _vot_box(v, line.strip(), where)
        if box is None:
            obj = GroundTruthObject(id=POINT_ID, visible=False)
        else:
            x0, y0, x1, y1 = box
            obj = GroundTruthObject(id=POINT_ID, x=(x0 + x1) / 2, y=(y0 + y1) / 2, w=x1 - x0, h=y1 - y0, visible=True)
        frames[frame] = (obj,)
        frame += 1
    if not frames:
        raise SourceError(f"annotation file {path} is empty")
    return GroundTruthTable(str(path), "vot", frames, dense=False)


def _vot_box(v: list[float], text: str, where: str) -> tuple[float, float, float, float] | None:
    """Corners ``x0, y0, x1, y1`` of a VOT region's bounding box; None for an absent target."""
    nan = [math.isnan(a) for a in v]
    if len(v) == 1 or all(nan) or all(a == 0 for a in v):
        return None  # (a single number is one of the toolkit's codes: initialise, failure, skip)
    if any(nan) or any(math.isinf(a) for a in v):
        raise SourceError(f"{where}: the region {text} is neither a region nor VOT's mark of an absent target "
                          "(NaN in every value, zeros, or a single number)")
    if len(v) == 4:
        x, y, w, h = v
        if w < 0 or h < 0:
            raise SourceError(f"{where}: the rectangle {text} has a negative width or height")
        x0, y0, x1, y1 = x, y, x + w, y + h
    elif len(v) >= 6 and len(v) % 2 == 0:
        x0, x1, y0, y1 = min(v[0::2]), max(v[0::2]), min(v[1::2]), max(v[1::2])
    else:
        raise SourceError(f"{where}: expected a polygon x1,y1,x2,y2,x3,y3,x4,y4 (or a rectangle x,y,w,h), got {len(v)} values")
    return (x0, y0, x1, y1) if x1 > x0 and y1 > y0 else None


def _csv_table(path: Path) -> tuple[int, list[str], list[tuple[int, list[str]]]]:
    """Header line number, header cells and the data rows (line number, cells) of a CSV file."""
    rows = [(n, [c.strip() for c in row]) for n, row in enumerate(CsvRows(read_text(path).splitlines(), path), 1)
            if any(c.strip() for c in row)]
    if not rows:
        raise SourceError(f"annotation file {path} is empty")
    (header_line, header), data = rows[0], rows[1:]
    if not data:
        raise SourceError(f"annotation file {path} has a header and no rows")
    return header_line, header, data


def _column(header: list[str], names: tuple[str, ...], where: str) -> int:
    lower = [h.lower() for h in header]
    for name in names:
        if name in lower:
            return lower.index(name)
    raise SourceError(f"{where}: the header {','.join(header)} has no {names[0]} column (one of {', '.join(names)})")


def _frame_number(text: str, where: str, from_name: bool) -> int:
    """A 0-based frame number; with ``from_name``, the last number in a file name (TrackNet's ``0007.jpg``)."""
    digits = re.findall(r"\d+", text) if from_name and not text.isdigit() else [text]
    try:
        frame = int(digits[-1]) if digits else -1
    except ValueError:
        frame = -1
    if frame < 0:
        raise SourceError(f"{where}: frame {text!r} is not a 0-based frame number")
    return frame


def _point(cells: list[str], xi: int, yi: int, where: str) -> GroundTruthObject:
    x, y = _float(cells[xi], "x", where), _float(cells[yi], "y", where)
    if not (math.isfinite(x) and math.isfinite(y)):
        raise SourceError(f"{where}: the position {cells[xi]},{cells[yi]} of a visible target is not finite")
    return GroundTruthObject(id=POINT_ID, x=x, y=y, visible=True)


def read_point_labels(path: Path, fmt: str = "points") -> GroundTruthTable:
    """Point labels (``frame,visible,x,y``) or TrackNet labels (``Frame,Visibility,X,Y``): see the module."""
    header_line, header, rows = _csv_table(path)
    tracknet = fmt == "tracknet"
    where = f"{path}:{header_line}"
    fi = _column(header, _FRAME_NAMES if tracknet else ("frame",), where)
    vi = _column(header, _VISIBILITY_NAMES if tracknet else ("visible",), where)
    xi, yi = _column(header, _X_NAMES, where), _column(header, _Y_NAMES, where)
    classes = (0, 1, 2, 3) if tracknet else (0, 1)
    frames: dict[int, tuple[GroundTruthObject, ...]] = {}
    for lineno, cells in rows:
        where = f"{path}:{lineno}"
        if len(cells) <= max(fi, vi, xi, yi):
            raise SourceError(f"{where}: expected the header's {len(header)} columns ({','.join(header)}), got {len(cells)}")
        frame = _frame_number(cells[fi], where, from_name=tracknet)
        vis = _float(cells[vi], header[vi], where)
        if vis not in classes:
            hint = "" if tracknet else " (TrackNet's visibility classes 0-3: --gt-format tracknet)"
            raise SourceError(f"{where}: {header[vi]} {cells[vi]!r} is not one of {', '.join(map(str, classes))}{hint}")
        if frame in frames:
            raise SourceError(f"{where}: frame {frame} is labelled twice")
        frames[frame] = (_point(cells, xi, yi, where) if vis else GroundTruthObject(id=POINT_ID, visible=False),)
    seen = [(o.x, o.y) for objs in frames.values() for o in objs if o.x is not None]
    normalised = tracknet and bool(seen) and all(0 <= x <= 1 and 0 <= y <= 1 for x, y in seen)
    return GroundTruthTable(str(path), fmt, dict(sorted(frames.items())), dense=False, normalised=normalised)


def read_reference(path: Path) -> GroundTruthTable:
    """Reference points ``frame,x,y``: see the module."""
    header_line, header, rows = _csv_table(path)
    where = f"{path}:{header_line}"
    fi, xi, yi = _column(header, ("frame",), where), _column(header, _X_NAMES, where), _column(header, _Y_NAMES, where)
    frames: dict[int, tuple[GroundTruthObject, ...]] = {}
    for lineno, cells in rows:
        where = f"{path}:{lineno}"
        if len(cells) <= max(fi, xi, yi):
            raise SourceError(f"{where}: expected frame,x,y, got {len(cells)} columns")
        frame = _frame_number(cells[fi], where, from_name=False)
        if frame in frames:
            raise SourceError(f"{where}: frame {frame} is labelled twice")
        frames[frame] = (_point(cells, xi, yi, where),)
    return GroundTruthTable(str(path), "reference", dict(sorted(frames.items())), dense=False)


_READERS = {
    "mot": read_mot, "otb": read_otb, "vot": read_vot, "reference": read_reference,
    "points": lambda p: read_point_labels(p, "points"), "tracknet": lambda p: read_point_labels(p, "tracknet"),
}


def read_groundtruth(path: str | Path, fmt: str = "auto", first_frame: int = 0,
                     image_size: tuple[int, int] | None = None) -> GroundTruthTable:
    """Load a whole annotation file (they are small) so errors surface before recording.

    ``first_frame``: the recorded frame (0-based) the file's first frame describes (OTB's David: its
    truth starts at image 300 of the folder, so 299); every frame is moved by it. ``image_size``
    ``(width, height)``: scales normalised coordinates (TrackNet) to pixels; without it such a table
    keeps ``normalised`` set."""
    if fmt not in FORMATS:
        raise SourceError(f"ground-truth format must be one of {', '.join(FORMATS)}, not {fmt!r}")
    if isinstance(first_frame, bool) or not isinstance(first_frame, int) or first_frame < 0:
        raise SourceError(f"the ground truth's first frame must be a frame number >= 0, not {first_frame!r}")
    path = require_file(path, "annotation file")
    if fmt == "auto":
        fmt = detect_format(path)
    table = _READERS[fmt](path)
    if first_frame:
        table = dataclasses.replace(table, frames={f + first_frame: o for f, o in table.frames.items()})
    return table.in_pixels(*image_size) if image_size is not None else table
