"""Add ``/annotations/init`` to an existing log without changing anything else in it."""

from __future__ import annotations

import dataclasses
import io
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from mcap.reader import make_reader
from mcap_protobuf.schema import register_schema

from trackreplay.recorder.log_summary import log_file, read_summary, require_topic, topic_counts
from trackreplay.recorder.atomic import replace_when_done
from trackreplay.recorder.mcap_copy import McapCopy, damage_is_an_error, require_intact
from trackreplay.recorder.provenance import RECORD_NAME, provenance
from trackreplay.recorder.sources.base import CsvRows, read_text
from trackreplay.schemas import messages as m
from trackreplay.schemas import topics as T
from trackreplay.schemas.errors import SourceError
from trackreplay.schemas.records import GroundTruthFrame, GroundTruthObject, InitRegion, init_annotations_pb


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
            for line_no, row in enumerate(CsvRows(fh, path), start=1):
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


def _truth_box(obj: GroundTruthObject, mark_size: float) -> tuple[float, float, float, float] | None:
    """Centre and size to mark for a truth object: its box, an ``mark_size`` square round a point, or
    None when the truth does not place it visibly (``visible`` false, or no finite centre)."""
    if obj.visible is False or obj.x is None or obj.y is None or not (math.isfinite(obj.x) and math.isfinite(obj.y)):
        return None
    if obj.w is not None and obj.h is not None and math.isfinite(obj.w) and math.isfinite(obj.h) and obj.w > 0 and obj.h > 0:
        return obj.x, obj.y, obj.w, obj.h
    return obj.x, obj.y, mark_size, mark_size


def read_truth_frames(log: Path, topic: str = T.GROUNDTRUTH) -> dict[int, tuple[GroundTruthObject, ...]]:
    """The log's ground truth by frame (``frame`` as recorded: the image's position in the log)."""
    src = log_file(log)
    require_topic(src, read_summary(src), topic)
    frames: dict[int, tuple[GroundTruthObject, ...]] = {}
    with open(src, "rb") as fh, damage_is_an_error(src):
        for _, _, msg in make_reader(fh).iter_messages(topics=[topic], log_time_order=True):
            gt = GroundTruthFrame.from_pb(m.GroundTruthFrame.FromString(msg.data))
            frames[gt.frame] = frames.get(gt.frame, ()) + gt.objects
    return frames


def marks_from_truth(log: Path, frame: int | None = None, mark_size: float = 12.0, label: str | None = None,
                     ids: Sequence[int] | None = None, topic: str = T.GROUNDTRUTH) -> list[Mark]:
    """Marks (top-left box) where the log's ground truth places its objects on ``frame``: a truth box
    as it is, a point truth (no size) as a ``mark_size`` x ``mark_size`` square round it — a benchmark's
    start from its first labelled frame (OTB, VOT, TrackNet) without hand arithmetic.

    ``frame`` None: the first frame where the truth places one of ``ids`` visibly (default: any
    object). ``ids`` None: every object visible on that frame; given: each must be visible there.
    ``label`` None: ``target``. The marks may reach past the picture: :func:`clip_mark` fits one."""
    if not (math.isfinite(mark_size) and mark_size >= 1):
        raise SourceError(f"the mark size round a point must be at least one pixel, not {mark_size!r}")
    truth = read_truth_frames(log, topic)
    wanted = None if ids is None else [int(i) for i in ids]

    def usable(objs: tuple[GroundTruthObject, ...]) -> dict[int, tuple[float, float, float, float]]:
        boxes = {o.id: _truth_box(o, mark_size) for o in objs if wanted is None or o.id in wanted}
        return {i: b for i, b in boxes.items() if b is not None}

    if frame is None:
        frame = next((f for f in sorted(truth) if usable(truth[f])), None)
        if frame is None:
            who = "object" if wanted is None else "object " + ", ".join(map(str, wanted))
            raise SourceError(f"{log}: the ground truth places no {who} visibly on any of its {len(truth)} frames")
    if frame not in truth:
        raise SourceError(f"{log}: the ground truth does not label frame {frame} "
                          f"(it labels {len(truth)} frames, {min(truth, default=0)}-{max(truth, default=0)})")
    boxes = usable(truth[frame])
    missing = [] if wanted is None else [i for i in wanted if i not in boxes]
    if missing or not boxes:
        seen = ", ".join(str(o.id) for o in truth[frame] if _truth_box(o, mark_size)) or "none"
        who = f"object {', '.join(map(str, missing))}" if missing else "any object"
        raise SourceError(f"{log}: the ground truth does not place {who} visibly on frame {frame} "
                          f"(objects visible there: {seen})")
    order = wanted if wanted is not None else sorted(boxes)
    return [Mark(frame, boxes[i][0] - boxes[i][2] / 2, boxes[i][1] - boxes[i][3] / 2, boxes[i][2], boxes[i][3],
                 label or "target", source=f"{log}: ground truth of object {i} on frame {frame}") for i in order]


