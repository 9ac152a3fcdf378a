from pathlib import Path

import pytest
from mcap.writer import Writer

from trackreplay.recorder.image_codec import image_message
from trackreplay.recorder.writer import LogWriter
from trackreplay.replay.log.reader import LogReader
from trackreplay.schemas import topics as T
from trackreplay.schemas.errors import LogError, TruncatedLogError
from trackreplay.schemas.records import PtzReading

import numpy as np


def test_topics_counts_and_order(flow_sim1: Path) -> None:
    reader = LogReader(flow_sim1)
    topics = reader.topics()
    assert topics[T.CAMERA_IMAGE].count == 51
    assert topics[T.CAMERA_IMAGE].schema == "foxglove.CompressedImage"
    assert topics[T.GROUNDTRUTH].schema == "trackreplay.GroundTruthFrame"
    items = list(reader.messages([T.CAMERA_IMAGE, T.GROUNDTRUTH]))
    keys = [(m.log_time, m.channel_id, m.sequence) for m in items]
    assert keys == sorted(keys)
    assert [m.index for m in items if m.topic == T.CAMERA_IMAGE] == list(range(51))


def test_time_range_keeps_absolute_indices(flow_sim1: Path) -> None:
    reader = LogReader(flow_sim1)
    t0, _ = reader.time_range()
    t_of = [m.log_time for m in reader.messages([T.CAMERA_IMAGE])]
    items = list(reader.messages([T.CAMERA_IMAGE], start_ns=t_of[10] + 1, end_ns=t_of[20]))
    assert [m.index for m in items] == list(range(11, 20))


def test_ties_break_by_channel_then_sequence(tmp_path: Path) -> None:
    path = tmp_path / "ties.mcap"
    with LogWriter(path) as log:
        for k in range(3):
            log.write(T.PTZ_ENCODERS, PtzReading(5, k, 0, 0, 0).to_pb(), 5)  # channel 1
            log.write(T.CAMERA_IMAGE, image_message(np.zeros((4, 4), np.uint8), "raw", 5), 5)  # channel 2
    items = list(LogReader(path).messages([T.CAMERA_IMAGE, T.PTZ_ENCODERS]))
    assert [(m.topic, m.sequence) for m in items] == [(T.PTZ_ENCODERS, 0), (T.PTZ_ENCODERS, 1), (T.PTZ_ENCODERS, 2),
                                                      (T.CAMERA_IMAGE, 0), (T.CAMERA_IMAGE, 1), (T.CAMERA_IMAGE, 2)]


def test_missing_topic_lists_present(flow_sim1: Path) -> None:
    with pytest.raises(LogError, match=r"has no topic /ptz/encoders; topics present: /annotations/init, /camera/image, /groundtruth/objects"):
        LogReader(flow_sim1).require(T.PTZ_ENCODERS)


def test_truncated_log_points_to_recover(flow_sim1: Path, tmp_path: Path) -> None:
    cut = tmp_path / "cut.mcap"
    data = flow_sim1.read_bytes()
    cut.write_bytes(data[: len(data) // 2])
    with pytest.raises(TruncatedLogError, match=r"cut.mcap is truncated.*trackreplay recover"):
        LogReader(cut)


def test_not_mcap_and_missing_file(tmp_path: Path) -> None:
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(b"hello world, not a log")
    with pytest.raises(LogError, match="is not an MCAP file"):
        LogReader(junk)
    with pytest.raises(LogError, match="does not exist"):
        LogReader(tmp_path / "absent.mcap")


def test_undecodable_message_names_topic_and_index(tmp_path: Path) -> None:
    path = tmp_path / "bad.mcap"
    good = PtzReading(0, 1.0, 2.0, 3.0, 4.0).to_pb()
    with LogWriter(path) as log:
        log.write(T.PTZ_ENCODERS, good, 0)
    # Re-write with a corrupt payload on the same protobuf channel.
    from mcap_protobuf.schema import register_schema

    with open(path, "wb") as fh:
        w = Writer(fh)
        w.start()
        sid = register_schema(w, type(good))
        cid = w.register_channel(T.PTZ_ENCODERS, "protobuf", sid)
        w.add_message(cid, 0, good.SerializeToString(), 0)
        w.add_message(cid, 1, b"\xff\xff\xff\xff", 1)
        w.finish()
    items = list(LogReader(path).messages([T.PTZ_ENCODERS]))
    assert items[0].decode().pan == 1.0
    with pytest.raises(LogError, match=r"message 1 on topic /ptz/encoders cannot be decoded as trackreplay.PtzEncoders"):
        items[1].decode()
