"""Sources -> one MCAP log, streamed frame by frame in capture-time order.

Every side input (calibration, encoders, lens table, annotations, timestamps) is checked
before the output is created. If a source fails mid-way (e.g. a wrong-size image) the
partial output is removed; an interrupted recording (Ctrl-C) keeps a valid log of what was
recorded; a killed one leaves complete chunks that ``recover`` salvages.
"""

from __future__ import annotations

import sys
from collections.abc import Iterator
from dataclasses import dataclass, field, fields
from pathlib import Path

from tqdm import tqdm

from trackreplay.recorder.image_codec import ENCODINGS, compressed_image, image_message
from trackreplay.recorder.sources.base import FrameClock, ImageFrame, check_fps, read_timestamps
from trackreplay.recorder.sources.encoders import read_encoders, read_lens_table
from trackreplay.recorder.sources.ground_plane import read_ground_plane
from trackreplay.recorder.sources.ground_plane_truth import fit_truth_plane, truth_plane
from trackreplay.recorder.sources.groundtruth import GroundTruthTable, read_groundtruth
from trackreplay.recorder.sources.images import check_count, list_images, read_images
from trackreplay.recorder.sources.stereo import Calibration, StereoSource, load_calibration, pose_message
from trackreplay.recorder.sources.video import VideoLosses, frame_count_hint, read_video, video_clock
from trackreplay.recorder.writer import LogWriter
from trackreplay.schemas import topics as T
from trackreplay.schemas.errors import SourceError
from trackreplay.schemas.ground_plane import GroundPlaneCalibration
from trackreplay.schemas.records import GroundTruthFrame, PtzReading


@dataclass(frozen=True)
class RecordTopics:
    """Topic names written by ``record`` (defaults: the log contract's)."""

    camera_image: str = T.CAMERA_IMAGE
    camera_calibration: str = T.CAMERA_CALIBRATION
    left_image: str = T.STEREO_LEFT_IMAGE
    right_image: str = T.STEREO_RIGHT_IMAGE
    left_calibration: str = T.STEREO_LEFT_CALIBRATION
    right_calibration: str = T.STEREO_RIGHT_CALIBRATION
    encoders: str = T.PTZ_ENCODERS
    lens_table: str = T.PTZ_LENS_TABLE
    groundtruth: str = T.GROUNDTRUTH
    ground_plane: str = T.CAMERA_GROUND_PLANE
    stereo_pose: str = T.STEREO_POSE

    @classmethod
    def keys(cls) -> tuple[str, ...]:
        return tuple(f.name for f in fields(cls))


@dataclass(frozen=True)
class RecordReport:
    path: Path
    frames: int
    messages: int
    topics: dict[str, int] = field(default_factory=dict)
    start_ns: int | None = None
    end_ns: int | None = None
    warnings: tuple[str, ...] = ()
    frames_lost: bool = False  # the source had frames that could not be decoded (named in warnings)
    notes: tuple[str, ...] = ()  # what the recording derived (a ground plane fitted to the truth, and how well)


def _image_pb(frame: ImageFrame, encoding: str, frame_id: str):
    if frame.data is not None:
        return compressed_image(frame.data, frame.fmt, frame.t_ns, frame_id)
    return image_message(frame.pixels, encoding, frame.t_ns, frame_id=frame_id)


def _clock(video, images, stereo, fps, timestamps, t0_ns) -> FrameClock:
    if timestamps is not None:
        return FrameClock(timestamps=read_timestamps(timestamps), timestamps_path=str(timestamps))
    if video is not None:
        return video_clock(video, fps, t0_ns)
    if stereo is not None and not Path(stereo[0]).is_dir() and fps is None:
        return video_clock(stereo[0], None, t0_ns)
    return FrameClock(fps=fps, t0_ns=t0_ns)


class _Recording:
    """The output log plus per-topic counts."""

    def __init__(self, writer: LogWriter) -> None:
        self.writer = writer
        self.counts: dict[str, int] = {}
        self.start: int | None = None
        self.end: int | None = None

    def write(self, topic: str, message, t_ns: int) -> None:
        self.writer.write(topic, message, t_ns)
        self.counts[topic] = self.counts.get(topic, 0) + 1
        self.start = t_ns if self.start is None else min(self.start, t_ns)
        self.end = t_ns if self.end is None else max(self.end, t_ns)


