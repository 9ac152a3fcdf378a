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
"""

from __future__ import annotations

import dataclasses
import math
import re
from dataclasses import dataclass
from pathlib import Path

from trackreplay.recorder.sources.base import read_text, require_file
from trackreplay.schemas.errors import SourceError
from trackreplay.schemas.records import GroundTruthObject

FORMATS = ("auto", "mot", "otb")
OTB_ID = 1


@dataclass(frozen=True)
class GroundTruthTable:
    """Objects per 0-based frame. ``dense``: frames without rows still get an (empty) message."""

    path: str
    format: str
    frames: dict[int, tuple[GroundTruthObject, ...]]
    dense: bool

    @property
    def last_frame(self) -> int:
        return max(self.frames, default=-1)

    def objects_at(self, frame: int) -> tuple[GroundTruthObject, ...] | None:
        found = self.frames.get(frame)
        if found is None and self.dense:
            return ()
        return found


def _split(text: str) -> list[str]:
    return [c for c in re.split(r"[,\t ]+", text.strip()) if c]


def _float(text: str, name: str, where: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise SourceError(f"{where}: {name} {text!r} is not a number") from None


def detect_format(path: Path) -> str:
    if path.name.lower().startswith("groundtruth_rect"):
        return "otb"
    for lineno, line in enumerate(read_text(path).splitlines(), 1):  # (\n, \r\n or an old Mac's \r)
        if line.strip():
            n = len(_split(line))
            if n >= 6:
                return "mot"
            if n == 4:
                return "otb"
            raise SourceError(f"{path}:{lineno}: cannot tell the annotation format from {n} columns; pass --gt-format mot|otb")
    raise SourceError(f"annotation file {path} is empty")


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


def read_groundtruth(path: str | Path, fmt: str = "auto", first_frame: int = 0) -> GroundTruthTable:
    """Load a whole annotation file (they are small) so errors surface before recording.

    ``first_frame``: the recorded frame (0-based) the file's first frame describes (OTB's David: its
    truth starts at image 300 of the folder, so 299); every frame is moved by it."""
    if fmt not in FORMATS:
        raise SourceError(f"ground-truth format must be one of {', '.join(FORMATS)}, not {fmt!r}")
    if isinstance(first_frame, bool) or not isinstance(first_frame, int) or first_frame < 0:
        raise SourceError(f"the ground truth's first frame must be a frame number >= 0, not {first_frame!r}")
    path = require_file(path, "annotation file")
    if fmt == "auto":
        fmt = detect_format(path)
    table = read_mot(path) if fmt == "mot" else read_otb(path)
    if first_frame:
        table = dataclasses.replace(table, frames={f + first_frame: o for f, o in table.frames.items()})
    return table
