"""ROS 2 bags written with the ROS 2 MCAP writer (``mcap-ros2-support``), as rosbag2 writes them:
``sensor_msgs/msg/Image`` / ``CompressedImage`` / ``CameraInfo`` in CDR with ``ros2msg`` schemas
(the full definition text, ``builtin_interfaces/Time`` included, as Rerun needs)."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
from mcap.reader import make_reader
from mcap_ros2.writer import Writer as Ros2Writer

_SEP = "=" * 80 + "\n"
_HEADER = (_SEP + "MSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n"
           + _SEP + "MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n")
IMAGE = ("std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\nuint8 is_bigendian\nuint32 step\n"
         "uint8[] data\n" + _HEADER)
COMPRESSED = "std_msgs/Header header\nstring format\nuint8[] data\n" + _HEADER
CAMERA_INFO = ("std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\nfloat64[] d\n"
               "float64[9] k\nfloat64[9] r\nfloat64[12] p\nuint32 binning_x\nuint32 binning_y\n"
               "sensor_msgs/RegionOfInterest roi\n" + _SEP
               + "MSG: sensor_msgs/RegionOfInterest\nuint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\n"
                 "bool do_rectify\n" + _HEADER)


def header(t_ns: int, frame_id: str = "camera") -> dict:
    return {"stamp": {"sec": t_ns // 10**9, "nanosec": t_ns % 10**9}, "frame_id": frame_id}


class BagWriter:
    """Thin helper over the ROS 2 writer: one schema per type, messages by topic."""

    def __init__(self, path: Path) -> None:
        self._fh = open(path, "wb")
        self.writer = Ros2Writer(self._fh)
        self.schemas = {
            "image": self.writer.register_msgdef("sensor_msgs/msg/Image", IMAGE),
            "compressed": self.writer.register_msgdef("sensor_msgs/msg/CompressedImage", COMPRESSED),
            "info": self.writer.register_msgdef("sensor_msgs/msg/CameraInfo", CAMERA_INFO),
        }
        self._seq: dict[str, int] = {}

    def _write(self, topic: str, kind: str, msg: dict, t_ns: int) -> None:
        seq = self._seq.get(topic, 0)
        self.writer.write_message(topic, self.schemas[kind], msg, log_time=t_ns, publish_time=t_ns, sequence=seq)
        self._seq[topic] = seq + 1

    def raw(self, topic: str, image: np.ndarray, t_ns: int, encoding: str = "rgb8") -> None:
        """``image`` BGR or grey uint8 (uint16 for mono16), stored in ``encoding``."""
        if encoding == "rgb8":
            data = cv2.cvtColor(image, cv2.COLOR_BGR2RGB)
        else:
            data = image
        data = np.ascontiguousarray(data)
        h, w = data.shape[:2]
        self._write(topic, "image", {"header": header(t_ns), "height": h, "width": w, "encoding": encoding,
                                     "is_bigendian": 0, "step": data.strides[0], "data": data.tobytes()}, t_ns)

    def compressed(self, topic: str, data: bytes, t_ns: int, fmt: str = "jpeg") -> None:
        self._write(topic, "compressed", {"header": header(t_ns), "format": fmt, "data": data}, t_ns)

    def camera_info(self, topic: str, t_ns: int, width: int, height: int, f: float, cx: float, cy: float,
                    tx: float = 0.0) -> None:
        self._write(topic, "info", {
            "header": header(t_ns), "height": height, "width": width, "distortion_model": "plumb_bob",
            "d": [0.0] * 5, "k": [f, 0, cx, 0, f, cy, 0, 0, 1], "r": [1, 0, 0, 0, 1, 0, 0, 0, 1],
            "p": [f, 0, cx, tx, 0, f, cy, 0, 0, 0, 1, 0], "binning_x": 0, "binning_y": 0,
            "roi": {"x_offset": 0, "y_offset": 0, "height": 0, "width": 0, "do_rectify": False}}, t_ns)

    def close(self) -> None:
        self.writer.finish()
        self._fh.close()


def bag_from_log(src: Path, dst: Path, kind: str, topic: str = "/cam/image_raw") -> int:
    """Our log's ``/camera/image`` as a ROS 2 bag on ``topic``: ``compressed`` keeps the JPEG bytes,
    ``raw`` stores the decoded pixels as rgb8. Every other channel of ``src`` (marks, truth) is
    copied as it is (protobuf beside CDR, as a bag that was annotated). Returns the image count."""
    from trackreplay.replay.log.decode import decode_image
    from trackreplay.replay.log.reader import LogReader

    reader = LogReader(src)
    bag = BagWriter(dst)
    n = 0
    for item in reader.messages(["/camera/image"]):
        pb = item.decode()
        if kind == "compressed":
            bag.compressed(topic, bytes(pb.data), item.log_time, pb.format)
        else:
            bag.raw(topic, decode_image(pb, item.schema, "test")[0], item.log_time)
        n += 1
    w = bag.writer._writer  # the underlying mcap Writer: copy our other channels verbatim
    with open(src, "rb") as fh:
        ids: dict[int, int] = {}
        for schema, channel, msg in make_reader(fh).iter_messages(log_time_order=True):
            if channel.topic == "/camera/image":
                continue
            if channel.id not in ids:
                sid = w.register_schema(schema.name, schema.encoding, schema.data)
                ids[channel.id] = w.register_channel(channel.topic, channel.message_encoding, sid)
            w.add_message(ids[channel.id], msg.log_time, msg.data, msg.publish_time, msg.sequence)
    bag.close()
    return n
