"""Copy an MCAP's records into a new one: its header, its schemas and channels as messages of
theirs are copied, and its attachments and metadata (used by ``annotate`` and ``filter``)."""

from __future__ import annotations

from typing import BinaryIO

from mcap.reader import McapReader
from mcap.records import Channel, Schema
from mcap.writer import Writer


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