def clip_mark(mark: Mark, width: int, height: int) -> Mark:
    """``mark`` cut to the ``width`` x ``height`` picture (a truth box or a square round a point near
    the border may reach past it); refused when less than a pixel of it is inside."""
    x0, y0 = max(mark.x, 0.0), max(mark.y, 0.0)
    x1, y1 = min(mark.x + mark.w, float(width)), min(mark.y + mark.h, float(height))
    if x1 - x0 < 1 or y1 - y0 < 1:
        raise SourceError(f"{mark.source or 'the mark'}: the box {mark.x:g},{mark.y:g},{mark.w:g},{mark.h:g} on frame "
                          f"{mark.frame} lies outside the {width}x{height} picture")
    return dataclasses.replace(mark, x=x0, y=y0, w=x1 - x0, h=y1 - y0)


def _frame_times(path: Path, image_topic: str, sized: set[int] = frozenset()) -> tuple[list[int], dict[int, tuple[int, int]]]:
    """The frames' log times, and the picture size (width, height) of each frame in ``sized`` that a
    foxglove image holds (other encodings: not known here; ``replay`` checks its marks again)."""
    times: list[int] = []
    sizes: dict[int, tuple[int, int]] = {}
    with open(path, "rb") as fh, damage_is_an_error(path):
        for schema, _, msg in make_reader(fh).iter_messages(topics=[image_topic], log_time_order=True):
            if len(times) in sized and schema is not None:
                size = _picture_size(schema.name, msg.data)
                if size is not None:
                    sizes[len(times)] = size
            times.append(msg.log_time)
    return times, sizes


def _picture_size(schema: str, data: bytes) -> tuple[int, int] | None:
    """(width, height) of a foxglove RawImage or CompressedImage message, None when it does not say."""
    try:
        if schema == "foxglove.RawImage":
            raw = m.RawImage.FromString(data)
            return raw.width, raw.height
        if schema == "foxglove.CompressedImage":
            picture = cv2.imdecode(np.frombuffer(m.CompressedImage.FromString(data).data, np.uint8), cv2.IMREAD_UNCHANGED)
            return None if picture is None else (picture.shape[1], picture.shape[0])
    except Exception:  # an undecodable frame: `replay` names it as such
        return None
    return None


def check_mark_inside(mark: Mark, width: int, height: int) -> None:
    """Refuse a mark that does not lie inside the ``width`` x ``height`` picture of its frame (written
    so that nan fails too): a tracker would start on pixels that are not there."""
    if not (0 <= mark.x and 0 <= mark.y and mark.x + mark.w <= width and mark.y + mark.h <= height):
        raise SourceError(f"{mark.source or 'the mark'}: the box x,y,w,h = {mark.x:g},{mark.y:g},{mark.w:g},{mark.h:g} "
                          f"on frame {mark.frame} is not inside the {width}x{height} picture")


def annotate(src: Path, out: Path, marks: list[Mark], image_topic: str = T.CAMERA_IMAGE) -> list[InitRegion]:
    """Copy ``src`` to ``out`` record for record and add one ``/annotations/init`` message.

    ``out`` may equal ``src``: the new log is written beside it and renamed over it only
    once complete, so an interruption never damages the original.
    """
    src = log_file(src)  # (a ROS 2 bag folder: the .mcap in it)
    summary = read_summary(src)  # missing, not MCAP or truncated: one-sentence errors
    require_topic(src, summary, image_topic)
    require_intact(src)
    times, sizes = _frame_times(src, image_topic, {mk.frame for mk in marks})
    regions = []
    for mk in marks:
        if not 0 <= mk.frame < len(times):
            raise SourceError(f"{src} has no frame {mk.frame} on {image_topic} (it has {len(times)} frames)")
        if mk.frame in sizes:
            check_mark_inside(mk, *sizes[mk.frame])
        regions.append(InitRegion(mk.frame, times[mk.frame], mk.x + mk.w / 2, mk.y + mk.h / 2, mk.w, mk.h, mk.label))
    annotation = init_annotations_pb(regions, times[0])
    # Written as OUT.partial and renamed when complete (so --in-place never damages the original);
    # a new file gets the usual permissions (umask), one rewritten in place keeps its mode and owner.
    in_place = Path(out).exists() and Path(out).resolve() == src.resolve()
    with replace_when_done(out, in_place=in_place) as dst, open(src, "rb") as fh, damage_is_an_error(src):
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
