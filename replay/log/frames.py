"""Frame bundles from a log: mono frames, stereo pairs by equal log_time, PTZ at frame time."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field

from trackreplay.schemas import topics as T
from trackreplay.schemas.errors import LogError
from trackreplay.schemas.messages import CALIBRATION_SCHEMAS, IMAGE_SCHEMAS
from trackreplay.schemas.ground_plane import GroundPlaneCalibration
from trackreplay.schemas.records import InitRegion, LensTable, PtzReading
from trackreplay.trackers.frame import Frame
from trackreplay.trackers.geometry.ground_plane import GroundPlane
from trackreplay.trackers.geometry.ptz import PtzCamera
from trackreplay.trackers.geometry.rig_pose import RigPose
from trackreplay.trackers.geometry.stereo import StereoRig

from trackreplay.replay.log.decode import SizeMismatch, decode_image, projection
from trackreplay.replay.log.reader import LogMessage, LogReader


@dataclass(frozen=True)
class FrameTopics:
    """Which topics make a frame; ``right``/``ptz`` None means not used."""

    image: str = T.CAMERA_IMAGE
    right: str | None = None
    ptz: str | None = None
    lens: str = T.PTZ_LENS_TABLE
    hints: str = T.ANNOTATIONS_INIT
    ground_plane: str = T.CAMERA_GROUND_PLANE
    left_calibration: str = T.STEREO_LEFT_CALIBRATION
    right_calibration: str = T.STEREO_RIGHT_CALIBRATION
    stereo_pose: str = T.STEREO_POSE

    @classmethod
    def detect(cls, reader: LogReader, image: str | None = None,
               stereo: tuple[str, str] | None = None) -> FrameTopics:
        """The pair ``stereo`` or the topic ``image`` when given; else ``/camera/image``, else the
        ``/stereo/left|right/image`` pair, else the log's only image topic (any image schema: a ROS 2
        bag's ``sensor_msgs/msg/Image`` too); PTZ encoders when the log has them."""
        present = reader.topics()
        ptz = T.PTZ_ENCODERS if T.PTZ_ENCODERS in present else None
        if stereo is not None:
            for topic in stereo:
                require_image_topic(reader, topic)
            left_cal, right_cal = (calibration_topic(reader, t) for t in stereo)
            if left_cal and right_cal:  # a ROS 2 pair: each image topic's sibling camera_info
                return cls(image=stereo[0], right=stereo[1], ptz=ptz, left_calibration=left_cal,
                           right_calibration=right_cal)
            return cls(image=stereo[0], right=stereo[1], ptz=ptz)
        if image is None:
            image = choose_image_topic(reader)
        else:
            require_image_topic(reader, image)
        right = T.STEREO_RIGHT_IMAGE if image == T.STEREO_LEFT_IMAGE and T.STEREO_RIGHT_IMAGE in present else None
        return cls(image=image, right=right, ptz=ptz)


def _listed(reader: LogReader) -> str:
    return ", ".join(f"{t} ({info.schema or 'no schema'})" for t, info in sorted(reader.topics().items())) or "none"


def calibration_topic(reader: LogReader, image_topic: str) -> str | None:
    """The calibration beside ``image_topic`` by ROS convention (``/cam/left/image_rect`` ->
    ``/cam/left/camera_info``, a ``sensor_msgs/msg/CameraInfo`` or ``foxglove.CameraCalibration``)."""
    present = reader.topics()
    base = image_topic.rsplit("/", 1)[0]
    for name in ("camera_info", "calibration"):
        topic = f"{base}/{name}"
        if topic in present and present[topic].schema in CALIBRATION_SCHEMAS:
            return topic
    return None


def require_image_topic(reader: LogReader, topic: str) -> None:
    """``topic`` is in the log and holds images (any schema of ``IMAGE_SCHEMAS``)."""
    reader.require(topic)
    schema = reader.topics()[topic].schema
    if schema not in IMAGE_SCHEMAS:
        raise LogError(f"{reader.path}: topic {topic} holds {schema or 'messages without a schema'}, not images "
                       f"({', '.join(IMAGE_SCHEMAS)})")


