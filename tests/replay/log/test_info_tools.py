"""`info` as rosbag2 / mcap CLI users expect: size, compression, chunks, calendar times, aligned counts."""

from __future__ import annotations

from pathlib import Path

from trackreplay.replay.log.info import format_info, log_info

GOLDEN = Path(__file__).resolve().parents[2] / "golden"


def test_info_reports_size_chunks_compression_and_aligned_counts() -> None:
    log = GOLDEN / "golf-teeshot-640x360.mcap"
    info = log_info(log)
    assert info["file_bytes"] == log.stat().st_size and info["chunks"] >= 1 and info["compression"] == ["zstd"]
    text = format_info(info)
    assert f"{info['chunks']} chunks, compression zstd" in text
    rows = [line for line in text.splitlines() if line.startswith("    /")]
    ends = {len(line.rsplit("  ", 1)[0]) for line in rows}  # counts right-aligned in one column
    assert len(rows) == 5 and len(ends) == 1


def test_info_shows_calendar_times_for_wall_clock_logs(tmp_path: Path) -> None:
    from mcap.writer import Writer

    path = tmp_path / "wall.mcap"
    with open(path, "wb") as fh:
        w = Writer(fh)
        w.start(profile="", library="test")
        sid = w.register_schema("x", "jsonschema", b"{}")
        cid = w.register_channel("/a", "json", sid)
        t = 1_700_000_000_123_456_789
        w.add_message(cid, t, b"{}", t, 0)
        w.add_metadata("provenance", {"tool": "test"})
        w.finish()
    text = format_info(log_info(path))
    assert "(2023-11-14 22:13:20.123456 UTC)" in text
    assert "metadata provenance:" in text and "tool: test" in text
