from pathlib import Path

import numpy as np
import pytest

from trackreplay.recorder.image_codec import image_message
from trackreplay.recorder.writer import LogWriter
from trackreplay.replay.log.frames import BundleReport, FrameTopics, PtzInterpolator, interpolate_ptz, iter_frames
from trackreplay.replay.log.reader import LogReader
from trackreplay.schemas import topics as T
from trackreplay.schemas.errors import LogError
from trackreplay.schemas.records import LensEntry, LensTable, PtzReading

MS = 1_000_000


def _img(value: int, shape=(8, 10)) -> np.ndarray:
    return np.full(shape, value, np.uint8)


def test_ptz_interpolation_takes_short_way_round() -> None:
    a, b = PtzReading(0, 179.0, 0.0, 1.0, 2.0), PtzReading(10, -179.0, 10.0, 3.0, 4.0)
    mid = interpolate_ptz(a, b, 5)
    assert mid.pan == pytest.approx(180.0) and mid.tilt == pytest.approx(5.0)
    assert (mid.zoom, mid.focus) == (2.0, 3.0)


def test_interpolator_coverage_and_tolerance() -> None:
    readings = [PtzReading(t, float(t), 0.0, 0.0, 0.0) for t in (10, 20, 30, 100)]
    ptz = PtzInterpolator(iter(readings), tolerance_ns=15)
    assert ptz.at(5) is None  # before the first reading
    assert ptz.at(10).pan == 10.0  # exact reading
    assert ptz.at(25).pan == pytest.approx(25.0)
    assert ptz.at(50) is None  # 30 -> 100 is a gap longer than the tolerance
    assert ptz.at(100).pan == 100.0
    assert ptz.at(101) is None  # after the last reading


def test_stereo_pairs_by_equal_log_time_and_ptz_at_frame_time(tmp_path: Path) -> None:
    path = tmp_path / "rig.mcap"
    lens = LensTable(10, 8, (LensEntry(0, 0, 100, 100, 5, 4),))
    with LogWriter(path) as log:
        log.write(T.PTZ_LENS_TABLE, lens.to_pb(0), 0)
        for k in range(0, 60, 5):  # encoders every 5 ms, from 0 to 55 ms
            log.write(T.PTZ_ENCODERS, PtzReading(k * MS, float(k), 0.0, 1.0, 1.0).to_pb(), k * MS)
        for k, t in enumerate((0, 20, 40, 70)):
            log.write(T.STEREO_LEFT_IMAGE, image_message(_img(k), "png", t * MS), t * MS)
            if k != 2:  # the third left image has no partner
                log.write(T.STEREO_RIGHT_IMAGE, image_message(_img(100 + k), "png", t * MS), t * MS)
        log.write(T.STEREO_RIGHT_IMAGE, image_message(_img(9), "png", 50 * MS), 50 * MS)  # lone right
    reader = LogReader(path)
    topics = FrameTopics.detect(reader)
    assert (topics.image, topics.right, topics.ptz) == (T.STEREO_LEFT_IMAGE, T.STEREO_RIGHT_IMAGE, T.PTZ_ENCODERS)
    report = BundleReport()
    frames = list(iter_frames(reader, topics, report=report))
    assert [f.index for f in frames] == [0, 1, 3]
    assert [int(f.right[0, 0]) for f in frames] == [100, 101, 103]
    assert frames[1].ptz.pan == pytest.approx(20.0)
    assert frames[2].ptz is None  # 70 ms is after the last encoder reading
    assert report.outside_encoder_coverage == [3]
    assert sorted(report.unpaired) == [(T.STEREO_LEFT_IMAGE, 2), (T.STEREO_RIGHT_IMAGE, 2)]
    assert frames[0].lens == lens
    assert frames[1].camera.pan == pytest.approx(20.0) and frames[1].camera.intrinsics.fx == 100
    assert frames[2].camera is None


