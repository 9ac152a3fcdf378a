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
