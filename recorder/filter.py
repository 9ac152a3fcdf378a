"""Cut a log to some topics and a time range: ``trackreplay filter LOG OUT --topic … --start/--end``.

Messages are copied as they are (schemas, channels, sequence numbers, metadata and attachments
too), so the new log is the old one over the kept range. Three kinds of topic need more than a
time window to stay usable on their own:

- **state** (written once: lens table, ground plane, camera calibration / CameraInfo): the last
  message before ``start`` is kept, at its own time, so the cut log is still calibrated;
- **PTZ encoders**: readings up to 1 s either side of the range are kept, so frames at its edges
  still have a reading on each side to interpolate between (as ``replay --start`` reads them);
- **marks** (``/annotations/init``) and **ground truth**: frame numbers count images from the log's
  start, so they are renumbered to the cut log's images; marks on frames outside it are dropped (and
  counted), wherever in time the mark message itself was written.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from mcap.reader import make_reader

from trackreplay.recorder.atomic import replace_when_done
from trackreplay.recorder.log_summary import log_file, read_summary, topic_counts
from trackreplay.recorder.provenance import RECORD_NAME, provenance
from trackreplay.recorder.mcap_copy import McapCopy, damage_is_an_error, require_intact
from trackreplay.schemas import messages as m
from trackreplay.schemas import topics as T
from trackreplay.schemas.errors import SourceError

STATE_SCHEMAS = ("trackreplay.LensTable", "trackreplay.GroundPlane", *m.CALIBRATION_SCHEMAS)
ENCODER_MARGIN_NS = 1_000_000_000


@dataclass
class FilterReport:
    kept: dict[str, int] = field(default_factory=dict)
    marks_dropped: int = 0


def filter_log(src: Path, out: Path, topics: list[str] | None = None, start_ns: int | None = None,
               end_ns: int | None = None, image_topic: str | None = None) -> FilterReport:
    """Write ``out``: ``src``'s ``topics`` (all when None) with ``start_ns <= log_time < end_ns``
    (absolute ns); ``image_topic`` is the topic marks count frames on (default: /camera/image)."""
    src = log_file(src)  # (a ROS 2 bag folder: the .mcap in it)
    summary = read_summary(src)
    require_intact(src)
    present = topic_counts(summary)
    for topic in topics or ():
        if topic not in present:
            raise SourceError(f"{src} has no topic {topic}; topics present: {', '.join(sorted(present))}")
    keep = set(topics) if topics else set(present)
    schemas = {sid: s.name for sid, s in summary.schemas.items()}
    lo = start_ns if start_ns is not None else -1
    hi = end_ns if end_ns is not None else 2**63
    image_topic = image_topic or T.CAMERA_IMAGE
    report = FilterReport()

    with open(src, "rb") as fh, damage_is_an_error(src):
        reader = make_reader(fh)
        # Pass 1: the last state message before the range, and which images are kept (for marks).
        last_state: dict[int, tuple] = {}
        first_image = None
        kept_images = 0
        index = 0
        for schema, channel, msg in reader.iter_messages(log_time_order=True):
            if channel.topic == image_topic:
                if lo <= msg.log_time < hi:
                    first_image = index if first_image is None else first_image
                    kept_images += 1
                index += 1
            elif msg.log_time < lo and schema is not None and schema.name in STATE_SCHEMAS:
                last_state[channel.id] = (msg.log_time, msg.sequence)

    with replace_when_done(out) as dst, open(src, "rb") as fh, damage_is_an_error(src):
        reader = make_reader(fh)
        copy = McapCopy(reader, dst)
        writer = copy.writer
        for schema, channel, msg in reader.iter_messages(log_time_order=True):
            if channel.topic not in keep:
                continue
            name = schemas.get(channel.schema_id, "")
            t = msg.log_time
            if name == "trackreplay.PtzEncoders":
                inside = lo - ENCODER_MARGIN_NS <= t < hi + ENCODER_MARGIN_NS
            elif name in STATE_SCHEMAS and t < lo:
                inside = last_state.get(channel.id) == (t, msg.sequence)
            elif name == "trackreplay.InitAnnotations":
                # Marks are kept by the frames they mark, not by when they were written (annotate
                # writes them at the first frame's time): renumbered below, at the cut's start at the earliest
                inside, t = True, min(max(t, lo), hi - 1)
            else:
                inside = lo <= t < hi
            if not inside:
                continue
            data = msg.data
            if name == "trackreplay.InitAnnotations":
                data, dropped = _renumber_marks(data, first_image or 0, kept_images)
                report.marks_dropped += dropped
                if data is None:
                    continue
            elif name == "trackreplay.GroundTruthFrame" and first_image:
                data = _renumber_truth(data, first_image)  # it counts frames as marks do
            writer.add_message(copy.channel_id(schema, channel), t, data, msg.publish_time, msg.sequence)
            report.kept[channel.topic] = report.kept.get(channel.topic, 0) + 1
        copy.copy_attachments_and_metadata(reader)
        cut = {k: str(v) for k, v in (("start_ns", start_ns), ("end_ns", end_ns)) if v is not None}
        writer.add_metadata(RECORD_NAME, provenance({"log": src}, topics=",".join(sorted(keep)), **cut))  # this step's own
        writer.finish()
    return report


def _renumber_marks(data: bytes, first: int, count: int) -> tuple[bytes | None, int]:
    pb = m.InitAnnotations()
    pb.ParseFromString(data)
    kept = [r for r in pb.regions if first <= r.frame < first + count]
    dropped = len(pb.regions) - len(kept)
    if not kept:
        return None, dropped
    out = m.InitAnnotations(timestamp=pb.timestamp)
    for r in kept:
        region = out.regions.add()
        region.CopyFrom(r)
        region.frame = r.frame - first
    return out.SerializeToString(), dropped


def _renumber_truth(data: bytes, first: int) -> bytes:
    pb = m.GroundTruthFrame()
    pb.ParseFromString(data)
    pb.frame -= first
    return pb.SerializeToString()
