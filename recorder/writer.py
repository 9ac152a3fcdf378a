"""Protobuf MCAP writer that flushes complete chunks periodically.

A recording killed at any point leaves every message up to the last flush readable
(``trackreplay recover`` turns such a file into a valid one).
"""

from __future__ import annotations

from pathlib import Path
from types import TracebackType
from typing import Any, BinaryIO

from mcap.writer import CompressionType, Writer
from mcap_protobuf.schema import register_schema

COMPRESSION = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4, "none": CompressionType.NONE}


class LogWriter:
    """Writes protobuf messages to an MCAP file, one channel per topic.

    ``flush_every`` messages (and at least every ``chunk_size`` bytes) a chunk is
    closed and written through to the OS, so a crash loses at most that many.
    """

    def __init__(
        self,
        path: str | Path,
        *,
        flush_every: int = 30,
        compression: str = "zstd",
        chunk_size: int = 4 * 1024 * 1024,
        profile: str = "",
    ) -> None:
        if compression not in COMPRESSION:
            raise ValueError(f"compression must be one of {sorted(COMPRESSION)}, not {compression!r}")
        self.path = Path(path)
        self._fh: BinaryIO = open(self.path, "wb")
        self._writer = Writer(self._fh, chunk_size=chunk_size, compression=COMPRESSION[compression])
        self._writer.start(profile=profile, library="trackreplay")
        self._schemas: dict[str, int] = {}
        self._channels: dict[str, int] = {}
        self._sequence: dict[str, int] = {}
        self._flush_every = max(1, flush_every)
        self._since_flush = 0
        self.messages_written = 0
        self._closed = False

    def _channel_for(self, topic: str, message: Any) -> int:
        channel_id = self._channels.get(topic)
        if channel_id is not None:
            return channel_id
        name = message.DESCRIPTOR.full_name
        schema_id = self._schemas.get(name)
        if schema_id is None:
            schema_id = register_schema(self._writer, type(message))
            self._schemas[name] = schema_id
        channel_id = self._writer.register_channel(topic=topic, message_encoding="protobuf", schema_id=schema_id)
        self._channels[topic] = channel_id
        self._sequence[topic] = 0
        return channel_id

    def write(self, topic: str, message: Any, log_time: int) -> None:
        """Append ``message`` on ``topic`` at capture time ``log_time`` (ns)."""
        channel_id = self._channel_for(topic, message)
        self._writer.add_message(
            channel_id=channel_id,
            log_time=int(log_time),
            publish_time=int(log_time),
            data=message.SerializeToString(),
            sequence=self._sequence[topic],
        )
        self._sequence[topic] += 1
        self.messages_written += 1
        self._since_flush += 1
        if self._since_flush >= self._flush_every:
            self.flush()

    def add_metadata(self, name: str, data: dict[str, str]) -> None:
        self._writer.add_metadata(name, data)

    def add_attachment(self, name: str, data: bytes, media_type: str, log_time: int = 0) -> None:
        self._writer.add_attachment(create_time=log_time, log_time=log_time, name=name, media_type=media_type, data=data)

    def flush(self) -> None:
        """Close the open chunk and push everything to the OS."""
        self._writer.flush()
        self._since_flush = 0

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        self._writer.finish()
        self._fh.close()

    def __enter__(self) -> LogWriter:
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        # On an exception we still finish the file: what was written stays a valid log.
        self.close()