def test_wrong_image_size_names_topic_and_message(tmp_path: Path) -> None:
    path = tmp_path / "sizes.mcap"
    with LogWriter(path) as log:
        log.write(T.CAMERA_IMAGE, image_message(_img(1), "png", 0), 0)
        log.write(T.CAMERA_IMAGE, image_message(_img(1, (9, 10)), "png", MS), MS)
    reader = LogReader(path)
    frames = iter_frames(reader, FrameTopics.detect(reader))
    assert next(frames).index == 0  # what came before stays readable
    with pytest.raises(LogError, match=r"topic /camera/image message 1 is 10x9 but earlier images are 10x8"):
        next(frames)


def test_raw_image_with_short_payload_is_reported(tmp_path: Path) -> None:
    path = tmp_path / "raw.mcap"
    msg = image_message(_img(3), "raw", 0)
    msg.data = msg.data[:-5]
    with LogWriter(path) as log:
        log.write(T.CAMERA_IMAGE, msg, 0)
    reader = LogReader(path)
    report = BundleReport()
    assert list(iter_frames(reader, FrameTopics.detect(reader), report=report)) == []
    [lost] = report.lost
    assert (lost.topic, lost.index) == (T.CAMERA_IMAGE, 0)
    assert "message 0: raw image claims 10x8 mono8 but holds 75 bytes" in lost.reason
    with pytest.raises(LogError, match=r"frame 0 on topic /camera/image cannot be used .*holds 75 bytes.*without --strict"):
        list(iter_frames(reader, FrameTopics.detect(reader), strict=True))