def choose_image_topic(reader: LogReader) -> str:
    """``/camera/image``, else ``/stereo/left/image``, else the one topic whose schema is an image's."""
    present = reader.topics()
    for topic in (T.CAMERA_IMAGE, T.STEREO_LEFT_IMAGE):
        if topic in present:
            return topic
    images = sorted(t for t, info in present.items() if info.schema in IMAGE_SCHEMAS)
    if len(images) == 1:
        return images[0]
    if not images:
        raise LogError(f"{reader.path} has no image topic (schemas {', '.join(IMAGE_SCHEMAS)}); "
                       f"topics present: {_listed(reader)}")
    raise LogError(f"{reader.path} has {len(images)} image topics ({', '.join(images)}): choose one with "
                   f"--image-topic TOPIC, or a stereo pair with --stereo-topics LEFT RIGHT")


def image_times(reader: LogReader, image_topic: str | None = None) -> dict[int, int]:
    """Frame number -> log time of every image on ``image_topic`` (default :func:`choose_image_topic`),
    read without decoding: the frames a replay numbers. A lost image (a damaged chunk) keeps its
    number and, where the chunk's index gives it, its time; its frame exists, the tracker skipped it."""
    topic = image_topic or choose_image_topic(reader)
    require_image_topic(reader, topic)
    return {item.index: item.log_time for item in reader.messages([topic]) if item.lost is None or item.log_time >= 0}


@dataclass
class BundleReport:
    """What bundling noticed; filled while frames are produced."""

    frames: int = 0
    unpaired: list[tuple[str, int]] = field(default_factory=list)
    outside_encoder_coverage: list[int] = field(default_factory=list)
    lost: list[LostFrame] = field(default_factory=list)  # frames skipped: damaged chunk or undecodable image
    zoom_outside_lens: list[int] = field(default_factory=list)  # frames whose zoom the lens table does not cover
    out_of_order: list[int] = field(default_factory=list)  # frames written before the previous frame (time went backwards)
    channel_conflicts: dict[int, str] = field(default_factory=dict)  # channel id declared twice: the reader's sentences


@dataclass(frozen=True)
class LostFrame:
    """An image the replay could not use; the tracker never saw it (it predicts across the gap)."""

    topic: str
    index: int
    t_ns: int
    reason: str


class UndecodableImage(LogError):
    """One image's bytes do not decode: that frame is skipped, the replay goes on."""


def interpolate_ptz(a: PtzReading, b: PtzReading, t_ns: int) -> PtzReading:
    """Linear interpolation at ``t_ns``; pan takes the shorter way round the circle."""
    if b.t_ns == a.t_ns:
        return PtzReading(t_ns, a.pan, a.tilt, a.zoom, a.focus)
    s = (t_ns - a.t_ns) / (b.t_ns - a.t_ns)
    dpan = (b.pan - a.pan + 180.0) % 360.0 - 180.0
    return PtzReading(
        t_ns,
        a.pan + s * dpan,
        a.tilt + s * (b.tilt - a.tilt),
        a.zoom + s * (b.zoom - a.zoom),
        a.focus + s * (b.focus - a.focus),
    )


class PtzInterpolator:
    """Streams encoder readings and answers the pose at increasing frame times."""

    def __init__(self, readings: Iterator[PtzReading], tolerance_ns: int) -> None:
        self._it = readings
        self._tol = tolerance_ns
        self._prev: PtzReading | None = None
        self._next: PtzReading | None = next(self._it, None)

    def at(self, t_ns: int) -> PtzReading | None:
        while self._next is not None and self._next.t_ns < t_ns:
            self._prev, self._next = self._next, next(self._it, None)
        nxt, prev = self._next, self._prev
        if nxt is not None and nxt.t_ns == t_ns:
            return nxt
        if prev is None or nxt is None or nxt.t_ns - prev.t_ns > self._tol:
            return None
        return interpolate_ptz(prev, nxt, t_ns)