def record(
    out_path: str | Path,
    *,
    video: str | Path | None = None,
    images: str | Path | None = None,
    fps: float | None = None,
    timestamps: str | Path | None = None,
    t0_ns: int = 0,
    stereo: tuple[str | Path, str | Path] | None = None,
    calibration: str | Path | None = None,
    encoders: str | Path | None = None,
    lens_table: str | Path | None = None,
    groundtruth: str | Path | None = None,
    gt_format: str = "auto",
    gt_first_frame: int = 0,
    ground_plane: str | Path | None = None,
    ground_plane_from_truth: bool = False,
    encoding: str = "jpeg",
    flush_every: int = 30,
    topics: RecordTopics = RecordTopics(),
    quiet: bool = False,
) -> RecordReport:
    """Record one image source (``video``, ``images`` or ``stereo``) and side inputs to ``out_path``.

    Frame times: ``timestamps`` file values as they are, else ``t0_ns + i / fps`` (``fps``
    defaults to a video's own rate). JPEG/PNG files keep their bytes; video frames and other
    image files are encoded as ``encoding``. ``ground_plane_from_truth``: the ground plane is fitted
    to the truth's foot points and ground positions (:mod:`.sources.ground_plane_truth`).
    """
    out = Path(out_path)
    given = [name for name, v in (("video", video), ("images", images), ("stereo", stereo)) if v is not None]
    if len(given) != 1:
        raise SourceError(f"record needs exactly one image source (--video, --images or --stereo), got {len(given) or 'none'}")
    if encoding not in ENCODINGS:
        raise SourceError(f"image encoding must be one of {', '.join(ENCODINGS)}, not {encoding!r}")
    if fps is not None:
        check_fps(fps)

    # Everything that can be checked is checked before the output exists.
    clock = _clock(video, images, stereo, fps, timestamps, t0_ns)
    total: int | None = None
    pair: StereoSource | None = None
    if images is not None:
        files = list_images(images)
        check_count(files, clock, images)
        total = len(files)
    elif stereo is not None:
        pair = StereoSource(Path(stereo[0]), Path(stereo[1]))
        total = pair.check(clock)
    else:
        total = frame_count_hint(video)
    calib = load_calibration(calibration, stereo=pair is not None) if calibration is not None else None
    if encoders is not None:
        for _ in read_encoders(encoders):
            pass
    if lens_table is not None:
        read_lens_table(lens_table)
    gt = read_groundtruth(groundtruth, gt_format, gt_first_frame) if groundtruth is not None else None
    plane, plane_warnings = read_ground_plane(ground_plane) if ground_plane is not None else (None, ())
    if ground_plane_from_truth and (gt is None or ground_plane is not None):
        raise SourceError("--ground-plane-from-truth fits the plane to the ground truth: give --groundtruth, and no --ground-plane")
    truth_fit = fit_truth_plane(gt) if ground_plane_from_truth and gt is not None else None
    inputs = {Path(p).resolve() for p in (video, images, timestamps, calibration, encoders, lens_table, groundtruth, ground_plane, *(stereo or ())) if p is not None}
    if out.resolve() in inputs:
        raise SourceError(f"output {out} is also an input; choose another output path")
    if not out.parent.is_dir():
        raise SourceError(f"output folder {out.parent} does not exist")

    losses = VideoLosses(str(video))
    if pair is not None:
        bundles: Iterator[tuple[ImageFrame, ImageFrame | None]] = pair.pairs(clock)
    else:
        mono = read_images(images, clock) if images is not None else read_video(video, clock, losses)
        bundles = ((f, None) for f in mono)

    try:
        writer = LogWriter(out, flush_every=flush_every, sources={
            "video": video, "images": images, "stereo_left": stereo[0] if stereo else None,
            "stereo_right": stereo[1] if stereo else None, "timestamps": timestamps, "calibration": calibration,
            "encoders": encoders, "lens_table": lens_table, "groundtruth": groundtruth, "ground_plane": ground_plane})
    except OSError as err:
        raise SourceError(f"cannot write output {out} ({err.strerror})") from None
    rec = _Recording(writer)
    frames = 0
    sources = 0  # the source's frames up to the last one read (more than `frames` when some did not decode)
    try:
        with tqdm(total=total, unit="frame", desc=out.name, file=sys.stderr, disable=quiet or not sys.stderr.isatty()) as bar:
            ptz = read_encoders(encoders) if encoders is not None else iter(())
            pending: PtzReading | None = next(ptz, None)
            for left, right in bundles:
                t = left.t_ns
                while pending is not None and pending.t_ns <= t:
                    rec.write(topics.encoders, pending.to_pb(), pending.t_ns)
                    pending = next(ptz, None)
                if frames == 0:
                    plane = truth_plane(truth_fit, *left.size) if truth_fit is not None else plane
                    _write_once(rec, topics, left, right is not None, calib, lens_table, plane)
                    gt = gt.in_pixels(*left.size) if gt is not None else None  # (TrackNet's normalised centres)
                if right is None:
                    rec.write(topics.camera_image, _image_pb(left, encoding, "camera"), t)
                else:
                    rec.write(topics.left_image, _image_pb(left, encoding, "left"), t)
                    rec.write(topics.right_image, _image_pb(right, encoding, "right"), t)
                if gt is not None:
                    objects = gt.objects_at(left.index)
                    if objects is not None:
                        # the log's frame number (its image's position), not the source's: a video frame that
                        # did not decode leaves no image, and the truth of the frames after it stays with them
                        rec.write(topics.groundtruth, GroundTruthFrame(frames, t, objects).to_pb(), t)
                frames += 1
                sources = left.index + 1
                bar.update(1)
            while pending is not None:
                rec.write(topics.encoders, pending.to_pb(), pending.t_ns)
                pending = next(ptz, None)
    except KeyboardInterrupt:
        writer.close()  # keep what was recorded as a valid log
        raise
    except BaseException:
        writer.discard()  # a half-recorded log of a broken source would mislead; an earlier `out` stays
        raise
    writer.close()
    lost = losses.warnings() if video is not None else ()
    return RecordReport(out, frames, writer.messages_written, dict(rec.counts), rec.start, rec.end,
                        plane_warnings + lost + _warnings(gt, sources), frames_lost=bool(lost),
                        notes=(truth_fit.summary(str(groundtruth)),) if truth_fit is not None else ())


