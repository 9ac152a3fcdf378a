"""The summary of a complete MCAP written without one (a streamed recording: ``summary_start`` 0),
rebuilt by one linear scan of its records.

A writer that streams (to a pipe, or with the summary turned off) ends the file with a valid
footer pointing at no summary; mcap's seeking reader then has no schemas, channels or chunk index
to work from. The scan (:func:`~.mcap_scan.scan`, every chunk's CRC checked) gives all three, so a
reader treats such a log like any other: chunked messages are read through the rebuilt chunk index,
messages outside chunks by mcap's linear reader.
"""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

from mcap.opcode import Opcode
from mcap.reader import Summary
from mcap.records import Channel, ChunkIndex, Footer, Message, MessageIndex, Schema, Statistics

from trackreplay.recorder.mcap_scan import FOOTER_SIZE, MCAP_MAGIC, ChunkRecords, RecordDamage, open_mapped, read_record


def streamed(data: bytes) -> bool:
    """Does ``data`` end with an intact footer (closing magic) that points at no summary section?"""
    end = len(data) - len(MCAP_MAGIC)
    start = end - FOOTER_SIZE
    if start < len(MCAP_MAGIC) or bytes(data[end:]) != MCAP_MAGIC or data[start] != Opcode.FOOTER:
        return False
    summary_start, _, summary_crc = struct.unpack_from("<QQI", data, start + 9)
    # the CRC then covers the footer's own fields: a summary_start flipped to 0 is damage, not a stream
    return summary_start == 0 and (summary_crc == 0 or zlib.crc32(data[start:start + 9 + 16]) == summary_crc)


def streamed_summary(path: Path) -> Summary | None:
    """:func:`rebuild_summary` of the log at ``path`` when it is :func:`streamed`, else None (a file
    without a valid end: truncated). Raises :class:`~.mcap_scan.RecordDamage` for a damaged record."""
    data = open_mapped(path)
    try:
        return rebuild_summary(data) if streamed(data) else None
    finally:
        if hasattr(data, "close"):
            data.close()


def rebuild_summary(data: bytes) -> Summary:
    """Schemas, channels, statistics and a chunk index from every record of ``data`` (a whole MCAP
    image); raises :class:`~.mcap_scan.RecordDamage` at the first record that does not check out.
    A chunk index is built only when every message is in a chunk."""
    summary = Summary()
    counts: dict[int, int] = {}
    first, last_time = 2**64, -1
    loose = False  # a message outside any chunk
    chunk: ChunkIndex | None = None
    pos = len(MCAP_MAGIC)
    while pos < len(data):
        size, record = read_record(data, pos, message_index=True)
        if isinstance(record, Footer):
            break
        if isinstance(record, ChunkRecords):
            chunk = _chunk_index(pos, size, data, record.records)
            summary.chunk_indexes.append(chunk)
        elif isinstance(record, MessageIndex) and chunk is not None:
            chunk.message_index_offsets[record.channel_id] = pos
            chunk.message_index_length += size
        loose |= isinstance(record, Message)
        for item in record.records if isinstance(record, ChunkRecords) else (record,):
            if isinstance(item, Schema):
                summary.schemas.setdefault(item.id, item)
            elif isinstance(item, Channel):
                summary.channels.setdefault(item.id, item)
            elif isinstance(item, Message):
                counts[item.channel_id] = counts.get(item.channel_id, 0) + 1
                first, last_time = min(first, item.log_time), max(last_time, item.log_time)
        pos += size
    else:
        raise RecordDamage("the file ends before its footer")
    if loose:
        summary.chunk_indexes = []
    summary.statistics = Statistics(
        message_count=sum(counts.values()), schema_count=len(summary.schemas), channel_count=len(summary.channels),
        attachment_count=0, metadata_count=0, chunk_count=len(summary.chunk_indexes),
        message_start_time=first if counts else 0, message_end_time=last_time if counts else 0,
        channel_message_counts=counts)
    return summary


def _chunk_index(pos: int, size: int, data: bytes, records) -> ChunkIndex:
    """An index of the chunk at ``pos``: its time range, and each of its channels (at offset 0, the
    file's magic, until its message index record is met: read as "index unreadable")."""
    messages = [r for r in records if isinstance(r, Message)]
    body = pos + 9
    compression_len = struct.unpack_from("<I", data, body + 28)[0]
    compression = bytes(data[body + 32:body + 32 + compression_len]).decode()
    return ChunkIndex(
        message_start_time=min((m.log_time for m in messages), default=0),
        message_end_time=max((m.log_time for m in messages), default=0),
        chunk_start_offset=pos, chunk_length=size,
        message_index_offsets={m.channel_id: 0 for m in messages}, message_index_length=0,
        compression=compression, compressed_size=struct.unpack_from("<Q", data, body + 32 + compression_len)[0],
        uncompressed_size=struct.unpack_from("<Q", data, body + 16)[0])
