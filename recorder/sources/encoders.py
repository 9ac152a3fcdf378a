"""PTZ encoder readings and the lens table, from CSV files.

Encoder CSV: a header ``t_ns,pan,tilt,zoom,focus`` (these names, any order), then one reading
per row; ``t_ns`` an integer strictly increasing, pan/tilt in degrees, zoom/focus raw values.

Lens table CSV: optional comment lines ``# width: 1920``, ``# height: 1080`` and
``# camera_position: X, Y, Z`` (metres, world frame), an optional header
``zoom,focus,fx,fy,cx,cy``, then one row of those six numbers per calibrated lens setting.
Without width/height lines the recorder uses the first frame's size; the position defaults
to the origin.
"""

from __future__ import annotations

import io
import math
from collections.abc import Iterator
from pathlib import Path

from trackreplay.recorder.sources.base import CsvRows, parse_t_ns, read_text, require_file
from trackreplay.schemas.errors import SourceError
from trackreplay.schemas.records import LensEntry, LensTable, PtzReading

ENCODER_COLUMNS = ("t_ns", "pan", "tilt", "zoom", "focus")
LENS_COLUMNS = ("zoom", "focus", "fx", "fy", "cx", "cy")
# Bounds far past any real camera, so that a typo is an error at its line and not a crash in a replay
MAX_PAN_DEG = 36_000.0
MAX_LENS_VALUE = 1e7
MAX_IMAGE_SIDE = 100_000
MAX_POSITION_M = 1e7


def _number(text: str, name: str, where: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise SourceError(f"{where}: {name} {text.strip()!r} is not a number") from None
    if not math.isfinite(value):
        raise SourceError(f"{where}: {name} {text.strip()!r} is not a finite number")
    return value


def read_encoders(path: str | Path) -> Iterator[PtzReading]:
    """Stream readings; any bad row raises ``SourceError('file:line: ...')``."""
    path = require_file(path, "encoder file")
    with io.StringIO(read_text(path), newline="") as fh:
        rows = CsvRows(fh, path)
        header = next(rows, None)
        names = [h.strip() for h in header] if header else []
        if sorted(names) != sorted(ENCODER_COLUMNS):
            raise SourceError(f"{path}:1: header must be {','.join(ENCODER_COLUMNS)}, not {','.join(names) or 'empty'}")
        cols = [names.index(c) for c in ENCODER_COLUMNS]
        prev: int | None = None
        for row in rows:
            where = f"{path}:{rows.line_num}"
            if not row or all(not c.strip() for c in row):
                continue
            if len(row) != len(ENCODER_COLUMNS):
                raise SourceError(f"{where}: expected {len(ENCODER_COLUMNS)} columns, got {len(row)}")
            raw = [row[c] for c in cols]
            t_ns = parse_t_ns(raw[0], where)
            if prev is not None and t_ns <= prev:
                raise SourceError(f"{where}: t_ns {t_ns} is not after the previous reading's {prev}")
            prev = t_ns
            pan, tilt, zoom, focus = (_number(v, n, where) for v, n in zip(raw[1:], ENCODER_COLUMNS[1:]))
            if not -90.0 <= tilt <= 90.0:  # past straight up or down the pan/tilt model would look backwards
                raise SourceError(f"{where}: tilt {tilt:g} degrees is outside -90..90")
            if not -MAX_PAN_DEG <= pan <= MAX_PAN_DEG:
                raise SourceError(f"{where}: pan {pan:g} degrees is beyond {MAX_PAN_DEG:g} (100 turns)")
            if zoom < 0 or abs(focus) > MAX_LENS_VALUE or zoom > MAX_LENS_VALUE:
                raise SourceError(f"{where}: zoom {zoom:g} must be >= 0 and zoom, focus within {MAX_LENS_VALUE:g}")
            yield PtzReading(t_ns, pan, tilt, zoom, focus)


def _comment(text: str, table: dict[str, str], where: str) -> None:
    body = text.lstrip("#").strip()
    if ":" not in body:
        return  # a plain comment
    key, value = (s.strip() for s in body.split(":", 1))
    if key in ("width", "height", "camera_position"):
        if key in table:
            raise SourceError(f"{where}: {key} is given twice (also at {table[key + '@']})")
        table[key] = value
        table[key + "@"] = where


def read_lens_table(path: str | Path, width: int | None = None, height: int | None = None) -> LensTable:
    """The lens table; ``width``/``height`` fill in when the file gives none (e.g. the frame size).

    Returns width/height 0 when neither the file nor the caller gives them.
    """
    path = require_file(path, "lens table")
    header: dict[str, str] = {}
    entries: list[LensEntry] = []
    seen: dict[tuple[float, float], str] = {}  # (zoom, focus) -> the line that has it
    with io.StringIO(read_text(path), newline="") as fh:
        for lineno, line in enumerate(fh, 1):
            where = f"{path}:{lineno}"
            text = line.strip()
            if not text:
                continue
            if text.startswith("#"):
                _comment(text, header, where)
                continue
            cells = [c.strip() for c in next(CsvRows([text], path, lineno - 1))]
            if cells == list(LENS_COLUMNS):
                continue
            if len(cells) != len(LENS_COLUMNS):
                raise SourceError(f"{where}: expected {len(LENS_COLUMNS)} columns {','.join(LENS_COLUMNS)}, got {len(cells)}")
            zoom, focus, fx, fy, cx, cy = (_number(v, n, where) for v, n in zip(cells, LENS_COLUMNS))
            if fx <= 0 or fy <= 0:
                raise SourceError(f"{where}: fx and fy must be positive")
            if max(fx, fy, abs(cx), abs(cy), abs(zoom), abs(focus)) > MAX_LENS_VALUE:
                raise SourceError(f"{where}: a value beyond {MAX_LENS_VALUE:g} (fx, fy, cx, cy in pixels; zoom, focus)")
            if (zoom, focus) in seen:
                raise SourceError(f"{where}: zoom {zoom:g}, focus {focus:g} already has a row (line {seen[(zoom, focus)]})")
            seen[(zoom, focus)] = where.rsplit(":", 1)[-1]
            entries.append(LensEntry(zoom, focus, fx, fy, cx, cy))
    if not entries:
        raise SourceError(f"lens table {path} has no zoom,focus,fx,fy,cx,cy rows")

    def size(key: str, fallback: int | None) -> int:
        if key not in header:
            return int(fallback or 0)
        value = _number(header[key], key, header[key + "@"])
        if value <= 0 or value != int(value) or value > MAX_IMAGE_SIDE:
            raise SourceError(f"{header[key + '@']}: {key} must be a positive integer up to {MAX_IMAGE_SIDE}")
        return int(value)

    position = (0.0, 0.0, 0.0)
    if "camera_position" in header:
        where = header["camera_position@"]
        parts = [p for p in header["camera_position"].replace(",", " ").split() if p]
        if len(parts) != 3:
            raise SourceError(f"{where}: camera_position needs three numbers X, Y, Z")
        position = tuple(_number(p, "camera_position", where) for p in parts)  # type: ignore[assignment]
        if max(abs(v) for v in position) > MAX_POSITION_M:
            raise SourceError(f"{where}: camera_position beyond {MAX_POSITION_M:g} m from the origin")
    return LensTable(size("width", width), size("height", height), tuple(entries), position)