def _write_once(rec: _Recording, topics: RecordTopics, first: ImageFrame, stereo: bool, calib: Calibration | None, lens_table,
                plane: GroundPlaneCalibration | None = None) -> None:
    """Calibration, lens table and ground plane, at the first frame's time."""
    t = first.t_ns
    w, h = first.size
    if calib is not None:
        if (calib.left.width, calib.left.height) != (w, h):
            raise SourceError(f"calibration {calib.path} is for {calib.left.width}x{calib.left.height} images but "
                              f"{first.where} is {w}x{h}")
        if stereo:
            rec.write(topics.left_calibration, calib.left.to_pb(t, "left"), t)
            rec.write(topics.right_calibration, calib.right.to_pb(t, "right"), t)
            if calib.pose is not None:
                rec.write(topics.stereo_pose, pose_message(calib.pose, t), t)
        else:
            rec.write(topics.camera_calibration, calib.left.to_pb(t, "camera"), t)
    if lens_table is not None:
        lens = read_lens_table(lens_table, w, h)
        if (lens.width, lens.height) != (w, h):  # a replay would refuse the log (its camera model is for other pixels)
            raise SourceError(f"the lens table {lens_table} is for {lens.width}x{lens.height} images but {first.where} is {w}x{h}")
        rec.write(topics.lens_table, lens.to_pb(t), t)
    if plane is not None:
        if (plane.width, plane.height) != (w, h):
            raise SourceError(f"the ground plane is for {plane.width}x{plane.height} images but {first.where} is {w}x{h}")
        rec.write(topics.ground_plane, plane.to_pb(t), t)


def _warnings(gt: GroundTruthTable | None, frames: int) -> tuple[str, ...]:
    if gt is not None and gt.last_frame >= frames:
        extra = sum(1 for f in gt.frames if f >= frames)
        return (f"{gt.path} annotates {extra} frame(s) after the last recorded frame ({frames}); they were not written",)
    if gt is not None and gt.format in ("otb", "vot") and len(gt.frames) < frames:  # (line k = frame k)
        first, last = min(gt.frames), gt.last_frame
        return (f"{gt.path} has {len(gt.frames)} boxes for {frames} recorded frames: they were taken as frames "
                f"{first}-{last} (line 1 = frame {first}); frames without a box have no ground truth "
                "(a truth that starts later in the sequence, as OTB's David at image 300: --gt-first-frame 299)",)
    return ()
