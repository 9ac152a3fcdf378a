"""Protobuf MCAP writer that flushes complete chunks periodically.

The log is written as ``NAME.partial`` (its header on disk from the first moment) and renamed to
``NAME`` when closed, so a file under the final name is always a complete log. A recording killed
at any point, or stopped by a full disk, leaves every message up to the last flush readable in
``NAME.partial`` (``trackreplay recover`` turns it into a valid log).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from types import TracebackType
from typing import Any

from mcap.writer import CompressionType, Writer
from mcap_protobuf.schema import register_schema

from trackreplay.recorder.atomic import open_partial
from trackreplay.recorder.interrupts import deferred_interrupts
from trackreplay.recorder.provenance import RECORD_NAME, provenance
from trackreplay.schemas.errors import OutputError

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
        sources: Mapping[str, Path | str | None] | None = None,
    ) -> None:
        """``sources``: the input files by role, described in the log's provenance record."""
        if compression not in COMPRESSION:
            raise ValueError(f"compression must be one of {sorted(COMPRESSION)}, not {compression!r}")
        self.path = Path(path)
        self._closed = False
        # this process's own file: another recording of the same name, or the leftover of one kept for
        # `recover`, is never truncated
        self.partial, self._fh = open_partial(self.path)
        self._writer = Writer(self._fh, chunk_size=chunk_size, compression=COMPRESSION[compression])
        with self._failing_as_output_error():
            self._writer.start(profile=profile, library="trackreplay")
            self._writer.add_metadata(RECORD_NAME, provenance(sources))
            self._fh.flush()
        self._schemas: dict[str, int] = {}
        self._channels: dict[str, int] = {}
        self._sequence: dict[str, int] = {}
        self._flush_every = max(1, flush_every)
        self._since_flush = 0
        self.messages_written = 0

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

    def _failing_as_output_error(self):
        return _OutputGuard(self)

    def write(self, topic: str, message: Any, log_time: int) -> None:
        """Append ``message`` on ``topic`` at capture time ``log_time`` (ns)."""
        with self._failing_as_output_error():
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
        with self._failing_as_output_error():
            self._writer.add_metadata(name, data)

    def add_attachment(self, name: str, data: bytes, media_type: str, log_time: int = 0) -> None:
        with self._failing_as_output_error():
            self._writer.add_attachment(create_time=log_time, log_time=log_time, name=name, media_type=media_type, data=data)

    def flush(self) -> None:
        """Close the open chunk and push everything to the OS."""
        with self._failing_as_output_error():
            self._writer.flush()
            self._fh.flush()
        self._since_flush = 0

    def close(self) -> None:
        """Finish the log (summary, footer) and give it its final name."""
        if self._closed:
            return
        with deferred_interrupts():  # finished and renamed, or not begun: never a summary without its name
            with self._failing_as_output_error():
                self._writer.finish()
                self._fh.flush()
                os.fsync(self._fh.fileno())
            self._closed = True
            self._fh.close()
            os.replace(self.partial, self.path)

    def discard(self) -> None:
        """Stop without a log: remove this writer's own temporary file (a file already under the final
        name, from an earlier run, stays as it was). After a failed write the partial log stays, for `recover`."""
        if self._closed:
            return
        self._abandon()
        self.partial.unlink(missing_ok=True)

    def _abandon(self) -> None:
        """After a failed write: stop, keeping ``NAME.partial`` (every flushed chunk) for ``recover``."""
        self._closed = True
        try:
            self._fh.close()
        except OSError:
            pass  # the buffered tail could not be written either; what was flushed stays

    def __enter__(self) -> LogWriter:
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        # On an exception we still finish the file: what was written stays a valid log.
        self.close()


class _OutputGuard:
    """Turns an OSError while writing (disk full, quota, file too large) into one sentence, and
    abandons the writer so that nothing more is attempted on the damaged file. Ctrl-C and SIGTERM
    wait for the guarded write to finish (:mod:`.interrupts`): a log is cut between records."""

    def __init__(self, log: LogWriter) -> None:
        self.log = log
        self._deferred = deferred_interrupts()

    def __enter__(self) -> None:
        self._deferred.__enter__()
        return None

    def __exit__(self, exc_type, exc, tb) -> bool:
        try:
            return self._handle(exc)
        finally:
            self._deferred.__exit__(None, None, None)  # a kept interrupt is raised here, after the write

    def _handle(self, exc: BaseException | None) -> bool:
        if exc is None or not isinstance(exc, OSError):
            return False
        self.log._abandon()
        raise OutputError(
            f"cannot write {self.log.path} ({exc.strerror or exc}); every message up to the last flush is in "
            f"{self.log.partial}: run `trackreplay recover {self.log.partial} {self.log.path}`"
        ) from None
