"""Salvage a truncated or damaged MCAP log into a valid one.

The source is read as a stream of records (``mcap.stream_reader.StreamReader``, the layer
under ``NonSeekingReader``, so that attachments and metadata come along in the same pass):
every complete chunk is kept, and reading stops at the first incomplete or damaged record.
Chunk CRCs are checked, so a chunk cut short is dropped rather than half-read.

A file that does not start with the MCAP magic raises ``LogError`` and nothing is written.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO

from mcap.records import Attachment, Channel, Footer, Header, McapRecord, Message, Metadata, Schema
from mcap.stream_reader import StreamReader
from mcap.writer import CompressionType, Writer

from trackreplay.schemas.errors import LogError

MCAP_MAGIC = b"\x89MCAP0\r\n"


@dataclass(frozen=True)
class RecoverReport:
    messages_saved: int
    complete: bool  # the source ended with a valid footer: nothing was lost
    error: str | None  # why reading stopped early, when it did
    attachments_saved: int = 0
    metadata_saved: int = 0


class RecordStream:
    """Records of an MCAP file up to the first damage; afterwards ``complete``/``error`` tell why it stopped."""

    def __init__(self, fh: BinaryIO, name: str) -> None:
        self._fh = fh
        self.name = name
        self.complete = False
        self.error: str | None = None
        self.header: Header | None = None

    def __iter__(self) -> Iterator[McapRecord]:
        start = self._fh.tell()
        if self._fh.read(len(MCAP_MAGIC)) != MCAP_MAGIC:
            raise LogError(f"{self.name} is not an MCAP file (bad magic bytes)")
        self._fh.seek(start)
        reader = StreamReader(self._fh, validate_crcs=True)
        try:
            for record in reader.records:
                if isinstance(record, Header):
                    self.header = record
                if isinstance(record, Footer):
                    self.complete = True  # StreamReader still checks the closing magic after this
                yield record
        except Exception as err:  # any damage: EndOfFile, bad lengths, CRC, decompression, struct errors
            self.complete = False
            self.error = self._describe(err)

    def _describe(self, err: Exception) -> str:
        pos, size = self._fh.tell(), os.fstat(self._fh.fileno()).st_size
        if pos >= size:
            what = "the file ends in the middle of a record"
        else:
            what = f"damaged record ({type(err).__name__}{': ' + str(err) if str(err) else ''})"
        return f"{what}, near byte {pos} of {size}"


def truncation_message(path: str | Path) -> str:
    return (
        f"{path} is truncated or damaged (no valid MCAP end); "
        f"run `trackreplay recover {path} OUT.mcap` to salvage every complete chunk"
    )


def recover(broken: str | Path, out: str | Path) -> RecoverReport:
    """Rewrite every readable schema, channel, message, attachment and metadata record of ``broken`` to ``out``."""
    broken, out = Path(broken), Path(out)
    if not broken.is_file():
        raise LogError(f"{broken} does not exist or is not a file")
    if out.exists() and os.path.samefile(broken, out):
        raise LogError(f"recover needs a new output path, not the input {broken} itself")
    with open(broken, "rb") as src:
        if src.read(len(MCAP_MAGIC)) != MCAP_MAGIC:
            raise LogError(f"{broken} is not an MCAP file (bad magic bytes); nothing to recover")
        src.seek(0)
        try:
            dst = open(out, "wb")
        except OSError as err:
            raise LogError(f"cannot write {out} ({err.strerror})") from None
        with dst:
            return _rewrite(RecordStream(src, str(broken)), dst)


def _rewrite(stream: RecordStream, dst: BinaryIO) -> RecoverReport:
    writer = Writer(dst, compression=CompressionType.ZSTD)
    started = False
    schemas: dict[int, int] = {}  # source id -> output id
    channels: dict[int, int] = {}
    messages = attachments = metadata = 0

    def start(profile: str = "") -> None:
        nonlocal started
        if not started:
            writer.start(profile=profile, library="trackreplay recover")
            started = True

    for record in stream:
        if isinstance(record, Header):
            start(record.profile)
            continue
        start()
        if isinstance(record, Schema):
            if record.id not in schemas:
                schemas[record.id] = writer.register_schema(record.name, record.encoding, record.data)
        elif isinstance(record, Channel):
            if record.id not in channels:
                if record.schema_id != 0 and record.schema_id not in schemas:
                    continue  # its schema was lost: the channel's messages cannot be decoded
                channels[record.id] = writer.register_channel(
                    record.topic, record.message_encoding, schemas.get(record.schema_id, 0), dict(record.metadata)
                )
        elif isinstance(record, Message):
            cid = channels.get(record.channel_id)
            if cid is not None:
                writer.add_message(cid, record.log_time, record.data, record.publish_time, record.sequence)
                messages += 1
        elif isinstance(record, Attachment):
            writer.add_attachment(record.create_time, record.log_time, record.name, record.media_type, record.data)
            attachments += 1
        elif isinstance(record, Metadata):
            writer.add_metadata(record.name, dict(record.metadata))
            metadata += 1
    start()
    writer.finish()
    return RecoverReport(messages, stream.complete and stream.error is None, stream.error, attachments, metadata)