def _ptz_stream(reader: LogReader, topic: str, start_ns: int | None) -> Iterator[PtzReading]:
    for item in reader.messages([topic], start_ns=None if start_ns is None else max(0, start_ns - 10**9)):
        if item.lost is None:  # a lost reading leaves a wider bracket; the pose tolerance decides
            yield _checked(PtzReading.from_pb, item)


def _checked(convert, item: LogMessage):
    """``convert(decoded message)``, a value it refuses named by file, topic and message index."""
    try:
        return convert(item.decode())
    except ValueError as err:
        raise LogError(f"{item._path}: message {item.index} on topic {item.topic}: {err}") from None


def read_hints(reader: LogReader, topic: str, image_topic: str = T.CAMERA_IMAGE) -> tuple[InitRegion, ...]:
    if topic not in reader.topics():
        return ()
    regions: list[InitRegion] = []
    for item in reader.messages([topic]):
        if item.lost is None:
            regions.extend(_checked(lambda pb: [InitRegion.from_pb(r) for r in pb.regions], item))
    images = reader.topics()[image_topic].count if image_topic in reader.topics() else None
    for region in regions:
        if images is not None and region.frame >= images:
            raise LogError(f"{reader.path}: topic {topic} marks frame {region.frame}, but {image_topic} has {images} frames")
    return tuple(regions)


def read_ground_plane(reader: LogReader, topic: str) -> GroundPlaneCalibration | None:
    """The log's ground-plane calibration (its first message on ``topic``), None when absent."""
    pb = reader.first(topic)
    if pb is None:
        return None
    try:
        return GroundPlaneCalibration.from_pb(pb)
    except ValueError as err:
        raise LogError(f"{reader.path}: topic {topic} holds an unusable ground plane ({err})") from None


def read_stereo_rig(reader: LogReader, topics: FrameTopics) -> StereoRig | None:
    """The rectified rig from the left and right ``CameraCalibration`` (f, cx, cy from the left
    ``P``; baseline ``-P_right[3] / P_right[0]``), None unless both are present and usable."""
    if topics.right is None:
        return None
    left, right = reader.first(topics.left_calibration), reader.first(topics.right_calibration)
    if left is None or right is None:
        return None
    lp, rp = projection(left) or [], projection(right) or []  # CameraCalibration P or ROS 2 CameraInfo p
    if len(lp) != 12 or len(rp) != 12 or lp[0] <= 0 or rp[0] <= 0 or -rp[3] / rp[0] <= 0:
        raise LogError(f"{reader.path}: topics {topics.left_calibration}/{topics.right_calibration} do not describe "
                       f"a rectified pair (need 3x4 P with fx > 0 and the right camera to the right)")
    return StereoRig(f=float(lp[0]), baseline=float(-rp[3] / rp[0]), cx=float(lp[2]), cy=float(lp[6]),
                     pose=read_rig_pose(reader, topics.stereo_pose))


def read_rig_pose(reader: LogReader, topic: str = T.STEREO_POSE) -> RigPose | None:
    """The left camera's pose in the world (Z up) from the first ``foxglove.FrameTransform`` on
    ``topic`` (``/stereo/pose``), None when the log has none."""
    if topic not in reader.topics():
        return None
    pb = reader.first(topic)
    if pb is None:
        return None
    try:
        q, t = pb.rotation, pb.translation
        return RigPose.from_quaternion([q.x, q.y, q.z, q.w], [t.x, t.y, t.z])
    except (AttributeError, ValueError, ZeroDivisionError, FloatingPointError) as err:
        raise LogError(f"{reader.path}: topic {topic} is not a usable rig pose (foxglove.FrameTransform): {err}") from None


def marks_in_window(hints: tuple[InitRegion, ...], start_ns: int | None, end_ns: int | None) -> tuple[InitRegion, ...]:
    """The marks on frames inside ``start_ns <= t < end_ns`` (a mark's time is its frame's, checked
    when frames are bundled): a replay from --start must not start a track from a mark on a frame it
    never shows the tracker."""
    if start_ns is None and end_ns is None:
        return hints
    return tuple(r for r in hints if (start_ns is None or r.t_ns >= start_ns) and (end_ns is None or r.t_ns < end_ns))


