"""Add side inputs to an existing log: ``trackreplay merge LOG --encoders CSV | --groundtruth FILE |
--calibration FILE … -o OUT``.

The inputs are read by ``record``'s own readers (so a file ``record`` takes, ``merge`` takes, with
the same one-sentence errors), all checked before ``OUT`` exists. ``OUT`` is a new log: every record
of ``LOG`` copied as it is (schemas, channels, messages, attachments, metadata), then the new
topics; ``LOG`` itself is never written. Encoder readings go at their own times; the lens table and
the calibration at the first image's time (as ``record`` writes them); ground truth frame by frame
at its images' times (file frame k = the log's k-th image, ``gt_first_frame`` shifting it as in
``record``). A topic the log already has is refused (``filter --exclude`` it first): two sources for
one topic would contradict each other.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mcap.reader import make_reader
from mcap_protobuf.schema import register_schema

from trackreplay.recorder.annotate import _frame_times
from trackreplay.recorder.atomic import replace_when_done
from trackreplay.recorder.log_summary import log_file, read_summary, topic_counts
from trackreplay.recorder.mcap_copy import McapCopy, damage_is_an_error, require_intact
from trackreplay.recorder.provenance import RECORD_NAME, provenance
from trackreplay.recorder.record import _warnings
from trackreplay.recorder.sources.encoders import read_encoders, read_lens_table
from trackreplay.recorder.sources.groundtruth import read_groundtruth
from trackreplay.recorder.sources.stereo import load_calibration, pose_message
from trackreplay.schemas import topics as T
from trackreplay.schemas.errors import OutputError, SourceError
from trackreplay.schemas.records import GroundTruthFrame


@dataclass
class MergeReport:
    added: dict[str, int] = field(default_factory=dict)  # topic -> messages added
    warnings: tuple[str, ...] = ()


@dataclass(frozen=True)
class MergeInputs:
    encoders: Path | None = None
    lens_table: Path | None = None
    groundtruth: Path | None = None
    gt_format: str = "auto"
    gt_first_frame: int = 0
    calibration: Path | None = None

    def given(self) -> dict[str, Path]:
        return {k: v for k, v in (("encoders", self.encoders), ("lens_table", self.lens_table),
                                  ("groundtruth", self.groundtruth), ("calibration", self.calibration)) if v is not None}


def _image_topic(src: Path, present: dict[str, int]) -> tuple[str, bool]:
    """The topic frames are counted on, and whether the log is a stereo pair."""
    for topic, stereo in ((T.CAMERA_IMAGE, False), (T.STEREO_LEFT_IMAGE, True)):
        if present.get(topic):
            return topic, stereo
    raise SourceError(f"{src} has no images on {T.CAMERA_IMAGE} or {T.STEREO_LEFT_IMAGE}: ground truth, a lens table "
                      f"and a calibration are placed by its frames")


def _messages(src: Path, inputs: MergeInputs, present: dict[str, int]) -> tuple[list[tuple[str, int, Any]], tuple[str, ...]]:
    """Every new message as (topic, log time, protobuf), read and checked before anything is written."""
    out: list[tuple[str, int, Any]] = []
    warnings: tuple[str, ...] = ()
    if inputs.encoders is not None:
        out += [(T.PTZ_ENCODERS, r.t_ns, r.to_pb()) for r in read_encoders(inputs.encoders)]
    if inputs.lens_table is None and inputs.groundtruth is None and inputs.calibration is None:
        return out, warnings
    image_topic, stereo = _image_topic(src, present)
    times, sizes = _frame_times(src, image_topic, {0})
    t0 = times[0]
    size = sizes.get(0)
    if inputs.lens_table is not None:
        lens = read_lens_table(inputs.lens_table, *(size or (None, None)))
        if size is not None and (lens.width, lens.height) != size:
            raise SourceError(f"the lens table {inputs.lens_table} is for {lens.width}x{lens.height} images but {src}'s "
                              f"are {size[0]}x{size[1]}")
        out.append((T.PTZ_LENS_TABLE, t0, lens.to_pb(t0)))
    if inputs.calibration is not None:
        calib = load_calibration(inputs.calibration, stereo=stereo)
        if size is not None and (calib.left.width, calib.left.height) != size:
            raise SourceError(f"calibration {inputs.calibration} is for {calib.left.width}x{calib.left.height} images but "
                              f"{src}'s are {size[0]}x{size[1]}")
        if stereo:
            out += [(T.STEREO_LEFT_CALIBRATION, t0, calib.left.to_pb(t0, "left")),
                    (T.STEREO_RIGHT_CALIBRATION, t0, calib.right.to_pb(t0, "right"))]
            if calib.pose is not None:
                out.append((T.STEREO_POSE, t0, pose_message(calib.pose, t0)))
        else:
            out.append((T.CAMERA_CALIBRATION, t0, calib.left.to_pb(t0, "camera")))
    if inputs.groundtruth is not None:
        gt = read_groundtruth(inputs.groundtruth, inputs.gt_format, inputs.gt_first_frame)
        if gt.normalised:
            if size is None:
                raise SourceError(f"{inputs.groundtruth} gives normalised positions and {src}'s image size is not known here")
            gt = gt.in_pixels(*size)
        for frame, t in enumerate(times):
            objects = gt.objects_at(frame)
            if objects is not None:
                out.append((T.GROUNDTRUTH, t, GroundTruthFrame(frame, t, objects).to_pb()))
        warnings = _warnings(gt, len(times))
    return out, warnings


def merge(src: Path, out: Path, inputs: MergeInputs) -> MergeReport:
    """Write ``out``: ``src`` with ``inputs`` added as new topics (see the module's docstring)."""
    src = log_file(src)  # (a ROS 2 bag folder: the .mcap in it)
    out = Path(out)
    if not inputs.given():
        raise SourceError("merge needs a side input to add: --encoders, --lens-table, --groundtruth or --calibration")
    if out.exists() and os.path.samefile(out, src) or out.resolve() in {p.resolve() for p in inputs.given().values()}:
        raise SourceError(f"output {out} is one of the inputs; merge writes a new log and never overwrites one")
    if not out.parent.is_dir():
        raise OutputError(f"cannot write {out}: output folder {out.parent} does not exist")
    summary = read_summary(src)
    present = topic_counts(summary)
    require_intact(src)
    new, warnings = _messages(src, inputs, present)
    clash = sorted({t for t, _, _ in new if t in present})
    if clash:
        raise SourceError(f"{src} already has {', '.join(clash)}; merge adds topics a log lacks (`trackreplay filter "
                          f"{src} OUT --exclude {clash[0]}` drops the old one first)")
    report = MergeReport(warnings=warnings)
    with replace_when_done(out) as dst, open(src, "rb") as fh, damage_is_an_error(src):
        source = make_reader(fh)
        copy = McapCopy(source, dst)
        writer = copy.writer
        for schema, channel, msg in source.iter_messages(log_time_order=False):
            writer.add_message(copy.channel_id(schema, channel), msg.log_time, msg.data, msg.publish_time, msg.sequence)
        copy.copy_attachments_and_metadata(source)
        writer.add_metadata(RECORD_NAME, provenance({"log": src, **inputs.given()}))
        schemas: dict[str, int] = {}
        channels: dict[str, int] = {}
        for topic, t, pb in sorted(new, key=lambda m: m[1]):
            if topic not in channels:
                name = pb.DESCRIPTOR.full_name
                if name not in schemas:
                    schemas[name] = register_schema(writer, type(pb))
                channels[topic] = writer.register_channel(topic, "protobuf", schemas[name])
            seq = report.added.get(topic, 0)
            writer.add_message(channels[topic], t, pb.SerializeToString(), t, seq)
            report.added[topic] = seq + 1
        writer.finish()
    return report
