"""Reading trackreplay logs with clear, one-sentence errors.

Messages come in a total, reproducible order: log_time, then channel id, then
sequence (docs/architecture.md §3 Log contract).

Channels are decoded by their encoding: protobuf (ours and Foxglove's), ROS 2 CDR with a
``ros2msg`` schema (rosbag2's MCAP profile, via ``mcap-ros2-support``), and JSON (Foxglove's
JSON-encoded schemas; decoded into attribute namespaces, ``bytes`` fields still base64 text).
"""

from __future__ import annotations

import heapq
import json
import struct
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

from mcap.exceptions import McapError
from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory
from mcap_ros2.decoder import DecoderFactory as Ros2DecoderFactory

from trackreplay.replay.log.chunks import ChunkCache, DamagedChunk, iter_checked
from trackreplay.schemas.errors import LogError, TruncatedLogError

MCAP_MAGIC = b"\x89MCAP0\r\n"


@dataclass(frozen=True)
class TopicInfo:
    topic: str
    schema: str
    encoding: str
    count: int


@dataclass(frozen=True)
class LogMessage:
    """A message with its place in the log; ``decode()`` parses it on demand."""

    topic: str
    schema: str
    log_time: int
    channel_id: int
    sequence: int
    index: int  # position of this message within its topic (0-based)
    data: bytes
    _decoder: Callable[[bytes], Any]
    _path: str
    lost: str | None = None  # why this message could not be read (a damaged chunk); it has no data

    def decode(self) -> Any:
        if self.lost is not None:
            raise LogError(f"{self._path}: message {self.index} on topic {self.topic} is lost ({self.lost})")
        try:
            return self._decoder(self.data)
        except Exception as err:  # protobuf raises DecodeError or RuntimeWarning-ish errors
            raise LogError(
                f"{self._path}: message {self.index} on topic {self.topic} cannot be decoded as {self.schema} ({err})"
            ) from None


class JsonMessage(dict):
    """A decoded JSON message: keys read as attributes too (``msg.data``), like protobuf and ROS 2 ones."""

    def __getattr__(self, name: str) -> Any:
        try:
            return self[name]
        except KeyError:
            raise AttributeError(name) from None


def _to_message(value: Any) -> Any:
    if isinstance(value, dict):
        return JsonMessage({k: _to_message(v) for k, v in value.items()})
    if isinstance(value, list):
        return [_to_message(v) for v in value]
    return value


def _json_decode(data: bytes) -> JsonMessage:
    value = json.loads(data)
    if not isinstance(value, dict):
        raise ValueError(f"a JSON message is an object, not {type(value).__name__}")
    return _to_message(value)


MAX_LOG_TIME = 2**63 - 1  # log times are signed 64-bit nanosecond counts downstream (Arrow, numpy, Parquet)


def time_out_of_range(path: str | Path, topic: str, index: int, log_time: int) -> LogError:
    """The one-sentence refusal of a log time that does not fit a signed 64-bit nanosecond count (a
    negative time written as unsigned wraps to 2**63 or more)."""
    return LogError(f"{path}: message {index} on topic {topic} has log time {log_time} ns, beyond the signed 64-bit "
                    f"range (at most {MAX_LOG_TIME}; a negative time written as unsigned wraps there)")


def _truncation_hint(path: Path) -> str:
    return f"{path} is truncated or corrupt (no valid MCAP footer); run `trackreplay recover {path} FIXED.mcap` to salvage every complete chunk"


def _streamed_summary(path: Path):
    """The summary of a complete log written without one (``summary_start`` 0: a streamed recording),
    rebuilt by a linear scan; a file that is not one is truncated."""
    from trackreplay.recorder.mcap_scan import RecordDamage
    from trackreplay.recorder.mcap_summary import streamed_summary

    try:
        summary = streamed_summary(path)
    except RecordDamage as bad:
        raise TruncatedLogError(f"{_truncation_hint(path)} ({bad})") from None
    if summary is None:
        raise TruncatedLogError(_truncation_hint(path))
    return summary


