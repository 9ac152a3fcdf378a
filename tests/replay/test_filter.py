"""`trackreplay filter`: the cut log replays to the same per-frame states over the kept range."""

from __future__ import annotations

from pathlib import Path

import polars as pl
import pytest

from trackreplay.replay.cli import main
from trackreplay.replay.engine import ReplayRequest, replay
from trackreplay.replay.reader import LogReader

GOLDEN = Path(__file__).resolve().parents[1] / "golden"
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
