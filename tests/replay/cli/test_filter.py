"""`trackreplay filter`: the cut log replays to the same per-frame states over the kept range."""

from __future__ import annotations

from pathlib import Path

import polars as pl
import pytest

from trackreplay.replay.cli.main import main
from trackreplay.replay.core.engine import ReplayRequest, replay
from trackreplay.replay.log.reader import LogReader

GOLDEN = Path(__file__).resolve().parents[2] / "golden"
STATE = ["t_ns", "x", "y", "w", "h", "vx", "vy", "status", "X", "Y", "Z", "dx", "dy", "dz"]


def _states(table: pl.DataFrame) -> pl.DataFrame:
    return table.select([c for c in STATE if c in table.columns]).sort("t_ns")


@pytest.mark.parametrize("tracker,log,start,end", [
    ("flow", "flow-sim1-24f.mcap", 0.2, 0.6),
    ("golf", "golf-teeshot-640x360.mcap", None, 1.2),   # the marks stay inside the range
])
def test_filtered_log_replays_like_the_source_range(tmp_path: Path, tracker, log, start, end) -> None:
    src, out = GOLDEN / log, tmp_path / "cut.mcap"
    args = ["filter", str(src), str(out)] + (["--start", str(start)] if start is not None else []) + ["--end", str(end)]
    assert main(args) == 0
    source = replay(ReplayRequest(log=src, tracker=tracker, start_s=start, end_s=end))
    cut = replay(ReplayRequest(log=out, tracker=tracker))
    assert cut.frames == source.frames > 0
    assert _states(cut.trajectory).equals(_states(source.trajectory))
    kept, before = LogReader(out).topics(), LogReader(src).topics()
    assert set(kept) <= set(before) and ("/ptz/lens_table" in kept) == ("/ptz/lens_table" in before)
    assert ("/annotations/init" in kept) == (start is None)  # flow's mark is on frame 0, before the range


def test_filter_topics_and_refusals(tmp_path: Path, capsys) -> None:
    src, out = GOLDEN / "golf-teeshot-640x360.mcap", tmp_path / "images.mcap"
    assert main(["filter", str(src), str(out), "--topic", "/camera/image", "--topic", "/ptz/encoders"]) == 0
    topics = LogReader(out).topics()
    assert set(topics) == {"/camera/image", "/ptz/encoders"}
    assert topics["/camera/image"].count == LogReader(src).topics()["/camera/image"].count
    assert main(["filter", str(src), str(tmp_path / "x.mcap"), "--topic", "/nope"]) == 2
    assert "has no topic /nope" in capsys.readouterr().err


def test_a_mark_written_at_the_start_and_the_ground_truth_follow_a_cut(tmp_path: Path, capsys) -> None:
    """`annotate` writes its marks at the first frame's time: a cut from --start keeps a mark whose frame
    is inside the range (renumbered), and the ground truth is renumbered alike, so `eval` compares
    each estimate with the same moment's truth."""
    src = GOLDEN / "flow-sim1-24f.mcap"
    plain, marked, cut = tmp_path / "plain.mcap", tmp_path / "marked.mcap", tmp_path / "cut.mcap"
    assert main(["filter", str(src), str(plain), "--topic", "/camera/image", "--topic", "/groundtruth/objects"]) == 0
    assert main(["annotate", str(plain), "--frame", "12", "--box", "100,100,20,20", "--out", str(marked)]) == 0
    assert main(["filter", str(marked), str(cut), "--start", "0.2"]) == 0  # frame 12 is at 0.4 s, frame 6 at 0.2 s
    from trackreplay.replay.log.frames import read_hints
    from trackreplay.replay.log.groundtruth import read_groundtruth

    (mark,) = read_hints(LogReader(cut), "/annotations/init")
    (before,) = read_hints(LogReader(marked), "/annotations/init")
    assert (mark.frame, mark.t_ns, mark.x) == (before.frame - 6, before.t_ns, before.x)
    gt_cut, gt_src = read_groundtruth(LogReader(cut)), read_groundtruth(LogReader(src))
    assert gt_cut["frame"].min() == 0
    assert gt_cut.drop("frame").equals(gt_src.filter(pl.col("frame") >= 6).drop("frame"))
    traj = tmp_path / "traj.csv"
    assert main(["replay", str(cut), "--tracker", "flow", "--quiet", "--export", str(traj)]) == 0
    capsys.readouterr()
    assert main(["eval", str(traj), str(cut)]) == 0


def test_a_cut_log_says_how_it_was_made(tmp_path: Path) -> None:
    """Every log we write carries its own provenance record (a review found filter's output with only its source's)."""
    from mcap.reader import make_reader

    out = tmp_path / "cut.mcap"
    assert main(["filter", str(GOLDEN / "flow-sim1-24f.mcap"), str(out), "--end", "0.5"]) == 0
    with open(out, "rb") as fh:
        records = [m.metadata for m in make_reader(fh).iter_metadata() if m.name == "trackreplay.provenance"]
    assert records[-1]["source.log"].startswith("flow-sim1-24f.mcap sha256:") and "end_ns" in records[-1]


def test_filter_takes_globs_regex_and_exclusions(tmp_path: Path, capsys) -> None:
    src = GOLDEN / "golf-teeshot-640x360.mcap"
    present = set(LogReader(src).topics())
    out = tmp_path / "a.mcap"
    assert main(["filter", str(src), str(out), "--topic", "ptz/*"]) == 0
    assert set(LogReader(out).topics()) == {t for t in present if t.startswith("/ptz/")} != set()
    out = tmp_path / "b.mcap"
    assert main(["filter", str(src), str(out), "--exclude", "re:/(camera|ptz)/.*"]) == 0
    assert set(LogReader(out).topics()) == {t for t in present if not t.startswith(("/camera/", "/ptz/"))}
    assert main(["filter", str(src), str(tmp_path / "c.mcap"), "--topic", "lidar/*"]) == 2
    err = capsys.readouterr().err
    assert "has no topic matching 'lidar/*'; topics present: " in err and err.count("\n") == 1
    assert not (tmp_path / "c.mcap").exists()