def marked_images(reader: LogReader, topics: FrameTopics, start_ns: int | None = None,
                  end_ns: int | None = None) -> list[tuple]:
    """``(image, regions)`` for every frame the log's init annotations mark (inside the replay's
    window), in frame order.

    Only those images are decoded; trackers that learn from the marks (the golf LUTs) get them
    all before the first step, wherever the marked frames are in the window.
    """
    hints = marks_in_window(read_hints(reader, topics.hints, topics.image), start_ns, end_ns)
    by_frame: dict[int, list[InitRegion]] = {}
    for region in hints:
        by_frame.setdefault(region.frame, []).append(region)
    out = []
    if not by_frame:
        return out
    last = max(by_frame)
    # Straight to the marked frames' chunks when the message indexes allow (a tee shot marked at
    # frame 355 of 369 read and parsed the whole log before the first step: ~0.12 s of a 1.3 s replay)
    items = reader.messages_at(topics.image, by_frame)
    for item in reader.messages([topics.image]) if items is None else items:
        if item.index in by_frame and item.lost is None:
            where = f"{reader.path}: topic {item.topic} message {item.index}"
            out.append((decode_image(item.decode(), item.schema, where)[0], tuple(by_frame[item.index])))
        if item.index >= last:
            break
    return out


def _lens_table(reader: LogReader, topic: str) -> LensTable | None:
    """The log's lens table (its first message on ``topic``), None when absent."""
    lens_pb = reader.first(topic)
    try:
        return LensTable.from_pb(lens_pb) if lens_pb is not None else None
    except ValueError as err:
        raise LogError(f"{reader.path}: topic {topic}: {err}") from None


def _kind(shape: tuple) -> str:
    """An image's kind by its shape (a grey right view of a colour left: the same size, another kind)."""
    return "grey" if len(shape) == 2 or shape[2] == 1 else "colour" if shape[2] == 3 else f"{shape[2]}-channel"


