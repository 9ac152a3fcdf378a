"""What a log holds: topics, counts, rates, time gaps, stereo pairing, encoder coverage.

Streams the file once without decoding any payload (only log times are kept, for image and
encoder topics), so it works on damaged and truncated logs too: it reports what is readable and says
which is true — stretches ``damaged`` (a chunk failing its CRC) while the end is intact, or a file
``truncated`` (it ends early, with no MCAP footer), or both.
"""

from __future__ import annotations

from array import array
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from mcap.records import Attachment, Channel, Footer, Header, Message, Metadata, Schema

from trackreplay.recorder.mcap_scan import MCAP_MAGIC, ChunkRecords, Damage, open_mapped, scan
from trackreplay.replay.log.reader import MAX_LOG_TIME, time_out_of_range
from trackreplay.schemas.errors import LogError, TruncatedLogError
from trackreplay.schemas.messages import IMAGE_SCHEMAS

ENCODER_SCHEMA = "trackreplay.PtzEncoders"
GAP_FACTOR = 1.5  # an interval longer than this times the median is a gap
ENCODER_TOLERANCE_FACTOR = 3.0  # encoder readings further apart than this times the median leave a hole
LIST_LIMIT = 10  # items listed per problem in the text format


@dataclass
class _Tally:
    """What one pass over a log's records keeps: per channel counts and first/last times, image and
    encoder log times, schema names, attachments, metadata, damaged stretches, header and footer."""

    schemas: dict[int, str] = field(default_factory=dict)
    channels: dict[int, Channel] = field(default_factory=dict)
    counts: dict[int, int] = field(default_factory=dict)
    first: dict[int, int] = field(default_factory=dict)
    last: dict[int, int] = field(default_factory=dict)
    times: dict[int, array] = field(default_factory=dict)
    attachments: list[str] = field(default_factory=list)
    metadata: list[str] = field(default_factory=list)
    metadata_values: list[dict[str, Any]] = field(default_factory=list)
    damage: list[Damage] = field(default_factory=list)
    conflicts: list[str] = field(default_factory=list)  # a channel id declared again with other contents
    header: Header | None = None
    path: Path | None = None
    ended: bool = False
    size: int = 0

    def add(self, record) -> None:
        if isinstance(record, Message):
            cid = record.channel_id
            t = record.log_time
            if t > MAX_LOG_TIME:
                channel = self.channels.get(cid)
                raise time_out_of_range(self.path, channel.topic if channel else f"of channel {cid}",
                                        self.counts.get(cid, 0), t)
            if cid in self.counts:
                self.counts[cid] += 1
                self.first[cid] = min(self.first[cid], t)
                self.last[cid] = max(self.last[cid], t)
            else:
                self.counts[cid], self.first[cid], self.last[cid] = 1, t, t
            if cid in self.times:
                self.times[cid].append(t)
        elif isinstance(record, Schema):
            self.schemas.setdefault(record.id, record.name)
        elif isinstance(record, Channel) and record.id not in self.channels:
            self.channels[record.id] = record
            if self.schemas.get(record.schema_id) in (*IMAGE_SCHEMAS, ENCODER_SCHEMA):
                self.times[record.id] = array("q")
        elif isinstance(record, Channel):
            first = self.channels[record.id]
            if (first.topic, first.schema_id, first.message_encoding) != (record.topic, record.schema_id,
                                                                          record.message_encoding):
                self.conflicts.append(
                    f"channel {record.id} is declared twice with different contents ({first.topic} schema "
                    f"{first.schema_id} {first.message_encoding}, then {record.topic} schema {record.schema_id} "
                    f"{record.message_encoding}); its messages are counted as the first")
        elif isinstance(record, Attachment):
            self.attachments.append(record.name)
        elif isinstance(record, Metadata):
            self.metadata.append(record.name)
            self.metadata_values.append({"name": record.name, "values": dict(record.metadata)})
        elif isinstance(record, Header):
            self.header = record
        elif isinstance(record, Footer):
            self.ended = True

    @property
    def error(self) -> str | None:
        """Why the log is truncated (its damaged stretches, or the missing footer), None when it is complete."""
        if self.damage:
            return "; ".join(f"{d.reason} at bytes {d.start}-{d.end} of {self.size}" for d in self.damage[:LIST_LIMIT])
        if not self.ended:
            return f"the file ends without a footer after byte {self.size}"
        return None


