"""Issue 33, defect 4: input files that ended in an internal error (exit 70) are one sentence naming
the file and line: a CSV field over 128 KB, JSON nested 200k deep or with a 5000-digit number."""

from pathlib import Path

import pytest

from trackreplay.recorder.annotate import read_marks_csv
from trackreplay.recorder.sources.encoders import read_encoders, read_lens_table
from trackreplay.recorder.sources.ground_plane import read_ground_plane
from trackreplay.recorder.sources.groundtruth import read_groundtruth
from trackreplay.recorder.sources.stereo import load_calibration
from trackreplay.schemas.errors import SourceError

HUGE = "9" * 200_000


@pytest.mark.parametrize("name, text, line, parse", [
    ("enc.csv", f"t_ns,pan,tilt,zoom,focus\n0,1,2,3,4\n1,{HUGE},0,1,1\n", 3, lambda p: list(read_encoders(p))),
    ("lens.csv", f"zoom,focus,fx,fy,cx,cy\n1,1,\"{HUGE}\",50,32,24\n", 2, read_lens_table),
    ("marks.csv", f"frame,x,y,w,h,label\n0,1,1,4,4,{HUGE}\n", 2, lambda p: read_marks_csv(p, "ball")),
    ("gt.csv", f"frame,x,y,visibility\n0,1,1,1\n1,1,1,{HUGE}\n", 3, lambda p: read_groundtruth(p, "points", 0)),
], ids=["encoders", "lens", "marks", "groundtruth"])
def test_a_csv_field_over_128kb_names_file_and_line(tmp_path: Path, name: str, text: str, line: int, parse) -> None:
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(SourceError, match=rf"^{path}:{line}: not valid CSV \(field larger than field limit"):
        parse(path)


@pytest.mark.parametrize("parse", [lambda p: load_calibration(p), read_ground_plane], ids=["calibration", "ground_plane"])
def test_json_nested_200k_deep_names_file_and_line(tmp_path: Path, parse) -> None:
    path = tmp_path / "c.json"
    path.write_text('{"width": 64,\n"K": ' + "[" * 200_000 + "]" * 200_000 + "}")
    with pytest.raises(SourceError, match=rf"^{path}:2: nested more than 64 deep$"):
        parse(path)


@pytest.mark.parametrize("parse", [lambda p: load_calibration(p), read_ground_plane], ids=["calibration", "ground_plane"])
def test_a_5000_digit_json_number_names_file_and_line(tmp_path: Path, parse) -> None:
    path = tmp_path / "c.json"
    path.write_text('{"width": 64,\n "height": 48,\n "K": [' + "9" * 5000 + ", 0, 32, 0, 50, 24, 0, 0, 1]}")
    with pytest.raises(SourceError, match=rf"^{path}:3: a number of 5000 digits; at most 40 are read$"):
        parse(path)