@dataclass
class _Bundler:
    """What every frame of one replay shares (lens table, marks, ground plane, stereo rig, encoder
    stream) and the stages that turn image messages into frames: decode, check, bundle, skip."""

    reader: LogReader
    topics: FrameTopics
    report: BundleReport
    strict: bool
    lens: LensTable | None
    zoom_range: tuple[float, float]
    hints: tuple[InitRegion, ...]
    hints_by_frame: dict[int, list[InitRegion]]
    calibration: GroundPlaneCalibration | None
    ground: GroundPlane | None
    rig: StereoRig | None
    ptz: PtzInterpolator | None
    shape: tuple[int, ...] | None = None  # the first image's; every later image must match it

    @classmethod
    def from_log(cls, reader: LogReader, topics: FrameTopics, start_ns: int | None, end_ns: int | None,
             ptz_tolerance_ns: int, report: BundleReport, strict: bool) -> _Bundler:
        """Read what the frames share, in this order: topics present, lens table, marks, ground plane, rig, encoders."""
        reader.require(topics.image, *([topics.right] if topics.right else []), *([topics.ptz] if topics.ptz else []))
        lens = _lens_table(reader, topics.lens)
        zoom_range = (min(e.zoom for e in lens.entries), max(e.zoom for e in lens.entries)) if lens is not None else (0.0, 0.0)
        hints = marks_in_window(read_hints(reader, topics.hints, topics.image), start_ns, end_ns)
        hints_by_frame: dict[int, list[InitRegion]] = {}
        for region in hints:
            hints_by_frame.setdefault(region.frame, []).append(region)
        calibration = read_ground_plane(reader, topics.ground_plane)
        ground = None if calibration is None else GroundPlane(
            calibration.matrix, calibration.camera_ground, calibration.camera_height,
            calibration.principal_point, calibration.focal_px)
        rig = read_stereo_rig(reader, topics)
        ptz = PtzInterpolator(_ptz_stream(reader, topics.ptz, start_ns), ptz_tolerance_ns) if topics.ptz else None
        return cls(reader, topics, report, strict, lens, zoom_range, hints, hints_by_frame, calibration, ground, rig, ptz)

    def pixels(self, item: LogMessage):
        """``(image, encoded, encoding)`` of one image message, its size checked against the others'."""
        where = f"{self.reader.path}: topic {item.topic} message {item.index}"
        expect = None if self.shape is None else (self.shape[1], self.shape[0])
        try:
            image, encoded, encoding = decode_image(item.decode(), item.schema, where, expect)
        except SizeMismatch as err:  # (as after decoding: the log is inconsistent, not one frame damaged)
            raise LogError(str(err)) from None
        except LogError as err:
            raise UndecodableImage(str(err)) from None
        if self.shape is None:
            self.shape = image.shape
            self._check_calibrations_fit(image.shape, where)
        elif image.shape != self.shape:
            shape = self.shape
            if image.shape[:2] != shape[:2]:
                raise LogError(f"{where} is {image.shape[1]}x{image.shape[0]} but earlier images are {shape[1]}x{shape[0]}")
            raise LogError(f"{where} is {_kind(image.shape)} but earlier images are {_kind(shape)} (both {shape[1]}x{shape[0]})")
        return image, encoded, encoding

    def _check_calibrations_fit(self, shape: tuple[int, ...], where: str) -> None:
        """The ground plane and the lens table describe images of the first image's size."""
        calibration, lens, path = self.calibration, self.lens, self.reader.path
        if calibration is not None and (calibration.width, calibration.height) != (shape[1], shape[0]):
            raise LogError(f"{path}: topic {self.topics.ground_plane} is for {calibration.width}x{calibration.height} "
                           f"images but {where} is {shape[1]}x{shape[0]}")
        if lens is not None and lens.width and lens.height and (lens.width, lens.height) != (shape[1], shape[0]):
            raise LogError(f"{path}: topic {self.topics.lens} is for {lens.width}x{lens.height} images "
                           f"but {where} is {shape[1]}x{shape[0]}")

    def _check_marks(self, left: LogMessage) -> None:
        for region in self.hints_by_frame.get(left.index, ()):
            if region.t_ns and region.t_ns != left.log_time:  # a mark counts frames; its time says which image it saw
                raise LogError(f"{self.reader.path}: topic {self.topics.hints} marks frame {region.frame} at t={region.t_ns} "
                               f"ns, but frame {region.frame} of {self.topics.image} is at t={left.log_time} ns: the log lost "
                               "or gained images after it was marked (a tool that did not renumber its marks); mark it again")

    def bundle(self, left: LogMessage, right: LogMessage | None) -> Frame:
        """One frame: the image (and its right partner), the PTZ pose at its time, the log's calibrations and marks."""
        self._check_marks(left)
        image, encoded, encoding = self.pixels(left)
        right_image = self.pixels(right)[0] if right is not None else None
        ptz, lens, report = self.ptz, self.lens, self.report
        pose = ptz.at(left.log_time) if ptz is not None else None
        if ptz is not None and pose is None:
            report.outside_encoder_coverage.append(left.index)
        if pose is not None and lens is not None and not self.zoom_range[0] <= pose.zoom <= self.zoom_range[1]:
            report.zoom_outside_lens.append(left.index)  # the camera model clamps to the nearest entry
        report.frames += 1
        return Frame(
            index=left.index,
            t_ns=left.log_time,
            image=image,
            right=right_image,
            ptz=pose,
            lens=lens,
            camera=PtzCamera.from_reading(pose, lens) if pose is not None and lens is not None else None,
            hints=tuple(self.hints_by_frame.get(left.index, ())),
            all_hints=self.hints,
            encoded=encoded,
            encoding=encoding,
            ground_plane=self.ground,
            stereo=self.rig,
        )

    def skip(self, item: LogMessage, reason: str) -> None:
        """List a frame the tracker will not see (an error with ``strict``)."""
        if self.strict:
            raise LogError(f"{self.reader.path}: frame {item.index} on topic {item.topic} cannot be used ({reason}); "
                           f"without --strict it is skipped")
        self.report.lost.append(LostFrame(item.topic, item.index, item.log_time, reason))

    def usable(self, left: LogMessage, right: LogMessage | None) -> Frame | None:
        """The frame, or None when an image of it was lost or does not decode (then listed as skipped)."""
        for item in (left, right):
            if item is not None and item.lost is not None:
                self.skip(left, item.lost)
                return None
        try:
            return self.bundle(left, right)
        except UndecodableImage as err:
            self.skip(left, str(err))
            return None