def _tally(path: Path) -> _Tally:
    """One pass over the file's records, payloads not decoded."""
    tally = _Tally(path=path)
    data = open_mapped(path)
    if bytes(data[:len(MCAP_MAGIC)]) != MCAP_MAGIC:
        raise LogError(f"{path} is not an MCAP file (bad magic bytes)")
    try:
        for record in _records(scan(data), tally.damage):
            tally.add(record)
        tally.size = len(data)
    finally:
        if hasattr(data, "close"):
            data.close()
    return tally


def _topic_table(tally: _Tally) -> tuple[dict[str, dict[str, Any]], dict[str, np.ndarray]]:
    """Per topic (its channels merged): schema, encoding, count, first/last time, rate; and the sorted
    log times of the image and encoder topics."""
    topics: dict[str, dict[str, Any]] = {}
    topic_times: dict[str, list[np.ndarray]] = {}
    for cid in sorted(tally.channels):
        ch = tally.channels[cid]
        entry = topics.setdefault(
            ch.topic, {"topic": ch.topic, "schema": tally.schemas.get(ch.schema_id, ""), "encoding": ch.message_encoding,
                       "count": 0, "first_ns": None, "last_ns": None},
        )
        n = tally.counts.get(cid, 0)
        if n:
            first, last = tally.first[cid], tally.last[cid]
            entry["count"] += n
            entry["first_ns"] = first if entry["first_ns"] is None else min(entry["first_ns"], first)
            entry["last_ns"] = last if entry["last_ns"] is None else max(entry["last_ns"], last)
        if cid in tally.times:
            topic_times.setdefault(ch.topic, []).append(np.frombuffer(tally.times[cid], dtype=np.int64))
    for entry in topics.values():
        span = (entry["last_ns"] or 0) - (entry["first_ns"] or 0)
        entry["rate_hz"] = (entry["count"] - 1) / (span / 1e9) if entry["count"] > 1 and span > 0 else None
    return topics, {t: np.sort(np.concatenate(parts)) for t, parts in topic_times.items()}


def _time_checks(topics: dict[str, dict[str, Any]], sorted_times: dict[str, np.ndarray]) -> dict[str, Any]:
    """Time gaps per image topic, stereo pairing, and each image topic's coverage by each encoder topic."""
    image_topics = [t for t, e in topics.items() if e["schema"] in IMAGE_SCHEMAS]
    encoder_topics = [t for t, e in topics.items() if e["schema"] == ENCODER_SCHEMA]
    return {
        "gaps": {t: time_gaps(sorted_times[t]) for t in image_topics},
        "stereo": stereo_pairing(sorted_times, image_topics),
        "encoder_coverage": [
            encoder_coverage(sorted_times[img], sorted_times[enc], img, enc)
            for enc in encoder_topics
            for img in image_topics
            if "/right/" not in img  # a right image shares its left partner's time
        ],
    }


