"""The one checked MCAP record reader (recorder.mcap_scan.read_record), which both the scan and the
replay's indexed chunk reader (replay.log.chunks) read with."""

from __future__ import annotations

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap.records import MessageIndex

from trackreplay.recorder.image_codec import image_message
from trackreplay.recorder.mcap_scan import ChunkRecords, RecordDamage, chunk_messages, read_record
from trackreplay.recorder.writer import LogWriter
from trackreplay.replay.log.chunks import _lost_times, iter_checked


@pytest.fixture
def log(tmp_path):
    """20 images in chunks of 5 (messages every 10 ms)."""
    path = tmp_path / "log.mcap"
    rng = np.random.default_rng(0)
    with LogWriter(path, flush_every=5) as writer:
        for i in range(20):
            t = i * 10_000_000
            writer.write("/camera/image", image_message(rng.integers(0, 255, (12, 16, 3), dtype=np.uint8), "png", t), t)
    with open(path, "rb") as fh:
        summary = make_reader(fh).get_summary()
    return path, summary


def test_a_chunk_and_its_message_index_read_back(log) -> None:
    path, summary = log
    data = path.read_bytes()
    index = summary.chunk_indexes[1]
    start, end = index.chunk_start_offset, index.chunk_start_offset + index.chunk_length
    size, chunk = read_record(data, start)
    assert size == index.chunk_length and isinstance(chunk, ChunkRecords) and chunk.offset == start
    assert [m.log_time for m in chunk_messages(data[start:end])] == [t * 10_000_000 for t in range(5, 10)]
    (channel_id, at), = index.message_index_offsets.items()
    assert read_record(data, at)[1] is None  # the scan passes over indexes
    entry = read_record(data, at, message_index=True)[1]
    assert isinstance(entry, MessageIndex) and entry.channel_id == channel_id
    with open(path, "rb") as fh:
        assert _lost_times(fh, index, channel_id) == tuple(t * 10_000_000 for t in range(5, 10))


def test_a_flipped_byte_is_damage_for_both_readers(log, tmp_path) -> None:
    path, summary = log
    index = summary.chunk_indexes[2]
    data = bytearray(path.read_bytes())
    data[index.chunk_start_offset + index.chunk_length - 20] ^= 0xFF  # inside the chunk's records
    with pytest.raises(RecordDamage):
        chunk_messages(bytes(data[index.chunk_start_offset:index.chunk_start_offset + index.chunk_length]))
    with pytest.raises(RecordDamage):
        chunk_messages(bytes(data[:len(data) // 2]))  # not one chunk
    damaged = tmp_path / "damaged.mcap"
    damaged.write_bytes(bytes(data))
    with open(damaged, "rb") as fh:
        items = list(iter_checked(fh, summary, [next(iter(summary.channels))]))
    lost = [item for item in items if not hasattr(item, "log_time")]
    assert len(items) == 16 and len(lost) == 1 and lost[0].log_times == tuple(t * 10_000_000 for t in range(10, 15))