def _mono_frames(bundler: _Bundler, messages: Iterator[LogMessage]) -> Iterator[Frame]:
    """One frame per image message; frames written out of time order are listed, two at one time refused."""
    report, previous = bundler.report, None
    item = next(messages, None)
    while item is not None:
        if previous is not None and item.lost is None and 0 <= item.sequence < previous.sequence:
            report.out_of_order.append(item.index)  # written before the frame that precedes it in time
        if previous is not None and item.lost is None and previous.log_time == item.log_time:
            raise LogError(f"{bundler.reader.path}: messages {previous.index} and {item.index} on topic {item.topic} have "
                           f"the same log_time {item.log_time}: two frames cannot share a time")
        previous = item if item.lost is None else previous
        frame = bundler.usable(item, None)
        # The next message is read (the log's records parsed: Python, holding the GIL) before this frame is
        # handed over: in a prefetch thread that work is then done while the tracker waits for this frame,
        # not while it steps on it (the decode that follows releases the GIL). Every frame read is still
        # handed over before an error in what follows it.
        try:
            item = next(messages, None)
        except Exception:  # (an interrupt is not held back for the frame)
            if frame is not None:
                yield frame
            raise
        if frame is not None:
            yield frame


def _stereo_frames(bundler: _Bundler, messages: Iterator[LogMessage]) -> Iterator[Frame]:
    """One frame per left/right pair of equal log time; an image without a partner is listed as unpaired."""
    topics, report = bundler.topics, bundler.report
    group: dict[str, LogMessage] = {}
    group_time: int | None = None

    def flush() -> Iterator[Frame]:
        left, right = group.get(topics.image), group.get(topics.right)
        if left is not None and right is not None:
            frame = bundler.usable(left, right)
            if frame is not None:
                yield frame
        else:
            lone = left or right
            report.unpaired.append((lone.topic, lone.index))
        group.clear()

    for item in messages:
        if group_time is not None and item.log_time != group_time:
            yield from flush()
        group_time = item.log_time
        if item.topic in group:  # two images of one side at one time: the first is unpaired
            yield from flush()
        group[item.topic] = item
    if group:
        yield from flush()


def iter_frames(
    reader: LogReader,
    topics: FrameTopics,
    *,
    start_ns: int | None = None,
    end_ns: int | None = None,
    ptz_tolerance_ns: int = 100_000_000,
    report: BundleReport | None = None,
    strict: bool = False,
) -> Iterator[Frame]:
    """Yield one immutable :class:`Frame` per image (or stereo pair) in log-time order.

    An image lost with a damaged chunk, or one that does not decode, is skipped and listed in
    ``report.lost`` (the tracker predicts across it); ``strict`` makes it an error instead.
    """
    report = report if report is not None else BundleReport()
    report.channel_conflicts = reader.channel_conflicts  # (filled as the chunks are read)
    bundler = _Bundler.from_log(reader, topics, start_ns, end_ns, ptz_tolerance_ns, report, strict)
    image_topics = [topics.image] + ([topics.right] if topics.right else [])
    messages = iter(reader.messages(image_topics, start_ns=start_ns, end_ns=end_ns))
    if topics.right is None:
        yield from _mono_frames(bundler, messages)
    else:
        yield from _stereo_frames(bundler, messages)