class LogReader:
    """Random-access reader over one MCAP log (opens the file per iteration)."""

    def __init__(self, path: str | Path) -> None:
        from trackreplay.recorder.log_summary import log_file

        self.path = log_file(path)  # (a ROS 2 bag folder: the .mcap in it)
        with open(self.path, "rb") as fh:
            head = fh.read(8)
            fh.seek(0, 2)
            size = fh.tell()
            fh.seek(max(0, size - 8))
            tail = fh.read(8)
        if head != MCAP_MAGIC:
            raise LogError(f"{self.path} is not an MCAP file (bad magic bytes)")
        if tail != MCAP_MAGIC:
            raise TruncatedLogError(_truncation_hint(self.path))
        try:
            with open(self.path, "rb") as fh:
                summary = make_reader(fh).get_summary()
        except (McapError, OSError, ValueError, EOFError, struct.error) as err:  # e.g. magic only: seeks before byte 0
            raise TruncatedLogError(_truncation_hint(self.path) + f" ({type(err).__name__})") from None
        if summary is None:
            summary = _streamed_summary(self.path)
        self._summary = summary
        self._factory = DecoderFactory()
        self._ros2 = Ros2DecoderFactory()
        self._decoders: dict[int, Callable[[bytes], Any]] = {}
        # a replay's image and encoder iterations share each chunk's parse; it also notes a channel id
        # a chunk declares again with other contents (``channel_conflicts``)
        self._chunks = ChunkCache(channels=summary.channels)
        self.channel_conflicts: dict[int, str] = self._chunks.conflicts

    # -- what the log holds -------------------------------------------------

    def topics(self) -> dict[str, TopicInfo]:
        counts = self._summary.statistics.channel_message_counts if self._summary.statistics else {}
        out: dict[str, TopicInfo] = {}
        for cid in sorted(self._summary.channels):
            ch = self._summary.channels[cid]
            schema = self._summary.schemas.get(ch.schema_id)
            name = schema.name if schema else ""
            prev = out.get(ch.topic)
            n = counts.get(cid, 0) + (prev.count if prev else 0)
            out[ch.topic] = TopicInfo(ch.topic, name, ch.message_encoding, n)
        return out

    def time_range(self) -> tuple[int, int]:
        st = self._summary.statistics
        return (st.message_start_time, st.message_end_time) if st else (0, 0)

    def require(self, *topics: str) -> None:
        present = self.topics()
        for topic in topics:
            if topic not in present:
                listed = ", ".join(sorted(present)) or "none"
                raise LogError(f"{self.path} has no topic {topic}; topics present: {listed}")

    def schema_of(self, topic: str) -> str:
        self.require(topic)
        return self.topics()[topic].schema

    # -- messages -------------------------------------------------------------

    def _decoder(self, schema, channel) -> Callable[[bytes], Any]:
        dec = self._decoders.get(channel.id)
        if dec is None:
            encoding = channel.message_encoding
            try:
                if encoding == "json":
                    dec = _json_decode
                elif encoding == "cdr":
                    dec = self._ros2.decoder_for(encoding, schema)
                else:
                    dec = self._factory.decoder_for(encoding, schema)
            except Exception as err:
                raise LogError(f"{self.path}: schema of topic {channel.topic} cannot be loaded ({err})") from None
            if dec is None:
                schema_encoding = schema.encoding if schema else "no schema"
                raise LogError(
                    f"{self.path}: topic {channel.topic} is encoded as {encoding or 'nothing'} ({schema_encoding}); "
                    f"trackreplay reads protobuf, ROS 2 CDR (ros2msg schemas) and JSON channels"
                )
            self._decoders[channel.id] = dec
        return dec

    def messages(
        self,
        topics: Iterable[str],
        *,
        start_ns: int | None = None,
        end_ns: int | None = None,
    ) -> Iterator[LogMessage]:
        """Messages of ``topics`` with ``start_ns <= log_time < end_ns`` in total order.

        ``index`` counts from the start of the log, not from ``start_ns``.
        """
        topics = sorted(set(topics))
        self.require(*topics)
        offsets = self._index_offsets(topics, start_ns)
        counters = dict(offsets)
        if not self._summary.chunk_indexes:  # an unindexed log (other writers): mcap's linear reader
            yield from self._unindexed_messages(topics, counters, start_ns, end_ns)
            return
        channels = {cid: ch for cid, ch in self._summary.channels.items() if ch.topic in topics}
        try:
            with open(self.path, "rb") as fh:
                for item in iter_checked(fh, self._summary, channels, start_ns, end_ns, self._chunks):
                    channel = channels[item.channel_id]
                    schema = self._summary.schemas.get(channel.schema_id)
                    dec = self._decoder(schema, channel)
                    name = schema.name if schema else ""
                    if isinstance(item, DamagedChunk):
                        reason = f"damaged chunk at byte {item.offset}: {item.reason}"
                        if item.log_times is None:
                            reason += "; how many messages it held is unknown, so later message numbers may be too low"
                        for t in item.log_times or (None,):
                            idx = counters.get(channel.topic, 0)
                            if t is not None and t > MAX_LOG_TIME:
                                raise time_out_of_range(self.path, channel.topic, idx, t)
                            counters[channel.topic] = idx + (t is not None)
                            yield LogMessage(channel.topic, name, t if t is not None else -1, channel.id, -1, idx, b"",
                                             dec, str(self.path), lost=reason)
                        continue
                    idx = counters.get(channel.topic, 0)
                    counters[channel.topic] = idx + 1
                    if item.log_time > MAX_LOG_TIME:
                        raise time_out_of_range(self.path, channel.topic, idx, item.log_time)
                    yield LogMessage(channel.topic, name, item.log_time, channel.id, item.sequence, idx, item.data,
                                     dec, str(self.path))
        except (McapError, OSError, ValueError, EOFError, struct.error) as err:
            raise LogError(f"{_truncation_hint(self.path)} ({type(err).__name__}: {err})") from None

    def messages_at(self, topic: str, indices: Iterable[int]) -> list[LogMessage] | None:
        """The messages of ``topic`` numbered ``indices`` (as :meth:`messages` numbers them), in index
        order, reading only the chunks that hold them: the chunks' message index records (small,
        uncompressed) give every message's log time, so the k-th message in log-time order is found
        without decompressing the chunks before it. A message of a damaged chunk comes back ``lost``.

        None when the indexes cannot say (an unindexed log, a topic on two channels, a chunk whose
        message index is unreadable, two messages at one log time): iterate :meth:`messages` then.
        """
        from trackreplay.recorder.mcap_scan import RecordDamage
        from trackreplay.replay.log.chunks import _lost_times

        self.require(topic)
        channels = [ch for ch in self._summary.channels.values() if ch.topic == topic]
        if not self._summary.chunk_indexes or len(channels) != 1:
            return None
        channel = channels[0]
        schema = self._summary.schemas.get(channel.schema_id)
        dec = self._decoder(schema, channel)
        name = schema.name if schema else ""
        owners: dict[int, Any] = {}  # log time -> chunk index
        try:
            with open(self.path, "rb") as fh:
                for index in self._summary.chunk_indexes:
                    if channel.id not in index.message_index_offsets:
                        continue
                    times = _lost_times(fh, index, channel.id)
                    if times is None:
                        return None
                    for t in times:
                        if t in owners:
                            return None
                        owners[t] = index
                order = sorted(owners)
                out = []
                for k in sorted(set(indices)):
                    if not 0 <= k < len(order):
                        continue
                    t = order[k]
                    if t > MAX_LOG_TIME:
                        raise time_out_of_range(self.path, topic, k, t)
                    index = owners[t]
                    try:
                        found = [m for m in self._chunks.load(fh, index) if m.channel_id == channel.id and m.log_time == t]
                    except RecordDamage as bad:
                        out.append(LogMessage(topic, name, t, channel.id, -1, k, b"", dec, str(self.path),
                                              lost=f"damaged chunk at byte {index.chunk_start_offset}: {bad}"))
                        continue
                    if len(found) != 1:
                        return None
                    out.append(LogMessage(topic, name, t, channel.id, found[0].sequence, k, found[0].data, dec, str(self.path)))
                return out
        except (McapError, OSError, ValueError, EOFError, struct.error) as err:
            raise LogError(f"{_truncation_hint(self.path)} ({type(err).__name__}: {err})") from None

    def _unindexed_messages(self, topics: list[str], counters: dict[str, int], start_ns: int | None,
                            end_ns: int | None) -> Iterator[LogMessage]:
        pending: list[tuple[int, int, int, int, LogMessage]] = []
        try:
            with open(self.path, "rb") as fh:
                reader = make_reader(fh, validate_crcs=True)
                it = reader.iter_messages(topics=topics, starting_at=start_ns, ending_before=end_ns, log_time_order=True)
                for schema, channel, msg in it:
                    dec = self._decoder(schema, channel)
                    idx = counters.get(channel.topic, 0)
                    counters[channel.topic] = idx + 1
                    if msg.log_time > MAX_LOG_TIME:
                        raise time_out_of_range(self.path, channel.topic, idx, msg.log_time)
                    item = LogMessage(
                        channel.topic, schema.name if schema else "", msg.log_time, channel.id,
                        msg.sequence, idx, msg.data, dec, str(self.path),
                    )
                    # Equal log_time: release only once time advances, ordered by channel then sequence.
                    if pending and pending[0][0] != msg.log_time:
                        while pending:
                            yield heapq.heappop(pending)[4]
                    heapq.heappush(pending, (msg.log_time, channel.id, msg.sequence, idx, item))
                while pending:
                    yield heapq.heappop(pending)[4]
        except (McapError, OSError, ValueError, EOFError, struct.error) as err:
            raise LogError(f"{_truncation_hint(self.path)} ({type(err).__name__}: {err})") from None

    def _index_offsets(self, topics: list[str], start_ns: int | None) -> dict[str, int]:
        """How many messages each topic has before ``start_ns`` (lost ones included)."""
        if not start_ns:
            return {t: 0 for t in topics}
        counts = {t: 0 for t in topics}
        if not self._summary.chunk_indexes:
            with open(self.path, "rb") as fh:
                for _, channel, _ in make_reader(fh).iter_messages(
                    topics=topics, ending_before=start_ns, log_time_order=False
                ):
                    counts[channel.topic] += 1
            return counts
        channels = {cid: ch for cid, ch in self._summary.channels.items() if ch.topic in topics}
        with open(self.path, "rb") as fh:
            for item in iter_checked(fh, self._summary, channels, None, start_ns):
                lost = isinstance(item, DamagedChunk)
                counts[channels[item.channel_id].topic] += len(item.log_times or ()) if lost else 1
        return counts

    def first(self, topic: str) -> Any | None:
        """The first decoded message of ``topic``, or None when the topic is absent."""
        if topic not in self.topics():
            return None
        for item in self.messages([topic]):
            return item.decode()
        return None