def test_a_damaged_chunk_costs_its_frames_only(flow_sim1: Path, tmp_path: Path) -> None:
    """Frames after a damaged chunk keep their numbers; the lost ones are listed with their times."""
    from mcap.reader import make_reader

    with open(flow_sim1, "rb") as fh:
        summary = make_reader(fh).get_summary()
    chunk = sorted(summary.chunk_indexes, key=lambda c: c.chunk_start_offset)[1]
    data = bytearray(flow_sim1.read_bytes())
    data[chunk.chunk_start_offset + chunk.chunk_length // 2] ^= 0x04
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(bytes(data))
    intact = {f.index: f for f in iter_frames(LogReader(flow_sim1), FrameTopics.detect(LogReader(flow_sim1)))}
    report = BundleReport()
    reader = LogReader(bad)
    kept = {f.index: f for f in iter_frames(reader, FrameTopics.detect(reader), report=report)}
    lost = [x.index for x in report.lost]
    assert lost and sorted(set(kept) | set(lost)) == sorted(intact)
    assert lost == list(range(lost[0], lost[-1] + 1))  # one chunk: consecutive frames
    assert all("damaged chunk at byte" in x.reason and "crc" in x.reason.lower() for x in report.lost)
    assert [x.t_ns for x in report.lost] == [intact[i].t_ns for i in lost]
    for i, frame in kept.items():
        assert frame.t_ns == intact[i].t_ns and (frame.image == intact[i].image).all()


def test_hints_attach_to_their_frame(flow_sim1: Path) -> None:
    reader = LogReader(flow_sim1)
    frames = iter_frames(reader, FrameTopics.detect(reader))
    first, second = next(frames), next(frames)
    assert first.hints[0].label == "target" and first.hints[0].w == 13.0
    assert second.hints == ()
    assert first.image.shape == (256, 256) and first.encoding == "png"


def _log_with(tmp_path: Path, name: str, write) -> LogReader:
    path = tmp_path / name
    with LogWriter(path) as log:
        write(log)
    return LogReader(path)


def test_values_inside_a_log_are_checked_with_topic_and_index(tmp_path: Path) -> None:
    from trackreplay.schemas.records import InitRegion, LensEntry, LensTable, PtzReading, init_annotations_pb

    def frames(log, times=(0, 10, 20)):
        for t in times:
            log.write(T.CAMERA_IMAGE, image_message(_img(t), "png", t), t)

    def bad_pan(log):
        frames(log)
        log.write(T.PTZ_LENS_TABLE, LensTable(10, 8, (LensEntry(0, 0, 100, 100, 5, 4),)).to_pb(0), 0)
        for k, t in enumerate((0, 10, 20)):
            log.write(T.PTZ_ENCODERS, PtzReading(t, float("nan") if k == 1 else 0.0, 0, 0, 0).to_pb(), t)

    reader = _log_with(tmp_path, "pan.mcap", bad_pan)
    with pytest.raises(LogError, match=r"pan\.mcap: message 1 on topic /ptz/encoders: pan is nan, not a finite number"):
        list(iter_frames(reader, FrameTopics.detect(reader)))

    def empty_lens(log):
        frames(log)
        log.write(T.PTZ_LENS_TABLE, LensTable(10, 8, ()).to_pb(0), 0)

    reader = _log_with(tmp_path, "lens.mcap", empty_lens)
    with pytest.raises(LogError, match=r"lens\.mcap: topic /ptz/lens_table: the lens table has no entries"):
        list(iter_frames(reader, FrameTopics.detect(reader)))

    def wrong_lens_size(log):
        frames(log)
        log.write(T.PTZ_LENS_TABLE, LensTable(640, 480, (LensEntry(0, 0, 100, 100, 5, 4),)).to_pb(0), 0)

    reader = _log_with(tmp_path, "size.mcap", wrong_lens_size)
    with pytest.raises(LogError, match=r"topic /ptz/lens_table is for 640x480 images but .* is 10x8"):
        list(iter_frames(reader, FrameTopics.detect(reader)))

    def far_mark(log):
        frames(log)
        log.write(T.ANNOTATIONS_INIT, init_annotations_pb([InitRegion(10**12, 0, 5, 4, 2, 2)], 0), 0)

    reader = _log_with(tmp_path, "mark.mcap", far_mark)
    with pytest.raises(LogError, match=r"topic /annotations/init marks frame 1000000000000, but /camera/image has 3 frames"):
        list(iter_frames(reader, FrameTopics.detect(reader)))

    def nan_mark(log):
        frames(log)
        log.write(T.ANNOTATIONS_INIT, init_annotations_pb([InitRegion(0, 0, float("nan"), 4, 2, 2)], 0), 0)

    reader = _log_with(tmp_path, "nan.mcap", nan_mark)
    with pytest.raises(LogError, match=r"message 0 on topic /annotations/init: the box on frame 0 .* is not a finite box"):
        list(iter_frames(reader, FrameTopics.detect(reader)))

    reader = _log_with(tmp_path, "dup.mcap", lambda log: frames(log, (0, 10, 10, 20)))
    with pytest.raises(LogError, match=r"messages 1 and 2 on topic /camera/image have the same log_time 10"):
        list(iter_frames(reader, FrameTopics.detect(reader)))


def test_zoom_beyond_the_lens_table_and_images_out_of_time_order_are_reported(tmp_path: Path) -> None:
    from trackreplay.schemas.records import LensEntry, LensTable, PtzReading

    def write(log):
        log.write(T.PTZ_LENS_TABLE, LensTable(10, 8, (LensEntry(0, 0, 100, 100, 5, 4), LensEntry(2000, 0, 900, 900, 5, 4))).to_pb(0), 0)
        for t, zoom in ((0, 100.0), (10, 9999.0), (20, 9999.0), (30, 500.0)):
            log.write(T.PTZ_ENCODERS, PtzReading(t, 0, 0, zoom, 0).to_pb(), t)
        for t in (0, 20, 10, 30):  # the third image is written after a later one
            log.write(T.CAMERA_IMAGE, image_message(_img(t), "png", t), t)

    reader = _log_with(tmp_path, "zoom.mcap", write)
    report = BundleReport()
    frames = list(iter_frames(reader, FrameTopics.detect(reader), report=report))
    assert [f.t_ns for f in frames] == [0, 10, 20, 30]
    assert report.zoom_outside_lens == [1, 2]
    assert report.out_of_order == [2]  # frame 2 (t=20) was written before frame 1 (t=10)


def test_messages_at_equals_the_same_messages_of_a_full_iteration(flow_sim1: Path, tmp_path: Path) -> None:
    """``LogReader.messages_at`` (marked frames read straight from their chunks) gives what
    ``messages`` numbers the same, on an intact log and with a damaged chunk (its messages lost)."""
    from mcap.reader import make_reader

    with open(flow_sim1, "rb") as fh:
        summary = make_reader(fh).get_summary()
    chunk = sorted(summary.chunk_indexes, key=lambda c: c.chunk_start_offset)[1]
    data = bytearray(flow_sim1.read_bytes())
    data[chunk.chunk_start_offset + chunk.chunk_length // 2] ^= 0x04
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(bytes(data))
    for log in (flow_sim1, bad):
        reader = LogReader(log)
        topic = FrameTopics.detect(reader).image
        every = list(reader.messages([topic]))
        wanted = [0, 3, len(every) // 2, len(every) - 1, len(every) + 5]
        got = LogReader(log).messages_at(topic, wanted)
        assert got is not None
        expected = [every[k] for k in sorted(set(wanted)) if k < len(every)]
        assert [(m.index, m.log_time, m.sequence, bytes(m.data), m.lost is None) for m in got] == \
            [(m.index, m.log_time, m.sequence, bytes(m.data), m.lost is None) for m in expected]
    assert any(m.lost for m in LogReader(bad).messages_at(topic, range(len(every))))


def test_a_mark_for_another_moment_is_refused(tmp_path: Path) -> None:
    """A mark counts frames and records its frame's time: when the two disagree (the log lost or
    gained images after it was marked), replay says so instead of starting on the wrong image."""
    from trackreplay.schemas.records import InitRegion, init_annotations_pb

    def write(log):
        for t in (0, 10, 20):
            log.write(T.CAMERA_IMAGE, image_message(_img(t), "png", t), t)
        log.write(T.ANNOTATIONS_INIT, init_annotations_pb([InitRegion(1, 20, 4.0, 4.0, 2.0, 2.0, "target")], 0), 0)

    reader = _log_with(tmp_path, "shifted.mcap", write)
    with pytest.raises(LogError, match="marks frame 1 at t=20 ns, but frame 1 of /camera/image is at t=10 ns"):
        list(iter_frames(reader, FrameTopics.detect(reader)))


def _three_frames(tmp_path: Path) -> LogReader:
    """A log of three PNG frames 1 ms apart."""
    path = tmp_path / "three.mcap"
    with LogWriter(path) as log:
        for k in range(3):
            log.write(T.CAMERA_IMAGE, image_message(_img(k), "png", k * MS), k * MS)
    return LogReader(path)


def test_the_next_record_is_read_before_a_frame_is_handed_over_and_an_error_there_loses_no_frame(tmp_path: Path,
                                                                                                  monkeypatch) -> None:
    """iter_frames reads message k+1 (the log's records parsed in Python, holding the GIL) before it yields
    frame k, so a prefetch thread does that work while the tracker waits rather than while it steps; a
    failure reading message k+1 still hands frame k over first."""
    reader = _three_frames(tmp_path)
    real = LogReader.messages
    read: list[int] = []

    def failing(self, *args, **kwargs):
        for item in real(self, *args, **kwargs):
            if item.index == 2:
                raise LogError("message 2 is unreadable")
            read.append(item.index)
            yield item

    monkeypatch.setattr(LogReader, "messages", failing)
    frames = iter_frames(reader, FrameTopics.detect(reader))
    assert next(frames).index == 0 and read == [0, 1]  # message 1 was read before frame 0 came out
    assert next(frames).index == 1  # frame 1 handed over although reading what follows it failed ...
    with pytest.raises(LogError, match="message 2 is unreadable"):
        next(frames)  # ... and the error after it


def test_an_interrupt_while_reading_ahead_is_not_held_back(tmp_path: Path, monkeypatch) -> None:
    """A Ctrl-C while message k+1 is read goes out at once: frame k is not handed over first (only errors
    wait a step, so that no readable frame is lost to them)."""
    reader = _three_frames(tmp_path)
    real = LogReader.messages

    def interrupted(self, *args, **kwargs):
        for item in real(self, *args, **kwargs):
            if item.index == 2:
                raise KeyboardInterrupt
            yield item

    monkeypatch.setattr(LogReader, "messages", interrupted)
    frames = iter_frames(reader, FrameTopics.detect(reader))
    assert next(frames).index == 0
    with pytest.raises(KeyboardInterrupt):
        next(frames)  # not frame 1 first
