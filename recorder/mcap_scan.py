"""Walk an MCAP file record by record, checking every chunk's CRC, and resynchronise past damage.

``mcap``'s own readers stop at the first bad record (and so does the ``mcap`` CLI, mcap#1390): one
flipped byte in an early chunk would lose every later one. :func:`scan` instead reports the damaged
byte range and looks for the next record it can trust — a chunk whose framing adds up and whose
decompressed records match their CRC-32 — then carries on from there.

Only chunks are trusted after damage: they are the only data-section records that carry a checksum,
and every log trackreplay writes keeps its messages in chunks. Schema and channel records lost with
a damaged chunk are taken from the summary section when the file still has an intact one
(:func:`summary_definitions`), so the messages of later chunks stay decodable.

:func:`read_record` is the one reader of a record at an offset (framing, bounds, decompression,
CRC): the scan walks with it, and the replay's indexed reader (``replay.log.chunks``) reads each
indexed chunk and message index with it.
"""

from __future__ import annotations

import mmap
import struct
import zlib
from collections.abc import Iterator
from dataclasses import dataclass
from io import BytesIO
from pathlib import Path

from mcap.data_stream import ReadDataStream
from mcap.opcode import Opcode
from mcap.records import (Attachment, Channel, Chunk, DataEnd, Footer, Header, McapRecord, Message, MessageIndex,
                          Metadata, Schema)
from mcap.stream_reader import breakup_chunk

MCAP_MAGIC = b"\x89MCAP0\r\n"
FOOTER_SIZE = 1 + 8 + 8 + 8 + 4  # opcode, length, summary_start, summary_offset_start, summary_crc
# A record claiming more than this is damage, not data: nothing we write comes near it, and
# believing it would mean allocating it.
MAX_RECORD_BYTES = 1 << 30
COMPRESSIONS = (b"", b"zstd", b"lz4")

_READERS = {
    Opcode.HEADER: Header.read, Opcode.SCHEMA: Schema.read, Opcode.CHANNEL: Channel.read,
    Opcode.CHUNK: Chunk.read, Opcode.ATTACHMENT: Attachment.read, Opcode.METADATA: Metadata.read,
    Opcode.DATA_END: DataEnd.read, Opcode.FOOTER: Footer.read,
}
_KNOWN = frozenset(int(op) for op in Opcode)


@dataclass(frozen=True)
class Damage:
    """Bytes ``[start, end)`` could not be read as records; ``reason`` says why the first one failed."""

    start: int
    end: int
    reason: str


@dataclass(frozen=True)
class ChunkRecords:
    """The records of one chunk that passed its CRC check, and where the chunk sits in the file."""

    offset: int
    records: tuple[McapRecord, ...]


Item = McapRecord | ChunkRecords | Damage


class RecordDamage(Exception):
    """A record that does not check out (framing, bounds, decompression, CRC); the message says why."""


def _chunk_framing_ok(data: mmap.mmap | bytes, pos: int, length: int) -> bool:
    """Do a chunk's fixed fields at ``pos`` add up to its record length? (cheap: no decompression)"""
    body = pos + 9
    if body + 36 > len(data):
        return False
    compression_len = struct.unpack_from("<I", data, body + 28)[0]
    if compression_len > 4 or body + 32 + compression_len + 8 > len(data):
        return False
    if bytes(data[body + 32:body + 32 + compression_len]) not in COMPRESSIONS:
        return False
    records_len = struct.unpack_from("<Q", data, body + 32 + compression_len)[0]
    return 8 + 8 + 8 + 4 + 4 + compression_len + 8 + records_len == length


def read_record(data: mmap.mmap | bytes, pos: int, *,
                message_index: bool = False) -> tuple[int, McapRecord | ChunkRecords | None]:
    """The record at ``pos`` and its total size; a chunk as its CRC-checked :class:`ChunkRecords`;
    None for the records any writer rebuilds (indexes, statistics, summary offsets), except a
    message index when ``message_index``. Raises :class:`RecordDamage` for anything that does not
    check out."""
    if pos + 9 > len(data):
        raise RecordDamage("the file ends in the middle of a record")
    opcode = data[pos]
    length = struct.unpack_from("<Q", data, pos + 1)[0]
    if opcode not in _KNOWN:
        raise RecordDamage(f"unknown record type 0x{opcode:02x}")
    if length > MAX_RECORD_BYTES:
        raise RecordDamage(f"a record claims {length} bytes")
    end = pos + 9 + length
    if end > len(data):
        raise RecordDamage("the file ends in the middle of a record")
    if opcode == Opcode.CHUNK and not _chunk_framing_ok(data, pos, length):
        raise RecordDamage("a chunk's fields do not add up to its length")
    stream = ReadDataStream(BytesIO(data[pos + 9:end]))
    try:
        if opcode == Opcode.MESSAGE:
            record: McapRecord | None = Message.read(stream, length)
        elif opcode == Opcode.MESSAGE_INDEX and message_index:
            record = MessageIndex.read(stream)
        elif opcode in _READERS:
            record = _READERS[opcode](stream)
        else:
            record = None  # indexes, statistics, summary offsets: rebuilt by any writer
        if isinstance(record, Chunk):
            if record.uncompressed_size > MAX_RECORD_BYTES:
                raise RecordDamage(f"a chunk claims {record.uncompressed_size} bytes uncompressed")
            return end - pos, ChunkRecords(pos, tuple(breakup_chunk(record, validate_crc=True)))
    except RecordDamage:
        raise
    except Exception as err:  # CRC, zstd/lz4, struct, UTF-8, EOF inside the record: all mean damage
        raise RecordDamage(f"{type(err).__name__}: {err}" if str(err) else type(err).__name__) from None
    return end - pos, record


