"""Salvage a truncated or damaged MCAP log into a valid one.

The source is walked record by record (:mod:`.mcap_scan`): every chunk whose CRC checks out is
kept, a damaged stretch is skipped and reading resumes at the next intact chunk, so one flipped
byte costs the chunk it sits in and nothing after it. Schemas and channels lost with a damaged chunk
come from the summary section when the file still has one. The output is written under a temporary
name and renamed when complete, so it is always a valid log (possibly empty).

A file that does not start with the MCAP magic raises ``LogError`` and nothing is written.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import BinaryIO

from mcap.records import Attachment, Channel, Footer, Header, Message, Metadata, Schema
from mcap.writer import CompressionType, Writer

from trackreplay.recorder.atomic import replace_when_done
from trackreplay.recorder.provenance import RECORD_NAME, provenance
from trackreplay.recorder.mcap_scan import MCAP_MAGIC, ChunkRecords, Damage, open_mapped, scan, summary_definitions
from trackreplay.schemas import messages as m
from trackreplay.schemas import topics as T
from trackreplay.schemas.errors import LogError

# `trackreplay recover` exit statuses
COMPLETE, PARTIAL, NOTHING = 0, 1, 2


@dataclass(frozen=True)
class RecoverReport:
    messages_saved: int
    complete: bool  # the source was intact and ended with a valid footer: nothing was lost
    error: str | None  # what was damaged or missing, when anything was
    attachments_saved: int = 0
    metadata_saved: int = 0
    damage: tuple[Damage, ...] = field(default_factory=tuple)  # byte ranges skipped
    messages_orphaned: int = 0  # intact messages whose channel definition was lost with no summary to recover it
    marks_dropped: int = 0  # marks (and ground-truth frames) whose image was lost with a damaged chunk

    @property
    def exit_code(self) -> int:
        if self.complete:
            return COMPLETE
        return PARTIAL if self.messages_saved or self.attachments_saved or self.metadata_saved else NOTHING


def truncation_message(path: str | Path) -> str:
    return (
        f"{path} is truncated or damaged (no valid MCAP end); "
        f"run `trackreplay recover {path} OUT.mcap` to salvage every intact chunk"
    )


def recover(broken: str | Path, out: str | Path) -> RecoverReport:
    """Rewrite every intact schema, channel, message, attachment and metadata record of ``broken`` to ``out``."""
    broken, out = Path(broken), Path(out)
    if not broken.is_file():
        raise LogError(f"{broken} does not exist or is not a file")
    if out.exists() and os.path.samefile(broken, out):
        raise LogError(f"recover needs a new output path, not the input {broken} itself")
    data = open_mapped(broken)
    try:
        if bytes(data[:len(MCAP_MAGIC)]) != MCAP_MAGIC:
            raise LogError(f"{broken} is not an MCAP file (bad magic bytes); nothing to recover")
        with replace_when_done(out) as dst:
            return _rewrite(data, dst, broken)
    finally:
        if hasattr(data, "close"):
            data.close()


class _Copy:
    """The output writer and the id maps from source to output schemas and channels."""

    def __init__(self, dst: BinaryIO, summary: tuple[dict[int, Schema], dict[int, Channel]],
                 frames: dict[int, int] | None = None) -> None:
        self.writer = Writer(dst, compression=CompressionType.ZSTD)
        # With images lost: each surviving image's log time -> its new number, for the records that
        # count frames (marks, ground truth); None when nothing was lost (every record as it was)
        self.frames = frames
        self.topics: dict[int, str] = {}
        self.dropped = 0
        self.summary_schemas, self.summary_channels = summary
        self.started = False
        self.schemas: dict[int, int] = {}
        self.channels: dict[int, int] = {}
        self.messages = self.attachments = self.metadata = self.orphaned = 0

    def start(self, profile: str = "") -> None:
        if not self.started:
            self.writer.start(profile=profile, library="trackreplay recover")
            self.started = True

    def schema(self, record: Schema) -> None:
        if record.id not in self.schemas:
            self.schemas[record.id] = self.writer.register_schema(record.name, record.encoding, record.data)

    def channel(self, record: Channel) -> int | None:
        if record.id not in self.channels:
            if record.schema_id != 0 and record.schema_id not in self.schemas:
                lost = self.summary_schemas.get(record.schema_id)
                if lost is None:
                    return None  # its schema was lost: the channel's messages cannot be decoded
                self.schema(lost)
            self.topics[record.id] = record.topic
            self.channels[record.id] = self.writer.register_channel(
                record.topic, record.message_encoding, self.schemas.get(record.schema_id, 0), dict(record.metadata))
        return self.channels[record.id]

    def message(self, record: Message) -> None:
        cid = self.channels.get(record.channel_id)
        if cid is None and record.channel_id in self.summary_channels:
            cid = self.channel(self.summary_channels[record.channel_id])
        if cid is None:
            self.orphaned += 1
            return
        data = record.data
        if self.frames is not None and self.topics.get(record.channel_id) in (T.ANNOTATIONS_INIT, T.GROUNDTRUTH):
            data = self._renumbered(self.topics[record.channel_id], data)
            if data is None:
                return
        self.writer.add_message(cid, record.log_time, data, record.publish_time, record.sequence)
        self.messages += 1

    def _renumbered(self, topic: str, data: bytes) -> bytes | None:
        """Marks and ground truth count images from the log's start: after lost images, each is
        renumbered to the image at its own time, and dropped when that image was lost."""
        assert self.frames is not None
        if topic == T.GROUNDTRUTH:
            gt = m.GroundTruthFrame()
            gt.ParseFromString(data)
            if gt.t_ns not in self.frames:
                self.dropped += 1
                return None
            gt.frame = self.frames[gt.t_ns]
            return gt.SerializeToString()
        marks = m.InitAnnotations()
        marks.ParseFromString(data)
        out = m.InitAnnotations(timestamp=marks.timestamp)
        for region in marks.regions:
            if region.t_ns not in self.frames:
                self.dropped += 1
                continue
            kept = out.regions.add()
            kept.CopyFrom(region)
            kept.frame = self.frames[region.t_ns]
        return out.SerializeToString() if out.regions else None

    def add(self, record) -> None:
        if isinstance(record, Header):
            self.start(record.profile)
            return
        self.start()
        if isinstance(record, Schema):
            self.schema(record)
        elif isinstance(record, Channel):
            self.channel(record)
        elif isinstance(record, Message):
            self.message(record)
        elif isinstance(record, Attachment):
            self.writer.add_attachment(record.create_time, record.log_time, record.name, record.media_type, record.data)
            self.attachments += 1
        elif isinstance(record, Metadata):
            self.writer.add_metadata(record.name, dict(record.metadata))
            self.metadata += 1


def _surviving_frames(data, summary: tuple[dict[int, Schema], dict[int, Channel]]) -> dict[int, int] | None:
    """Each intact image's log time -> its number among the intact images, when a damaged stretch
    lost any record; None for an intact file."""
    channels = {cid: ch.topic for cid, ch in summary[1].items()}
    times: list[int] = []
    damaged = False
    for item in scan(data):
        if isinstance(item, Damage):
            damaged = True
        for record in item.records if isinstance(item, ChunkRecords) else (item,):
            if isinstance(record, Channel):
                channels[record.id] = record.topic
            elif isinstance(record, Message) and channels.get(record.channel_id) == T.CAMERA_IMAGE:
                times.append(record.log_time)
    if not damaged or not times:  # (no /camera/image: marks counting another topic's frames stay as they are)
        return None
    return {t: k for k, t in enumerate(sorted(times))}


def _rewrite(data, dst: BinaryIO, source: Path) -> RecoverReport:
    summary = summary_definitions(data)
    copy = _Copy(dst, summary, _surviving_frames(data, summary))
    damage: list[Damage] = []
    ended = False
    for item in scan(data):
        if isinstance(item, Damage):
            damage.append(item)
        elif isinstance(item, ChunkRecords):
            for record in item.records:
                copy.add(record)
        elif isinstance(item, Footer):
            ended = True
        else:
            copy.add(item)
    copy.start()
    copy.writer.add_metadata(RECORD_NAME, provenance({"log": source}))  # this step's own, after the source's records
    copy.writer.finish()
    error = None
    if damage:
        error = "; ".join(f"{d.reason} at bytes {d.start}-{d.end} of {len(data)}" for d in damage[:3])
        if len(damage) > 3:
            error += f"; and {len(damage) - 3} more damaged stretch(es)"
    elif not ended:
        error = f"the file ends without a footer after byte {len(data)}"
    if copy.orphaned:
        error = (error + "; " if error else "") + f"{copy.orphaned} intact message(s) dropped: their channel definition was lost"
    if copy.dropped:
        error = (error + "; " if error else "") + (f"{copy.dropped} mark(s) or ground-truth frame(s) dropped with their "
                                                   "lost images (the rest renumbered to the images kept)")
    return RecoverReport(copy.messages, error is None, error, copy.attachments, copy.metadata, tuple(damage), copy.orphaned,
                         copy.dropped)
