"""Add ``/annotations/init`` to an existing log without changing anything else in it."""

from __future__ import annotations

import csv
import dataclasses
import io
import math
from dataclasses import dataclass
from pathlib import Path

from mcap.reader import make_reader
from mcap_protobuf.schema import register_schema

from trackreplay.recorder.log_summary import log_file, read_summary, require_topic, topic_counts
from trackreplay.recorder.atomic import replace_when_done
from trackreplay.recorder.mcap_copy import McapCopy, damage_is_an_error, require_intact
from trackreplay.recorder.provenance import RECORD_NAME, provenance
from trackreplay.recorder.sources.base import read_text
from trackreplay.schemas import messages as m
from trackreplay.schemas import topics as T
from trackreplay.schemas.errors import SourceError
from trackreplay.schemas.records import InitRegion, init_annotations_pb


@dataclass(frozen=True)
class Mark:
    """A box the user drew: top-left ``(x, y)`` and size, on ``frame``."""

    frame: int
    x: float
    y: float
    w: float
    h: float
    label: str = "target"
    source: str = ""  # where it was given (a CSV's file:line), for messages; "" for --box


def parse_box(text: str, frame: int, label: str) -> Mark:
    try:
        x, y, w, h = (float(v) for v in text.split(","))
    except ValueError:
        raise SourceError(f"box {text!r} must be four numbers x,y,w,h (top-left corner, width, height)") from None
    if not all(math.isfinite(v) for v in (x, y, w, h)):
        raise SourceError(f"box {text!r} must be four finite numbers x,y,w,h (nan or inf is no place in an image)")
    if w <= 0 or h <= 0:
        raise SourceError(f"box {text!r} has a non-positive width or height")
    if w < 1 or h < 1:
        raise SourceError(f"box {text!r} is under a pixel wide or high: it covers no whole pixel of the picture")
    return Mark(frame, x, y, w, h, label)


def read_marks_csv(path: Path, default_label: str) -> list[Mark]:
    """Rows ``frame,x,y,w,h[,label]``; a header row is allowed."""
    marks: list[Mark] = []
    try:
        with io.StringIO(read_text(path), newline="") as fh:
            for line_no, row in enumerate(csv.reader(fh), start=1):
                cells = [c.strip() for c in row]
                if not cells or not any(cells) or cells[0].startswith("#"):
                    continue
                if line_no == 1 and cells[0].lower() == "frame":
                    continue
                if len(cells) not in (5, 6):
                    raise SourceError(f"{path}:{line_no}: expected frame,x,y,w,h[,label], got {len(cells)} columns")
                try:
                    frame = int(cells[0])
                except ValueError:
                    raise SourceError(f"{path}:{line_no}: frame {cells[0]!r} is not an integer") from None
                try:
                    mark = parse_box(",".join(cells[1:5]), frame, cells[5] if len(cells) == 6 else default_label)
                except SourceError as err:
                    raise SourceError(f"{path}:{line_no}: {err}") from None
                marks.append(dataclasses.replace(mark, source=f"{path}:{line_no}"))
    except FileNotFoundError:
        raise SourceError(f"{path} does not exist") from None
    if not marks:
        raise SourceError(f"{path} holds no marks")
    return marks


def _frame_times(path: Path, image_topic: str) -> list[int]:
    with open(path, "rb") as fh, damage_is_an_error(path):
        return [msg.log_time for _, _, msg in make_reader(fh).iter_messages(topics=[image_topic], log_time_order=True)]


def annotate(src: Path, out: Path, marks: list[Mark], image_topic: str = T.CAMERA_IMAGE) -> list[InitRegion]:
    """Copy ``src`` to ``out`` record for record and add one ``/annotations/init`` message.

    ``out`` may equal ``src``: the new log is written beside it and renamed over it only
    once complete, so an interruption never damages the original.
    """
    src = log_file(src)  # (a ROS 2 bag folder: the .mcap in it)
    summary = read_summary(src)  # missing, not MCAP or truncated: one-sentence errors
    require_topic(src, summary, image_topic)
    require_intact(src)
    times = _frame_times(src, image_topic)
    regions = []
    for mk in marks:
        if not 0 <= mk.frame < len(times):
            raise SourceError(f"{src} has no frame {mk.frame} on {image_topic} (it has {len(times)} frames)")
        regions.append(InitRegion(mk.frame, times[mk.frame], mk.x + mk.w / 2, mk.y + mk.h / 2, mk.w, mk.h, mk.label))
    annotation = init_annotations_pb(regions, times[0])
    # Written as OUT.partial and renamed when complete (so --in-place never damages the original);
    # the file gets the usual permissions (umask), not a temporary file's 0600.
    with replace_when_done(out) as dst, open(src, "rb") as fh, damage_is_an_error(src):
        source = make_reader(fh)
        copy = McapCopy(source, dst)
        writer = copy.writer
        by_topic: dict[str, int] = {}
        for schema, channel, msg in source.iter_messages(log_time_order=False):
            cid = copy.channel_id(schema, channel)
            by_topic.setdefault(channel.topic, cid)
            writer.add_message(cid, msg.log_time, msg.data, msg.publish_time, msg.sequence)
        copy.copy_attachments_and_metadata(source)
        writer.add_metadata(RECORD_NAME, provenance({"log": src}, marks=str(len(regions))))
        cid = by_topic.get(T.ANNOTATIONS_INIT)  # append to an existing annotation channel
        if cid is None:
            cid = writer.register_channel(T.ANNOTATIONS_INIT, "protobuf", register_schema(writer, m.InitAnnotations))
        sequence = topic_counts(summary).get(T.ANNOTATIONS_INIT, 0)
        writer.add_message(cid, times[0], annotation.SerializeToString(), times[0], sequence)
        writer.finish()
    return regions