def _resync(data: mmap.mmap | bytes, start: int) -> int:
    """Offset of the next chunk after ``start`` that reads back intact (CRC included), else the file size."""
    pos = start
    while True:
        pos = data.find(bytes([Opcode.CHUNK]), pos + 1)
        if pos < 0 or pos + 9 > len(data):
            return len(data)
        length = struct.unpack_from("<Q", data, pos + 1)[0]
        if length > MAX_RECORD_BYTES or pos + 9 + length > len(data) or not _chunk_framing_ok(data, pos, length):
            continue
        try:
            read_record(data, pos)
        except RecordDamage:
            continue
        return pos


def chunk_messages(data: bytes, channels: list[Channel] | None = None) -> list[Message]:
    """The messages of the chunk record that ``data`` holds whole (e.g. read at a chunk index's offset
    and length), CRC-checked; raises :class:`RecordDamage` when it is damaged or not one chunk. The
    chunk's channel records are appended to ``channels`` when given."""
    size, item = read_record(data, 0)
    if not isinstance(item, ChunkRecords) or size != len(data):
        raise RecordDamage("no chunk record at the indexed offset")
    if channels is not None:
        channels.extend(r for r in item.records if isinstance(r, Channel))
    return [r for r in item.records if isinstance(r, Message)]


def scan(data: mmap.mmap | bytes) -> Iterator[Item]:
    """Every record of an MCAP image in file order (chunks as :class:`ChunkRecords`), with a
    :class:`Damage` for each unreadable stretch; stops after the footer or at the end of the data.
    The caller checks the leading magic."""
    pos = len(MCAP_MAGIC)
    while pos < len(data):
        try:
            size, record = read_record(data, pos)
        except RecordDamage as bad:
            nxt = _resync(data, pos)
            yield Damage(pos, nxt, str(bad))
            pos = nxt
            continue
        footer_at, pos = pos, pos + size
        if isinstance(record, Footer) and bytes(data[pos:]) != MCAP_MAGIC:
            yield Damage(pos, len(data), "the closing magic after the footer is missing or damaged")
            return
        if isinstance(record, Footer) and record.summary_crc and not _summary_intact(data, record, footer_at):
            # The summary (indexes, statistics) carries the only checksum after the data section:
            # readers that seek by it would be misled, so a mismatch is damage even if every chunk is fine.
            start = record.summary_start if len(MCAP_MAGIC) <= record.summary_start < footer_at else footer_at
            yield Damage(start, pos, "the summary section fails its CRC")
        if record is not None:
            yield record
        if isinstance(record, Footer):
            return


def _summary_intact(data: mmap.mmap | bytes, footer: Footer, footer_at: int) -> bool:
    """Does the CRC in the footer match the summary section and the footer's own offset fields?
    (``summary_start`` 0: a streamed log without a summary; the CRC covers those fields alone.)"""
    start = footer_at if footer.summary_start == 0 else footer.summary_start
    if not len(MCAP_MAGIC) <= start <= footer_at:
        return False
    return zlib.crc32(data[start:footer_at + 9 + 16]) == footer.summary_crc


def summary_definitions(data: mmap.mmap | bytes) -> tuple[dict[int, Schema], dict[int, Channel]]:
    """Schemas and channels from the file's summary section, when its footer and CRC are intact."""
    end = len(data) - len(MCAP_MAGIC)
    start = end - FOOTER_SIZE
    if start < len(MCAP_MAGIC) or bytes(data[end:]) != MCAP_MAGIC or data[start] != Opcode.FOOTER:
        return {}, {}
    summary_start, _, summary_crc = struct.unpack_from("<QQI", data, start + 9)
    if not len(MCAP_MAGIC) <= summary_start < start:
        return {}, {}
    if summary_crc and zlib.crc32(data[summary_start:start + 9 + 16]) != summary_crc:
        return {}, {}
    schemas: dict[int, Schema] = {}
    channels: dict[int, Channel] = {}
    pos = summary_start
    while pos < start:
        try:
            size, record = read_record(data, pos)
        except RecordDamage:
            return {}, {}
        if isinstance(record, Schema):
            schemas[record.id] = record
        elif isinstance(record, Channel):
            channels[record.id] = record
        pos += size
    return schemas, channels


def open_mapped(path: Path) -> mmap.mmap | bytes:
    """The file's bytes without reading them all into memory (an empty file maps to ``b""``)."""
    with open(path, "rb") as fh:
        if fh.seek(0, 2) == 0:
            return b""
        return mmap.mmap(fh.fileno(), 0, access=mmap.ACCESS_READ)