def log_info(path: str | Path, *, partial_ok: bool = False) -> dict[str, Any]:
    """Everything ``info`` reports, as JSON-ready data.

    A truncated or damaged log raises ``TruncatedLogError`` (:func:`problem_message`) unless
    ``partial_ok``, in which case the result covers the readable part with ``complete: False``,
    ``truncated`` (the file ends early: no footer), ``damaged`` (unreadable stretches, the chunks they
    cover numbered from 1 in file order), ``messages`` (readable) beside ``messages_expected`` (the
    summary's count, when the summary is readable) and ``error``.
    """
    from trackreplay.recorder.log_summary import log_file

    path = log_file(path)
    tally = _tally(path)
    chunking = _chunking(path)
    damaged = [{"start_byte": d.start, "end_byte": d.end, "reason": d.reason,
                "chunks": [i + 1 for i, offset in enumerate(chunking["chunk_offsets"] or []) if d.start <= offset < d.end]}
               for d in tally.damage]
    messages = sum(tally.counts.values())
    if (tally.damage or not tally.ended) and not partial_ok:
        raise TruncatedLogError(problem_message(path, not tally.ended, damaged, messages, chunking))
    topics, sorted_times = _topic_table(tally)
    starts = [e["first_ns"] for e in topics.values() if e["first_ns"] is not None]
    ends = [e["last_ns"] for e in topics.values() if e["last_ns"] is not None]
    start, end = (min(starts), max(ends)) if starts else (None, None)
    return {
        "path": str(path),
        "complete": tally.ended and not tally.damage,
        "truncated": not tally.ended,  # the file ends early: no footer
        "error": tally.error,
        "damaged": damaged,  # unreadable stretches (a file whose end is intact may have some)
        "channel_conflicts": tally.conflicts,
        "library": tally.header.library if tally.header else None,
        "messages": messages,  # readable ones
        "messages_expected": chunking["messages_expected"],  # the summary's count, when it has one
        "start_ns": start,
        "end_ns": end,
        "duration_s": (end - start) / 1e9 if start is not None else None,
        "topics": sorted(topics.values(), key=lambda e: e["topic"]),
        **_time_checks(topics, sorted_times),
        "attachments": tally.attachments,
        "metadata": tally.metadata,
        "metadata_values": tally.metadata_values,
        "file_bytes": path.stat().st_size,
        "chunks": chunking["chunks"],
        "compression": chunking["compression"],
    }


def problem_message(path: Path, truncated: bool, damaged: list[dict[str, Any]], messages: int,
                    chunking: dict[str, Any]) -> str:
    """One sentence on what is wrong with a log, by what is true: it ends early (``truncated``: no
    MCAP end), or stretches of it are unreadable while its end is intact (``damaged``)."""
    parts = []
    if damaged:
        total = chunking["chunks"]
        where = []
        for d in damaged[:LIST_LIMIT]:
            nums = d["chunks"]
            what = (f"chunk{'s' if len(nums) > 1 else ''} {', '.join(map(str, nums))}{f' of {total}' if total else ''} at "
                    if nums else "")
            where.append(f"{what}bytes {d['start_byte']}-{d['end_byte']}" + ("" if nums else f" ({d['reason']})"))
        more = f" and {len(damaged) - LIST_LIMIT} more" if len(damaged) > LIST_LIMIT else ""
        parts.append(f"{'; '.join(where)}{more} unreadable")
    parts.append("it ends early (no valid MCAP end)" if truncated else "the log's end is intact")
    expected = chunking["messages_expected"]
    parts.append(f"{messages} of {expected} messages readable" if expected is not None and not truncated
                 else f"{messages} messages readable")
    state = "truncated" if truncated else "damaged"
    return (f"{path} is {state}: {'; '.join(parts)}; run `trackreplay recover {path} OUT.mcap` "
            f"to salvage every intact chunk")


def _chunking(path: Path) -> dict[str, Any]:
    """Chunk count, compression, the chunks' byte offsets (in file order) and the message count from
    the summary section (None when it cannot be read)."""
    from mcap.reader import make_reader

    stats = None
    try:
        with open(path, "rb") as fh:
            summary = make_reader(fh).get_summary()
        if summary is None:  # a streamed log: its chunks counted by a linear scan
            from trackreplay.recorder.mcap_summary import streamed_summary

            summary = streamed_summary(path)
        else:
            stats = summary.statistics
        indexes = summary.chunk_indexes if summary else None
    except Exception:  # a truncated log: the scan above already says what is readable
        indexes = None
    if indexes is None:
        return {"chunks": None, "compression": None, "chunk_offsets": None, "messages_expected": None}
    return {"chunks": len(indexes), "compression": sorted({ci.compression or "none" for ci in indexes}) or ["none"],
            "chunk_offsets": sorted(ci.chunk_start_offset for ci in indexes),
            "messages_expected": stats.message_count if stats is not None else None}


