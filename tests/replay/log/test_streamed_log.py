"""Issue 33, defect 2: a valid MCAP without a summary section (a streamed recording, ``summary_start``
0) is read by a linear scan, and ``recover`` calls it complete."""

from pathlib import Path

import pytest
from mcap.reader import make_reader
from mcap.writer import IndexType, Writer

from trackreplay.recorder.log_summary import read_summary, topic_counts
from trackreplay.recorder.recover import recover
from trackreplay.replay.core.engine import ReplayRequest, replay
from trackreplay.replay.log.info import log_info
from trackreplay.replay.log.reader import LogReader
from trackreplay.schemas.errors import TruncatedLogError

GOLDEN = Path(__file__).resolve().parents[2] / "golden" / "flow-sim1-24f.mcap"


def streamed_copy(src: Path, dst: Path, *, chunked: bool = True) -> Path:
    """``src`` rewritten as a streaming writer leaves it: no summary section, no indexes."""
    with open(src, "rb") as fh, open(dst, "wb") as out:
        reader = make_reader(fh)
        writer = Writer(out, index_types=IndexType.NONE, repeat_channels=False, repeat_schemas=False,
                        use_chunking=chunked, use_statistics=False, use_summary_offsets=False)
        writer.start(profile=reader.get_header().profile, library="streamed")
        schemas: dict[int, int] = {}
        channels: dict[int, int] = {}
        for schema, channel, msg in reader.iter_messages(log_time_order=False):
            if schema.id not in schemas:
                schemas[schema.id] = writer.register_schema(schema.name, schema.encoding, schema.data)
            if channel.id not in channels:
                channels[channel.id] = writer.register_channel(channel.topic, channel.message_encoding, schemas[schema.id])
            writer.add_message(channels[channel.id], msg.log_time, msg.data, msg.publish_time, msg.sequence)
        writer.finish()
    with open(dst, "rb") as fh:
        assert make_reader(fh).get_summary() is None  # really summary-less
    return dst


@pytest.mark.parametrize("chunked", [True, False], ids=["chunked", "unchunked"])
def test_a_streamed_log_reads_like_its_indexed_original(tmp_path: Path, chunked: bool) -> None:
    log = streamed_copy(GOLDEN, tmp_path / "streamed.mcap", chunked=chunked)
    original, streamed = LogReader(GOLDEN), LogReader(log)
    assert streamed.topics() == original.topics() and streamed.time_range() == original.time_range()
    topics = list(original.topics())
    assert [(m.topic, m.log_time, m.index, m.data) for m in streamed.messages(topics)] == \
           [(m.topic, m.log_time, m.index, m.data) for m in original.messages(topics)]
    assert topic_counts(read_summary(log)) == topic_counts(read_summary(GOLDEN))
    info = log_info(log)
    assert not info["truncated"] and info["messages"] == sum(t.count for t in original.topics().values())
    report = recover(log, tmp_path / "fixed.mcap")
    assert report.complete and report.exit_code == 0


def test_a_streamed_log_replays_to_the_same_digest(tmp_path: Path) -> None:
    log = streamed_copy(GOLDEN, tmp_path / "streamed.mcap")
    assert replay(ReplayRequest(log=log, tracker="flow")).digest == replay(ReplayRequest(log=GOLDEN, tracker="flow")).digest


def test_a_streamed_log_cut_before_its_footer_is_still_truncated(tmp_path: Path) -> None:
    log = streamed_copy(GOLDEN, tmp_path / "streamed.mcap")
    data = log.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[:len(data) // 2] + data[-8:])  # closing magic, but no footer before it
    with pytest.raises(TruncatedLogError, match="recover"):
        LogReader(cut)


def test_an_indexed_log_whose_summary_start_is_zeroed_is_damaged_not_streamed(tmp_path: Path) -> None:
    data = bytearray(GOLDEN.read_bytes())
    footer = len(data) - 8 - 29
    data[footer + 9:footer + 17] = bytes(8)  # summary_start = 0, the CRC left as it was
    bad = tmp_path / "zeroed.mcap"
    bad.write_bytes(bytes(data))
    with pytest.raises(TruncatedLogError):
        LogReader(bad)
    info = log_info(bad, partial_ok=True)
    assert not info["complete"] and info["damaged"][0]["reason"] == "the summary section fails its CRC"
