"""What every source yields, and the small helpers they share."""

from __future__ import annotations

import csv
import json
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from trackreplay.schemas.errors import SourceError

# Log times are MCAP uint64 nanoseconds, but numpy, Polars and Rerun hold them as int64.
MAX_T_NS = 2**63 - 1

JPEG_MAGIC = b"\xff\xd8\xff"
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@dataclass(frozen=True)
class ImageFrame:
    """One image from a source.

    ``pixels`` is the decoded uint8 image (BGR or grey). ``data``/``fmt`` hold the file's own
    JPEG or PNG bytes when they are to be logged unchanged; otherwise both are None.
    """

    index: int
    t_ns: int
    where: str  # names the file or the video frame in error messages
    pixels: np.ndarray
    data: bytes | None = None
    fmt: str | None = None

    @property
    def size(self) -> tuple[int, int]:
        """(width, height)."""
        return int(self.pixels.shape[1]), int(self.pixels.shape[0])


MAX_T0_NS = 2**62
MAX_FPS = 1e6


def check_fps(fps: float) -> None:
    """A frame rate we can time frames by: positive, finite, frames at least 1 us apart."""
    if not 0 < fps <= MAX_FPS:  # (nan fails both)
        raise SourceError(f"--fps must be positive and finite, at most {MAX_FPS:g} frames a second, not {fps}")


@dataclass(frozen=True)
class FrameClock:
    """Capture time of frame ``i``: ``timestamps[i]`` when given, else ``t0_ns + i / fps``."""

    fps: float | None = None
    t0_ns: int = 0
    timestamps: Sequence[int] | None = None
    timestamps_path: str = ""

    def __post_init__(self) -> None:
        if self.timestamps is None and (self.fps is None or not self.fps > 0):
            raise SourceError("frame times need a positive --fps or a --timestamps file")
        if self.t0_ns < 0:
            raise SourceError(f"the first frame time must not be negative, not {self.t0_ns} ns")
        if self.t0_ns > MAX_T0_NS:  # log times are signed 64-bit ns; this leaves ~146 years of frames after it
            raise SourceError(f"the first frame time must be at most 2^62 ns ({MAX_T0_NS}), not {self.t0_ns} ns")
        if self.fps is not None:
            check_fps(self.fps)

    def t_ns(self, index: int) -> int:
        if self.timestamps is not None:
            if index >= len(self.timestamps):
                raise SourceError(
                    f"{self.timestamps_path} has {len(self.timestamps)} timestamps but the source has more frames"
                )
            return int(self.timestamps[index])
        return self.t0_ns + round(index * 1_000_000_000 / self.fps)


def natural_key(path: Path) -> tuple:
    """Sort key putting ``frame2`` before ``frame10`` (case-insensitive)."""
    return tuple(int(part) if part.isdigit() else part for part in re.split(r"(\d+)", path.name.lower()))


def require_file(path: str | Path, what: str) -> Path:
    path = Path(path)
    if not path.is_file():
        raise SourceError(f"{what} {path} does not exist or is not a file")
    return path


def encoded_format(data: bytes) -> str | None:
    """``"jpeg"``/``"png"`` judged by the bytes themselves, else None."""
    if data.startswith(JPEG_MAGIC):
        return "jpeg"
    if data.startswith(PNG_MAGIC):
        return "png"
    return None


def read_text(path: Path) -> str:
    """A text input's content as UTF-8 (a BOM allowed); a byte that is not UTF-8 is one sentence naming the line."""
    data = path.read_bytes()
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as err:
        line = data.count(b"\n", 0, err.start) + 1
        raise SourceError(f"{path}:{line}: byte 0x{data[err.start]:02x} is not UTF-8 text; save the file as UTF-8") from None


