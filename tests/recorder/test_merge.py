"""`trackreplay merge`: side inputs added to an existing log as a new log; the input never written."""

from pathlib import Path

import polars as pl
import pytest

from trackreplay.replay.cli.main import main
from trackreplay.replay.log.groundtruth import read_groundtruth
from trackreplay.replay.log.info import log_info
from trackreplay.replay.log.reader import LogReader

GOLDEN = Path(__file__).resolve().parents[1] / "golden"


@pytest.fixture(scope="module")
def plain(tmp_path_factory) -> Path:
    """The golden flow log without its ground truth."""
    out = tmp_path_factory.mktemp("merge") / "plain.mcap"
    assert main(["filter", str(GOLDEN / "flow-sim1-24f.mcap"), str(out), "--exclude", "/groundtruth/*"]) == 0
    return out


def test_truth_and_encoders_are_added_and_everything_else_kept(plain: Path, tmp_path: Path, capsys) -> None:
    truth = read_groundtruth(LogReader(GOLDEN / "flow-sim1-24f.mcap"))
    mot = tmp_path / "gt.txt"  # MOTChallenge: 1-based frames and pixels
    mot.write_text("".join(f"{r['frame'] + 1},{r['id']},{r['x'] - r['w'] / 2 + 1},{r['y'] - r['h'] / 2 + 1},{r['w']},{r['h']},1\n"
                           for r in truth.iter_rows(named=True)))
    enc = tmp_path / "ptz.csv"
    enc.write_text("t_ns,pan,tilt,zoom,focus\n" + "".join(f"{i * 10_000_000},0.1,0.2,1.0,0\n" for i in range(90)))
    before = plain.read_bytes()
    out = tmp_path / "merged.mcap"
    assert main(["merge", str(plain), "--groundtruth", str(mot), "--encoders", str(enc), "-o", str(out)]) == 0
    assert capsys.readouterr().out.startswith(f"wrote {out}: ")
    assert plain.read_bytes() == before  # the input untouched
    info = log_info(out)
    assert info["complete"]
    counts = {t["topic"]: t["count"] for t in info["topics"]}
    source = {t["topic"]: t["count"] for t in log_info(plain)["topics"]}
    assert counts == {**source, "/groundtruth/objects": truth["frame"].n_unique(), "/ptz/encoders": 90}
    merged = read_groundtruth(LogReader(out))
    cols = ["frame", "t_ns", "id", "x", "y", "w", "h"]
    assert merged.select(cols).equals(truth.select(cols))  # at their images' times, as record places them
    with pytest.raises(AssertionError):  # (the test can fail: a shifted truth differs)
        assert merged.select(cols).equals(truth.select(cols).with_columns(pl.col("x") + 1))


@pytest.mark.parametrize("extra, code, message", [
    (["--groundtruth", "{gt}"], 2, "already has /groundtruth/objects"),  # on the golden log, which has one
    (["--encoders", "{bad}"], 2, "bad.csv:2: pan 'x' is not a number"),
    ([], 2, "merge needs a side input to add"),
])
def test_bad_input_is_one_sentence_and_nothing_written(plain: Path, tmp_path: Path, capsys, extra, code, message) -> None:
    gt = tmp_path / "gt.txt"
    gt.write_text("1,1,10,10,5,5,1\n")
    bad = tmp_path / "bad.csv"
    bad.write_text("t_ns,pan,tilt,zoom,focus\n0,x,0,1,0\n")
    out = tmp_path / "out.mcap"
    log = GOLDEN / "flow-sim1-24f.mcap" if "{gt}" in extra else plain  # the golden log already has ground truth
    args = ["merge", str(log), "-o", str(out), *(a.format(gt=gt, bad=bad) for a in extra)]
    assert main(args) == code
    err = capsys.readouterr().err
    assert message in err and err.startswith("trackreplay: error: ") and err.count("\n") == 1
    assert not out.exists() and not list(tmp_path.glob("out.mcap*"))


def test_never_overwrites_its_input(plain: Path, capsys) -> None:
    before = plain.read_bytes()
    enc = plain.parent / "e.csv"
    enc.write_text("t_ns,pan,tilt,zoom,focus\n0,0,0,1,0\n")
    assert main(["merge", str(plain), "--encoders", str(enc), "-o", str(plain)]) == 2
    assert "never overwrites" in capsys.readouterr().err and plain.read_bytes() == before


def test_a_calibration_and_lens_table_go_at_the_first_image_and_are_checked(plain: Path, tmp_path: Path, capsys) -> None:
    from trackreplay.replay.log.frames import image_times

    reader = LogReader(plain)
    width = height = 256  # the flow scene's frames
    cal = tmp_path / "cam.json"
    cal.write_text(f'{{"width": {width}, "height": {height}, "K": [[300, 0, 128], [0, 300, 128], [0, 0, 1]]}}')
    lens = tmp_path / "lens.csv"
    lens.write_text(f"# width: {width}\n# height: {height}\nzoom,focus,fx,fy,cx,cy\n1,0,300,300,128,128\n2,0,600,600,128,128\n")
    out = tmp_path / "cal.mcap"
    assert main(["merge", str(plain), "--calibration", str(cal), "--lens-table", str(lens), "-o", str(out)]) == 0
    merged = LogReader(out)
    first = min(image_times(reader, None).values())
    for topic in ("/camera/calibration", "/ptz/lens_table"):
        (msg,) = merged.messages([topic])
        assert msg.log_time == first
    assert merged.first("/camera/calibration").width == width
    wrong = tmp_path / "wrong.json"
    wrong.write_text('{"width": 320, "height": 256, "K": [[300, 0, 128], [0, 300, 128], [0, 0, 1]]}')
    assert main(["merge", str(plain), "--calibration", str(wrong), "-o", str(tmp_path / "w.mcap")]) == 2
    assert "calibration " in capsys.readouterr().err and not (tmp_path / "w.mcap").exists()
