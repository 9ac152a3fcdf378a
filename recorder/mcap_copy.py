"""Copy an MCAP's records into a new one: its header, its schemas and channels as messages of
theirs are copied, and its attachments and metadata (used by ``annotate`` and ``filter``)."""

from __future__ import annotations

import struct
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import BinaryIO

import zstandard
from mcap.exceptions import McapError
from mcap.reader import McapReader
from mcap.records import Channel, Schema
from mcap.writer import Writer

from trackreplay.schemas.errors import TruncatedLogError

# the decompressors' own errors too: a flipped byte inside a compressed chunk (lz4 raises RuntimeError)
READ_ERRORS = (McapError, ValueError, EOFError, struct.error, zstandard.ZstdError, RuntimeError)


def require_intact(src: Path) -> None:
    """Walk ``src`` record by record, every chunk's CRC checked (:func:`.mcap_scan.scan`, as
    ``recover`` does), and refuse it at the first damage. mcap's own reader skips a chunk whose
    header is zeroed without a word, so its CRC checks alone would let such a copy lose frames."""
    from trackreplay.recorder.mcap_scan import Damage, open_mapped, scan

    data = open_mapped(src)
    try:
        for item in scan(data):
            if isinstance(item, Damage):
                raise TruncatedLogError(f"{src} is damaged ({item.reason} at bytes {item.start}-{item.end}); nothing "
                                        f"was written: run `trackreplay recover {src} FIXED.mcap` to salvage every "
                                        "intact chunk, then use FIXED.mcap")
    finally:
        if hasattr(data, "close"):
            data.close()


@contextmanager
def damage_is_an_error(src: Path) -> Iterator[None]:
    """A damaged or truncated ``src`` met while copying it after :func:`require_intact` passed it (a
    record mcap's reader cannot parse): one sentence; nothing is written (``replace_when_done``
    discards the partial output)."""
    try:
        yield
    except READ_ERRORS as err:
        raise TruncatedLogError(f"{src} is damaged ({type(err).__name__}: {err}); nothing was written: run "
                       f"`trackreplay recover {src} FIXED.mcap` to salvage every intact chunk, then use FIXED.mcap") from None


class McapCopy:
    """A :class:`Writer` on ``dst``, started with ``source``'s header profile and library."""

    def __init__(self, source: McapReader, dst: BinaryIO) -> None:
        header = source.get_header()
        self.writer = Writer(dst)
        self.writer.start(profile=header.profile, library=header.library)
        self._schema_ids: dict[int, int] = {}
        self._channel_ids: dict[int, int] = {}

    def channel_id(self, schema: Schema | None, channel: Channel) -> int:
        """The new id of ``channel``, registered (with its schema, if new too) on first use."""
        cid = self._channel_ids.get(channel.id)
        if cid is None:
            if schema is not None and schema.id not in self._schema_ids:
                self._schema_ids[schema.id] = self.writer.register_schema(schema.name, schema.encoding, schema.data)
            cid = self._channel_ids[channel.id] = self.writer.register_channel(
                channel.topic, channel.message_encoding, self._schema_ids[schema.id] if schema else 0,
                dict(channel.metadata))
        return cid

    def copy_attachments_and_metadata(self, source: McapReader) -> None:
        for att in source.iter_attachments():
            self.writer.add_attachment(att.create_time, att.log_time, att.name, att.media_type, att.data)
        for meta in source.iter_metadata():
            self.writer.add_metadata(meta.name, dict(meta.metadata))