def _calendar(t: int | None) -> str:
    """UTC date and time for a log_time in ns since the epoch; '' for a time near zero (a synthetic log's)."""
    if t is None or t < 10**17:  # before 1973: a relative clock, not a date
        return ""
    from datetime import datetime, timezone

    stamp = datetime.fromtimestamp(t // 10**9, tz=timezone.utc).strftime("%Y-%m-%d %H:%M:%S")
    return f" ({stamp}.{t % 10**9 // 1000:06d} UTC)"


def _size(n: int) -> str:
    for unit in ("B", "KiB", "MiB", "GiB"):
        if n < 1024 or unit == "GiB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1024
    return f"{n} B"


def _records(items, damage: list[Damage]):
    """Records in file order with chunks opened; damaged stretches go to ``damage``."""
    for item in items:
        if isinstance(item, Damage):
            damage.append(item)
        elif isinstance(item, ChunkRecords):
            yield from item.records
        else:
            yield item


def time_gaps(t: np.ndarray, factor: float = GAP_FACTOR) -> dict[str, Any]:
    """Intervals longer than ``factor`` x the median interval; ``after`` is the index of the frame before the gap."""
    if t.size < 3:
        return {"median_interval_ns": int(np.diff(t)[0]) if t.size == 2 else None, "gaps": []}
    dt = np.diff(t)
    median = float(np.median(dt))
    idx = np.flatnonzero(dt > factor * median)
    gaps = [{"after": int(i), "from_ns": int(t[i]), "to_ns": int(t[i + 1]), "interval_ns": int(dt[i])} for i in idx]
    return {"median_interval_ns": int(round(median)), "gaps": gaps}


def stereo_pairing(times: dict[str, np.ndarray], image_topics: list[str]) -> list[dict[str, Any]]:
    """For each ``.../left/...`` image topic with a ``.../right/...`` partner: times without an equal partner."""
    out = []
    for left in image_topics:
        right = left.replace("/left/", "/right/")
        if "/left/" not in left or right not in times:
            continue
        lt, rt = times[left], times[right]
        out.append({
            "left": left,
            "right": right,
            "pairs": int(np.intersect1d(lt, rt).size),
            "left_unpaired_ns": [int(v) for v in np.setdiff1d(lt, rt)],
            "right_unpaired_ns": [int(v) for v in np.setdiff1d(rt, lt)],
        })
    return out


def encoder_coverage(frames: np.ndarray, enc: np.ndarray, image_topic: str, encoder_topic: str,
                     factor: float = ENCODER_TOLERANCE_FACTOR) -> dict[str, Any]:
    """Frames outside [first, last] reading, and frames whose bracketing readings are too far apart."""
    result: dict[str, Any] = {"image_topic": image_topic, "encoder_topic": encoder_topic,
                              "tolerance_ns": None, "outside": [], "sparse": []}
    if enc.size == 0 or frames.size == 0:
        result["outside"] = list(range(frames.size))
        return result
    outside = (frames < enc[0]) | (frames > enc[-1])
    result["outside"] = [int(i) for i in np.flatnonzero(outside)]
    if enc.size < 2:
        return result
    tol = factor * float(np.median(np.diff(enc)))
    result["tolerance_ns"] = int(round(tol))
    hi = np.clip(np.searchsorted(enc, frames, side="left"), 1, enc.size - 1)
    exact = enc[np.clip(np.searchsorted(enc, frames), 0, enc.size - 1)] == frames
    span = enc[hi] - enc[hi - 1]
    sparse = ~outside & ~exact & (span > tol)
    result["sparse"] = [{"frame": int(i), "t_ns": int(frames[i]), "readings_apart_ns": int(span[i])} for i in np.flatnonzero(sparse)]
    return result


def _ns(t: int | None) -> str:
    return "-" if t is None else f"{t / 1e9:.6f} s"


def _listed(items: list, fmt) -> list[str]:
    lines = [f"      {fmt(i)}" for i in items[:LIST_LIMIT]]
    if len(items) > LIST_LIMIT:
        lines.append(f"      ... and {len(items) - LIST_LIMIT} more")
    return lines


def format_info(info: dict[str, Any]) -> str:
    """A human-readable report of ``log_info``'s result."""
    state = "TRUNCATED" if info["truncated"] else "DAMAGED" if info["damaged"] else None
    lines = [f"{info['path']}" + (f"  [{state}: showing the readable part]" if state else "")]
    dur = info["duration_s"]
    if info.get("file_bytes") is not None:
        chunks = "-" if info.get("chunks") is None else info["chunks"]
        compression = "/".join(info.get("compression") or ["-"])
        lines.append(f"  size {_size(info['file_bytes'])}, {chunks} chunks, compression {compression}, "
                     f"library {info.get('library') or '-'}")
    lines.append(f"  start {_ns(info['start_ns'])}{_calendar(info['start_ns'])}")
    lines.append(f"  end   {_ns(info['end_ns'])}{_calendar(info['end_ns'])}")
    lines.append(f"  duration {'-' if dur is None else f'{dur:.3f} s'}, {info['messages']} messages")
    width = max((len(e["topic"]) for e in info["topics"]), default=5)
    swidth = max((len(e["schema"]) for e in info["topics"]), default=6)
    cwidth = max((len(str(e["count"])) for e in info["topics"]), default=5)
    lines.append("  topics:")
    for e in info["topics"]:
        rate = "-" if e["rate_hz"] is None else f"{e['rate_hz']:.2f} Hz"
        lines.append(f"    {e['topic']:<{width}}  {e['schema']:<{swidth}}  {e['count']:>{cwidth}}  {rate}")
    for meta in info.get("metadata_values", []):
        lines.append(f"  metadata {meta['name']}:")
        lines.extend(f"    {k}: {v}" for k, v in sorted(meta["values"].items()))
    for topic, g in info["gaps"].items():
        if g["gaps"]:
            lines.append(f"  time gaps on {topic} (> {GAP_FACTOR}x median {g['median_interval_ns'] / 1e6:.2f} ms): {len(g['gaps'])}")
            lines += _listed(g["gaps"], lambda x: f"after frame {x['after']}: {_ns(x['from_ns'])} -> {_ns(x['to_ns'])} ({x['interval_ns'] / 1e6:.2f} ms)")
    for s in info["stereo"]:
        n_l, n_r = len(s["left_unpaired_ns"]), len(s["right_unpaired_ns"])
        if n_l or n_r:
            lines.append(f"  stereo pairing: {s['pairs']} pairs; {n_l} {s['left']} and {n_r} {s['right']} images without a partner of equal log_time")
            lines += _listed([("left", t) for t in s["left_unpaired_ns"]] + [("right", t) for t in s["right_unpaired_ns"]],
                             lambda x: f"{x[0]} at {_ns(x[1])}")
    for c in info["encoder_coverage"]:
        if c["outside"]:
            lines.append(f"  {len(c['outside'])} frame(s) of {c['image_topic']} outside the {c['encoder_topic']} readings' time range")
            lines += _listed(c["outside"], lambda i: f"frame {i}")
        if c["sparse"]:
            lines.append(f"  {len(c['sparse'])} frame(s) of {c['image_topic']} between {c['encoder_topic']} readings more than "
                         f"{c['tolerance_ns'] / 1e6:.2f} ms apart")
            lines += _listed(c["sparse"], lambda x: f"frame {x['frame']} at {_ns(x['t_ns'])}: readings {x['readings_apart_ns'] / 1e6:.2f} ms apart")
    if info["attachments"]:
        lines.append(f"  attachments: {', '.join(info['attachments'])}")
    if info["metadata"]:
        lines.append(f"  metadata: {', '.join(info['metadata'])}")
    if info.get("channel_conflicts"):
        lines.append(f"  WARNING: {len(info['channel_conflicts'])} channel declaration(s) contradict an earlier one")
        lines += _listed(info["channel_conflicts"], str)
    return "\n".join(lines + _problem_lines(info))


def _problem_lines(info: dict[str, Any]) -> list[str]:
    """What is unreadable, by what is true: damaged stretches (the end intact or not), or an early end."""
    if info["damaged"]:
        end = "the file ends early (no valid MCAP end)" if info["truncated"] else "the log's end is intact"
        expected = info.get("messages_expected")
        readable = (f"{info['messages']} of {expected} messages readable" if expected is not None and not info["truncated"]
                    else f"{info['messages']} messages readable")
        return [f"  DAMAGED: {len(info['damaged'])} unreadable stretch(es) skipped (their chunks' messages are not "
                f"counted above); {end}; {readable}",
                *_listed(info["damaged"], lambda d: (f"chunk {', '.join(map(str, d['chunks']))}: " if d.get("chunks") else "")
                         + f"bytes {d['start_byte']}-{d['end_byte']}: {d['reason']}")]
    return [f"  TRUNCATED: {info['error']}"] if info["truncated"] else []
