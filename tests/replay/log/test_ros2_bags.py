"""ROS 2 image bags replay: sensor_msgs/msg/Image and CompressedImage (CDR), CameraInfo, stereo
from two image topics, Foxglove JSON images; topics chosen automatically or by name."""

from __future__ import annotations

import base64
import json
from pathlib import Path

import cv2
import numpy as np
import pytest
from mcap.writer import Writer

from trackreplay.replay.cli.main import main
from trackreplay.replay.log.decode import decode_image
from trackreplay.replay.core.engine import ReplayRequest, replay
from trackreplay.replay.log.frames import FrameTopics, iter_frames
from trackreplay.replay.log.reader import LogReader
from trackreplay.schemas.errors import LogError



def _load_helpers():
    import importlib.util

    spec = importlib.util.spec_from_file_location("ros2_bags", Path(__file__).with_name("ros2_bags.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


_helpers = _load_helpers()
BagWriter, bag_from_log = _helpers.BagWriter, _helpers.bag_from_log

GOLDEN = Path(__file__).resolve().parents[2] / "golden"


@pytest.mark.parametrize("tracker,log", [("flow", "flow-sim1-24f.mcap"), ("golf", "golf-teeshot-640x360.mcap")])
@pytest.mark.parametrize("kind", ["compressed", "raw"])
def test_ros2_image_bag_replays_like_the_source(tmp_path: Path, tracker: str, log: str, kind: str) -> None:
    src = GOLDEN / log
    bag = tmp_path / f"{kind}.mcap"
    n = bag_from_log(src, bag, kind)
    topics = LogReader(bag).topics()
    assert topics["/cam/image_raw"].schema == ("sensor_msgs/msg/CompressedImage" if kind == "compressed" else "sensor_msgs/msg/Image")
    assert topics["/cam/image_raw"].encoding == "cdr"
    first = replay(ReplayRequest(log=bag, tracker=tracker, seed=0, prefetch=0))
    again = replay(ReplayRequest(log=bag, tracker=tracker, seed=0))
    assert first.frames == n and first.digest == again.digest
    source = replay(ReplayRequest(log=src, tracker=tracker, seed=0))
    # Same pixels, same marks: the same trajectory as our own log.
    assert first.trajectory.drop("t_ns").equals(source.trajectory.drop("t_ns"))


def _scene(i: int) -> np.ndarray:
    image = np.zeros((48, 64, 3), np.uint8)
    image[:, :, 0] = np.arange(64, dtype=np.uint8)[None, :] * 3
    image[:, :, 1] = np.arange(48, dtype=np.uint8)[:, None] * 5
    image[10:20, 10 + i:20 + i, 2] = 250
    return image


def test_raw_encodings_decode(tmp_path: Path) -> None:
    bgr = _scene(0)
    bag = tmp_path / "enc.mcap"
    w = BagWriter(bag)
    w.raw("/rgb", bgr, 1, "rgb8")
    w.raw("/bgr", bgr, 1, "bgr8")
    grey = cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY)
    w.raw("/mono", grey, 1, "mono8")
    w.raw("/mono16", grey.astype(np.uint16) << 8, 1, "mono16")
    mosaic = np.zeros(bgr.shape[:2], np.uint8)  # RGGB Bayer mosaic of bgr
    mosaic[0::2, 0::2] = bgr[0::2, 0::2, 2]
    mosaic[0::2, 1::2] = bgr[0::2, 1::2, 1]
    mosaic[1::2, 0::2] = bgr[1::2, 0::2, 1]
    mosaic[1::2, 1::2] = bgr[1::2, 1::2, 0]
    w.raw("/bayer", mosaic, 1, "bayer_rggb8")
    ok, png = cv2.imencode(".png", bgr)
    w.compressed("/png", png.tobytes(), 1, "png")
    w.compressed("/transport", cv2.imencode(".jpg", bgr)[1].tobytes(), 1, "rgb8; jpeg compressed bgr8")
    w.close()
    reader = LogReader(bag)

    def pixels(topic):
        item = next(reader.messages([topic]))
        return decode_image(item.decode(), item.schema, topic)[0]

    assert np.array_equal(pixels("/rgb"), bgr) and np.array_equal(pixels("/bgr"), bgr)
    assert np.array_equal(pixels("/mono"), grey) and np.array_equal(pixels("/mono16"), grey)
    assert np.array_equal(pixels("/png"), bgr)
    assert np.abs(pixels("/transport").astype(int) - bgr).mean() < 3
    bayer = pixels("/bayer")  # demosaiced: the channels must not be swapped (red box stays red)
    assert bayer.shape == bgr.shape and bayer[12:18, 12:18, 2].mean() > 200 and bayer[12:18, 12:18, 0].mean() < 120


def _stereo_bag(path: Path, frames: int = 5, with_info: bool = True) -> None:
    w = BagWriter(path)
    for i in range(frames):
        t = 10**9 + i * 50_000_000
        if with_info and i == 0:
            w.camera_info("/stereo_cam/left/camera_info", t, 64, 48, 80.0, 32.0, 24.0)
            w.camera_info("/stereo_cam/right/camera_info", t, 64, 48, 80.0, 32.0, 24.0, tx=-80.0 * 0.12)
        w.raw("/stereo_cam/left/image_rect", _scene(i), t, "bgr8")
        w.raw("/stereo_cam/right/image_rect", _scene(i + 2), t, "bgr8")
    w.close()


def test_stereo_pair_from_two_image_topics(tmp_path: Path) -> None:
    bag = tmp_path / "stereo.mcap"
    _stereo_bag(bag)
    reader = LogReader(bag)
    with pytest.raises(LogError, match="2 image topics .*--stereo-topics LEFT RIGHT"):
        FrameTopics.detect(reader)
    topics = FrameTopics.detect(reader, stereo=("/stereo_cam/left/image_rect", "/stereo_cam/right/image_rect"))
    frames = list(iter_frames(reader, topics))
    assert len(frames) == 5 and all(f.right is not None for f in frames)
    assert np.array_equal(frames[1].right, _scene(3))
    rig = frames[0].stereo  # from the sibling CameraInfo topics' p: f, cx, cy and the baseline -p[3]/p[0]
    assert topics.left_calibration == "/stereo_cam/left/camera_info"
    assert (rig.f, rig.cx, rig.cy) == (80.0, 32.0, 24.0) and rig.baseline == pytest.approx(0.12)
    single = FrameTopics.detect(reader, "/stereo_cam/right/image_rect")
    assert single.right is None and len(list(iter_frames(reader, single))) == 5
    with pytest.raises(LogError, match="holds sensor_msgs/msg/CameraInfo, not images"):
        FrameTopics.detect(reader, "/stereo_cam/left/camera_info")


def _foxglove_json_log(path: Path, frames: int = 4) -> None:
    with open(path, "wb") as fh:
        w = Writer(fh)
        w.start(profile="", library="test")
        cs = w.register_schema("foxglove.CompressedImage", "jsonschema", b'{"type":"object"}')
        rs = w.register_schema("foxglove.RawImage", "jsonschema", b'{"type":"object"}')
        cc = w.register_channel("/json/compressed", "json", cs)
        rc = w.register_channel("/json/raw", "json", rs)
        for i in range(frames):
            t = 1000 + i * 33_000_000
            image = _scene(i)
            jpeg = cv2.imencode(".png", image)[1].tobytes()
            stamp = {"sec": 0, "nsec": t}
            w.add_message(cc, t, json.dumps({"timestamp": stamp, "frame_id": "cam", "format": "png",
                                             "data": base64.b64encode(jpeg).decode()}).encode(), t, i)
            w.add_message(rc, t, json.dumps({"timestamp": stamp, "frame_id": "cam", "width": 64, "height": 48,
                                             "encoding": "rgb8", "step": 192,
                                             "data": base64.b64encode(cv2.cvtColor(image, cv2.COLOR_BGR2RGB).tobytes()).decode()
                                             }).encode(), t, i)
        w.finish()


def test_foxglove_json_images(tmp_path: Path) -> None:
    log = tmp_path / "json.mcap"
    _foxglove_json_log(log)
    reader = LogReader(log)
    for topic in ("/json/compressed", "/json/raw"):
        frames = list(iter_frames(reader, FrameTopics.detect(reader, topic)))
        assert len(frames) == 4 and np.array_equal(frames[2].image, _scene(2))


def test_cli_auto_topic_and_annotate_a_ros_bag(tmp_path: Path, capsys) -> None:
    bag = tmp_path / "one.mcap"
    w = BagWriter(bag)
    for i in range(6):
        w.raw("/camera/color/image_raw", _scene(i), 10**9 + i * 33_333_333, "rgb8")
    w.close()
    marked = tmp_path / "marked.mcap"
    assert main(["annotate", str(bag), "--frame", "0", "--box", "10,10,10,10", "--out", str(marked)]) == 0
    assert main(["replay", str(marked), "--tracker", "flow", "--quiet"]) == 0
    assert "flow: 6 frames" in capsys.readouterr().out
