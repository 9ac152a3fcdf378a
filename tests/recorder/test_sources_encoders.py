"""PTZ encoder CSV and lens table."""

from __future__ import annotations

import pytest

from trackreplay.recorder.record import record
from trackreplay.recorder.sources.encoders import read_encoders, read_lens_table
from trackreplay.schemas.errors import SourceError
from trackreplay.schemas.records import LensTable, PtzReading


def write_encoders(path, rows, header="t_ns,pan,tilt,zoom,focus"):
    path.write_text(header + "\n" + "".join(r + "\n" for r in rows))
    return path


def test_encoders_interleaved_in_time_order(tmp_path, make_images, log_messages):
    folder = make_images(tmp_path / "img", 4)
    enc = write_encoders(tmp_path / "enc.csv", [f"{t},{t / 1e8},-2.5,100,200" for t in range(50_000_000, 500_000_000, 40_000_000)])
    lens = tmp_path / "lens.csv"
    lens.write_text("# lens calibration\n# camera_position: 1.0, 2.0, 3.5\nzoom,focus,fx,fy,cx,cy\n100,200,500,505,32,24\n900,200,2000,2010,32,24\n")
    record(tmp_path / "out.mcap", images=folder, fps=10, t0_ns=100_000_000, encoders=enc, lens_table=lens, quiet=True)
    msgs = log_messages(tmp_path / "out.mcap")
    readings = [PtzReading.from_pb(m.pb) for m in msgs if m.topic == "/ptz/encoders"]
    assert [r.t_ns for r in readings] == list(range(50_000_000, 500_000_000, 40_000_000))
    assert readings[0] == PtzReading(50_000_000, 0.5, -2.5, 100.0, 200.0)
    assert [m.topic for m in msgs[:3]] == ["/ptz/encoders", "/ptz/encoders", "/ptz/lens_table"]
    assert all(m.log_time == PtzReading.from_pb(m.pb).t_ns for m in msgs if m.topic == "/ptz/encoders")
    tables = [m for m in msgs if m.topic == "/ptz/lens_table"]
    assert len(tables) == 1 and tables[0].log_time == 100_000_000
    table = LensTable.from_pb(tables[0].pb)
    assert (table.width, table.height) == (64, 48)  # from the frames: the file gives none
    assert table.camera_position == (1.0, 2.0, 3.5) and table.entries[1].fx == 2000.0


def test_lens_table_size_from_comments(tmp_path):
    lens = tmp_path / "lens.csv"
    lens.write_text("# width: 1920\n# height: 1080\n0,0,1000,1000,960,540\n")
    table = read_lens_table(lens, 64, 48)
    assert (table.width, table.height, table.camera_position) == (1920, 1080, (0.0, 0.0, 0.0))


@pytest.mark.parametrize("rows, match", [
    (["0,1,2,3,4", "10,1,x,3,4"], r"enc\.csv:3: tilt 'x' is not a number"),
    (["0,1,2,3,4", "10,1,2,3"], r"enc\.csv:3: expected 5 columns, got 4"),
    (["0,1,2,3,4", "10,1,2,3,4", "10,1,2,3,4"], r"enc\.csv:4: t_ns 10 is not after the previous reading's 10"),
    (["0.5,1,2,3,4"], r"enc\.csv:2: t_ns '0.5' is not an integer"),
    (["0,nan,2,3,4"], r"enc\.csv:2: pan 'nan' is not a finite number"),
    (["-5,1,2,3,4"], r"enc\.csv:2: t_ns -5 is negative"),
    (["0,1,2,3,4", "10,1,500,3,4"], r"enc\.csv:3: tilt 500 degrees is outside -90..90"),  # (found by a review:
    (["0,1e308,2,3,4"], r"enc\.csv:2: pan 1e\+308 degrees is beyond"),                  # lines of sight flipped)
])
def test_bad_encoder_row_names_file_and_line(tmp_path, make_images, rows, match):
    enc = write_encoders(tmp_path / "enc.csv", rows)
    folder = make_images(tmp_path / "img", 2)
    with pytest.raises(SourceError, match=match):
        record(tmp_path / "out.mcap", images=folder, fps=10, encoders=enc, quiet=True)
    assert not (tmp_path / "out.mcap").exists()


def test_bad_encoder_header_and_missing_file(tmp_path):
    with pytest.raises(SourceError, match=r"enc\.csv:1: header must be t_ns,pan,tilt,zoom,focus"):
        list(read_encoders(write_encoders(tmp_path / "enc.csv", ["0,1,2,3"], header="t,pan,tilt,zoom")))
    with pytest.raises(SourceError, match=r"encoder file .*nope\.csv does not exist"):
        list(read_encoders(tmp_path / "nope.csv"))


def test_encoder_columns_in_any_order(tmp_path):
    enc = write_encoders(tmp_path / "enc.csv", ["1,2,3,4,7"], header="zoom,focus,pan,tilt,t_ns")
    assert list(read_encoders(enc)) == [PtzReading(7, 3.0, 4.0, 1.0, 2.0)]


@pytest.mark.parametrize("text, match", [
    ("1,2,3\n", r"lens\.csv:1: expected 6 columns"),
    ("# width: big\n0,0,1,1,0,0\n", r"lens\.csv:1: width 'big' is not a number"),
    ("# camera_position: 1, 2\n0,0,1,1,0,0\n", r"lens\.csv:1: camera_position needs three numbers"),
    ("0,0,0,1,0,0\n", r"lens\.csv:1: fx and fy must be positive"),
    ("# only comments\n", r"has no zoom,focus,fx,fy,cx,cy rows"),
    ("# width: 5000000000\n0,0,1,1,0,0\n", r"lens\.csv:1: width must be a positive integer up to"),
    ("0,0,1e308,1e308,0,0\n", r"lens\.csv:1: a value beyond"),
    ("# camera_position: 1e308,1,1\n0,0,1,1,0,0\n", r"lens\.csv:1: camera_position beyond"),
    ("0,0,1,1,0,0\n0,0,2,2,0,0\n", r"lens\.csv:2: zoom 0, focus 0 already has a row \(line 1\)"),
    ("# width: 64\n# width: 32\n0,0,1,1,0,0\n", r"lens\.csv:2: width is given twice"),
])
def test_bad_lens_table(tmp_path, text, match):
    lens = tmp_path / "lens.csv"
    lens.write_text(text)
    with pytest.raises(SourceError, match=match):
        read_lens_table(lens)


def test_a_lens_table_for_other_images_is_refused_when_recording(tmp_path, make_images):
    """A review recorded a 640x480 lens table with 320x240 frames (exit 0): the log could then not be replayed."""
    lens = tmp_path / "lens.csv"
    lens.write_text("# width: 640\n# height: 480\n0,0,500,500,320,240\n")
    enc = write_encoders(tmp_path / "enc.csv", ["0,1,2,3,4"])
    folder = make_images(tmp_path / "img", 2)
    with pytest.raises(SourceError, match=r"lens table .*lens\.csv is for 640x480 images but .* is 64x48"):
        record(tmp_path / "out.mcap", images=folder, fps=10, encoders=enc, lens_table=lens, quiet=True)
    assert not (tmp_path / "out.mcap").exists()