def parse_t_ns(text: str, where: str, name: str = "t_ns") -> int:
    """A log time in ns: an integer in [0, 2**63)."""
    try:
        t = int(text)
    except ValueError:
        raise SourceError(f"{where}: {name} {text.strip()!r} is not an integer") from None
    if t < 0:
        raise SourceError(f"{where}: {name} {t} is negative (log times are unsigned)")
    if t > MAX_T_NS:
        raise SourceError(f"{where}: {name} {t} is beyond 2**63 - 1 ns (year 2262)")
    return t


def read_timestamps(path: str | Path) -> list[int]:
    """A timestamps file: one integer ``t_ns`` per line, strictly increasing.

    Blank lines and lines starting with ``#`` are ignored. Line ``k`` (counting only data
    lines) is the time of frame ``k`` in source order.
    """
    path = require_file(path, "timestamps file")
    out: list[int] = []
    for lineno, line in enumerate(read_text(path).split("\n"), 1):
        text = line.strip()
        if not text or text.startswith("#"):
            continue
        t = parse_t_ns(text, f"{path}:{lineno}")
        if out and t <= out[-1]:
            raise SourceError(f"{path}:{lineno}: t_ns {t} is not after the previous line's {out[-1]}")
        out.append(t)
    if not out:
        raise SourceError(f"timestamps file {path} holds no timestamps")
    return out


class CsvRows:
    """``csv.reader`` over ``lines`` whose own errors (a field over its 128 KB limit, a NUL byte) are one
    ``SourceError`` sentence naming the file and line; ``line_num`` as the reader's."""

    def __init__(self, lines, path: Path, lines_before: int = 0) -> None:
        self._rows = csv.reader(lines)
        self.path = path
        self._before = lines_before  # lines of the file before ``lines`` (one line parsed on its own)

    def __iter__(self) -> CsvRows:
        return self

    def __next__(self) -> list[str]:
        try:
            return next(self._rows)
        except csv.Error as err:
            raise SourceError(f"{self.path}:{self._before + self._rows.line_num}: not valid CSV ({err})") from None

    @property
    def line_num(self) -> int:
        return self._rows.line_num


MAX_JSON_DEPTH = 64  # arrays and objects inside one another; a calibration goes three deep
MAX_JSON_DIGITS = 40  # an integer longer than this is no calibration value (Python refuses over 4300)
_JSON_TOKENS = re.compile(r'"(?:[^"\\\n]|\\.)*"|[\[\]{}\n]')


def _line_at(text: str, offset: int) -> int:
    return text.count("\n", 0, max(offset, 0)) + 1


def _too_deep(text: str) -> int | None:
    """The line where arrays and objects first nest deeper than ``MAX_JSON_DEPTH`` (strings skipped), else None."""
    depth = 0
    for token in _JSON_TOKENS.finditer(text):
        ch = token.group()
        if ch in "[{":
            depth += 1
            if depth > MAX_JSON_DEPTH:
                return _line_at(text, token.start())
        elif ch in "]}":
            depth -= 1
    return None


def read_json(path: Path) -> Any:
    """A JSON input's value; malformed JSON, nesting deeper than ``MAX_JSON_DEPTH`` or an integer of more
    than ``MAX_JSON_DIGITS`` digits is one ``SourceError`` sentence naming the file and line (checked
    before parsing: the parser's own recursion and digit limits are internal errors)."""
    text = read_text(path)
    line = _too_deep(text)
    if line is not None:
        raise SourceError(f"{path}:{line}: nested more than {MAX_JSON_DEPTH} deep")

    def integer(digits: str) -> int:
        if len(digits.lstrip("-")) > MAX_JSON_DIGITS:
            raise SourceError(f"{path}:{_line_at(text, text.find(digits))}: a number of {len(digits)} digits; "
                              f"at most {MAX_JSON_DIGITS} are read")
        return int(digits)

    try:
        return json.loads(text, parse_int=integer)
    except json.JSONDecodeError as err:
        raise SourceError(f"{path}:{err.lineno}: not valid JSON ({err.msg})") from None
