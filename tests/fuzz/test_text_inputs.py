"""Every text input parser, fed arbitrary text and bytes: it parses, or it raises one SourceError
sentence naming the file (and the line where there is one) — never another exception.

Fixed seed and a small budget (``derandomize``): the same cases on every run, a few seconds in all.
"""

from __future__ import annotations

import re
import tempfile
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from trackreplay.recorder.annotate import read_marks_csv
from trackreplay.recorder.sources.base import read_timestamps
from trackreplay.recorder.sources.encoders import read_encoders, read_lens_table
from trackreplay.recorder.sources.ground_plane import read_ground_plane
from trackreplay.recorder.sources.groundtruth import read_groundtruth
from trackreplay.recorder.sources.stereo import load_calibration
from trackreplay.replay.core.config import config_from_toml
from trackreplay.schemas.errors import SourceError, TrackreplayError
from trackreplay.trackers.golf.config import GolfConfig

FUZZ = settings(max_examples=120, derandomize=True, deadline=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])

# Text that looks like the inputs (numbers, separators, headers, comments) with arbitrary bytes mixed in.
TOKENS = st.sampled_from([
    "0", "1", "-1", "3.5", "1e308", "1e999", "nan", "inf", "-inf", "18446744073709551616", "9" * 30, "",
    "t_ns", "pan", "tilt", "zoom", "focus", "fx", "fy", "cx", "cy", "frame", "x", "y", "w", "h",
    "# width: 640", "# height: 0", "# camera_position: 1, 2", ",", ",,", " ", "\t", "\n", "\r\n", "{", "}", "[", "]",
    '"', ":", "\"width\": 640", "\"image_to_ground\"", "\"points\": [[0,0,0,0]]", "%YAML:1.0", "K:", "é", "\x00",
    # issue 33: a field over csv's 128 KB limit, nesting past the parsers' recursion, a 5000-digit number
    "y" * 140_000, "[" * 70, "{\"a\":" * 70, "9" * 5000, "1e-300",
])
CSV_TEXT = st.lists(TOKENS, max_size=60).map("".join)
RAW = st.one_of(CSV_TEXT.map(lambda t: t.encode("utf-8")), st.binary(max_size=300),
                CSV_TEXT.map(lambda t: t.encode("utf-8") + b"\xe9\xff" + t.encode("utf-8")))


def _written(data: bytes, name: str) -> Path:
    folder = Path(tempfile.mkdtemp(prefix="fuzz-"))
    path = folder / name
    path.write_bytes(data)
    return path


def _consume(result):
    """Generators (encoder rows) fail only when iterated."""
    return list(result) if hasattr(result, "__next__") else result


def _parses_or_says_where(parse, data: bytes, name: str) -> None:
    path = _written(data, name)
    try:
        _consume(parse(path))
    except SourceError as err:
        message = str(err)
        assert "\n" not in message.strip(), message
        assert str(path) in message or path.name in message, message
        if re.match(rf"{re.escape(str(path))}:\d+:", message):
            line = int(message[len(str(path)) + 1:].split(":", 1)[0])
            assert 1 <= line <= data.count(b"\n") + 1, message


@FUZZ
@given(RAW)
def test_encoder_csv(data: bytes) -> None:
    _parses_or_says_where(read_encoders, b"t_ns,pan,tilt,zoom,focus\n" + data, "enc.csv")


@FUZZ
@given(RAW)
def test_lens_table(data: bytes) -> None:
    _parses_or_says_where(read_lens_table, data, "lens.csv")


@FUZZ
@given(RAW)
def test_timestamps(data: bytes) -> None:
    _parses_or_says_where(read_timestamps, data, "ts.txt")


@FUZZ
@given(RAW, st.sampled_from(["gt.txt", "groundtruth_rect.txt"]))
def test_ground_truth(data: bytes, name: str) -> None:
    _parses_or_says_where(read_groundtruth, data, name)


@FUZZ
@given(RAW, st.sampled_from(["calib.json", "calib.yaml"]))
def test_calibration(data: bytes, name: str) -> None:
    _parses_or_says_where(lambda p: load_calibration(p, stereo=True), data, name)


@FUZZ
@given(RAW)
def test_ground_plane(data: bytes) -> None:
    _parses_or_says_where(read_ground_plane, data, "plane.json")


@FUZZ
@given(RAW)
def test_marks_csv(data: bytes) -> None:
    _parses_or_says_where(lambda p: read_marks_csv(p, "target"), data, "marks.csv")


TOML_TOKENS = st.sampled_from([
    "[golf]", "[golf.contrast]", "[golf.particles]", "registration_px", "n", "seed", " = ", "=", "\n", "1", "2.5",
    "1e308", "1e-300", "-1e308", "nan", "inf", "9" * 5000, "true", '"x"', "[", "]", "[" * 40, "]" * 40, "{", "}",
    "a = ", ",", "#", "x" * 70_000, "\x00", "é",
])
TOML_RAW = st.one_of(st.lists(TOML_TOKENS, max_size=40).map(lambda t: "".join(t).encode("utf-8")), st.binary(max_size=200))


@FUZZ
@given(TOML_RAW)
def test_toml_config(data: bytes) -> None:
    """A tracker config file: it loads, or one TrackreplayError sentence names the file (issue 33: 1e308,
    nesting 500 deep and a huge line ended in internal errors or gigabytes)."""
    path = _written(data, "golf.toml")
    try:
        config_from_toml(GolfConfig, path, "golf")
    except TrackreplayError as err:
        message = str(err)
        assert "\n" not in message.strip() and str(path) in message, message


def test_a_latin1_byte_names_its_line(tmp_path: Path) -> None:
    path = tmp_path / "enc.csv"
    path.write_bytes(b"t_ns,pan,tilt,zoom,focus\n0,1,2,3,4\n1,caf\xe9,2,3,4\n")
    try:
        list(read_encoders(path))
    except SourceError as err:
        assert str(err) == f"{path}:3: byte 0xe9 is not UTF-8 text; save the file as UTF-8"
    else:
        raise AssertionError("a latin-1 byte was accepted")


def test_a_log_time_beyond_int64_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "enc.csv"
    path.write_text("t_ns,pan,tilt,zoom,focus\n18446744073709551615,1,2,3,4\n")
    try:
        list(read_encoders(path))
    except SourceError as err:
        assert str(err).startswith(f"{path}:2: t_ns 18446744073709551615 is beyond 2**63 - 1 ns")
    else:
        raise AssertionError("a log time near 2**64 was accepted")
