"""Image sizes are checked from headers and fields before any pixel memory is allocated."""

from __future__ import annotations

import struct
import tracemalloc

import cv2
import numpy as np
import pytest
from foxglove_schemas_protobuf.CompressedImage_pb2 import CompressedImage
from foxglove_schemas_protobuf.RawImage_pb2 import RawImage

from trackreplay.replay.log.decode import decode_image, encoded_size
from trackreplay.schemas.errors import LogError


def test_header_sizes_of_real_encodings() -> None:
    img = np.zeros((37, 53, 3), np.uint8)
    for ext in (".png", ".jpg"):
        ok, buf = cv2.imencode(ext, img)
        assert encoded_size(buf.tobytes()) == (53, 37)
    assert encoded_size(b"not an image") is None


def test_a_tiny_jpeg_claiming_30000_squared_is_refused_before_decoding() -> None:
    ok, buf = cv2.imencode(".jpg", np.zeros((8, 8, 3), np.uint8))
    data = bytearray(buf.tobytes())
    sof = data.index(b"\xff\xc0")
    data[sof + 5:sof + 9] = struct.pack(">HH", 30000, 30000)
    tracemalloc.start()
    with pytest.raises(LogError, match=r"jpeg header claims 30000x30000 pixels, more than the \d+ allowed"):
        decode_image(CompressedImage(data=bytes(data), format="jpeg"), "foxglove.CompressedImage", "log: message 0")
    assert tracemalloc.get_traced_memory()[1] < 50_000_000
    tracemalloc.stop()


def test_a_png_claiming_16000_squared_is_refused(monkeypatch) -> None:
    ok, buf = cv2.imencode(".png", np.zeros((4, 4), np.uint8))
    data = bytearray(buf.tobytes())
    data[16:24] = struct.pack(">II", 16000, 16000)
    monkeypatch.setenv("TRACKREPLAY_MAX_IMAGE_PIXELS", str(4000 * 4000))
    with pytest.raises(LogError, match="png header claims 16000x16000 pixels, more than the 16000000 allowed"):
        decode_image(CompressedImage(data=bytes(data), format="png"), "foxglove.CompressedImage", "log: message 0")


def test_a_raw_image_with_a_huge_step_allocates_nothing() -> None:
    pb = RawImage(width=1, height=1, encoding="mono8", step=4_000_000_000, data=b"\x07\x08\x09")
    tracemalloc.start()
    image, _, _ = decode_image(pb, "foxglove.RawImage", "log: message 0")
    assert tracemalloc.get_traced_memory()[1] < 1_000_000
    tracemalloc.stop()
    assert image.tolist() == [[7]]
    too_tall = RawImage(width=1, height=2, encoding="mono8", step=4_000_000_000, data=b"\x07\x08\x09")
    with pytest.raises(LogError, match="raw image claims 1x2 mono8 but holds 3 bytes"):
        decode_image(too_tall, "foxglove.RawImage", "log: message 0")


def test_raw_rows_with_padding_are_read_at_their_step() -> None:
    rows = np.arange(2 * 5, dtype=np.uint8).reshape(2, 5)
    pb = RawImage(width=3, height=2, encoding="mono8", step=5, data=rows.tobytes()[:8])
    image, _, _ = decode_image(pb, "foxglove.RawImage", "log: message 0")
    assert image.tolist() == [[0, 1, 2], [5, 6, 7]]


def _claiming(width: int, height: int, ext: str = ".png") -> bytes:
    """A small real picture whose header says ``width`` x ``height`` (its pixels do not)."""
    ok, buf = cv2.imencode(ext, np.zeros((8, 8), np.uint8))
    data = bytearray(buf.tobytes())
    if ext == ".png":
        data[16:24] = struct.pack(">II", width, height)
    else:
        sof = data.index(b"\xff\xc0")
        data[sof + 5:sof + 9] = struct.pack(">HH", height, width)
    return bytes(data)


@pytest.mark.parametrize("ext, name", [(".png", "png"), (".jpg", "jpeg")])
def test_a_frame_claiming_another_size_than_the_log_is_refused_before_decoding(monkeypatch, ext: str, name: str) -> None:
    """16000² is within the pixel limit: only the log's own frame size refuses it, before cv2.imdecode runs."""
    from trackreplay.replay.log import decode

    def no_decode(*args):
        raise AssertionError("decoded")

    monkeypatch.setattr(decode.cv2, "imdecode", no_decode)
    pb = CompressedImage(data=_claiming(16000, 16000, ext), format=name)
    with pytest.raises(decode.SizeMismatch, match=r"message 1 is 16000x16000 but earlier images are 640x480 "
                                                  rf"\(its {name} header; refused before decoding\)"):
        decode_image(pb, "foxglove.CompressedImage", "log: message 1", expect=(640, 480))
    raw = RawImage(width=640, height=481, encoding="mono8", step=640, data=bytes(640 * 481))
    with pytest.raises(decode.SizeMismatch, match="is 640x481 but earlier images are 640x480"):
        decode_image(raw, "foxglove.RawImage", "log: message 1", expect=(640, 480))


def test_a_replay_refuses_the_odd_frame_without_decoding_it(tmp_path, monkeypatch) -> None:
    from trackreplay.recorder.image_codec import compressed_image, image_message
    from trackreplay.recorder.writer import LogWriter
    from trackreplay.replay.log import decode
    from trackreplay.replay.log.frames import FrameTopics, iter_frames
    from trackreplay.replay.log.reader import LogReader
    from trackreplay.schemas import topics as T

    path = tmp_path / "odd.mcap"
    with LogWriter(path) as log:
        log.write(T.CAMERA_IMAGE, image_message(np.zeros((8, 8), np.uint8), "png", 0), 0)
        log.write(T.CAMERA_IMAGE, compressed_image(_claiming(16000, 16000), "png", 1000, "camera"), 1000)
    decoded: list[int] = []
    real = decode.cv2.imdecode
    monkeypatch.setattr(decode.cv2, "imdecode", lambda buf, flags: decoded.append(buf.size) or real(buf, flags))
    reader = LogReader(path)
    frames = iter_frames(reader, FrameTopics.detect(reader))
    assert next(frames).index == 0
    with pytest.raises(LogError, match="message 1 is 16000x16000 but earlier images are 8x8"):
        next(frames)
    assert len(decoded) == 1  # the first frame only


def test_decoding_allocates_one_picture() -> None:
    """The bound docs/memory.md states per frame: decoding a W x H x C picture allocates W·H·C bytes
    (the pixels), not a multiple of it."""
    image = np.random.default_rng(0).integers(0, 255, (600, 800, 3), dtype=np.uint8)
    pb = CompressedImage(data=cv2.imencode(".png", image)[1].tobytes(), format="png")
    tracemalloc.start()
    pixels, _, _ = decode_image(pb, "foxglove.CompressedImage", "log: message 0", expect=(800, 600))
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert pixels.shape == (600, 800, 3)
    assert peak < 1.1 * image.nbytes + len(pb.data) + 100_000, peak
