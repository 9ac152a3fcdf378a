"""Turn image messages back into pixels, checking what the log claims."""

from __future__ import annotations

import base64
import binascii
import os
import struct

import cv2
import numpy as np

from trackreplay.schemas.errors import LogError
from trackreplay.schemas.messages import COMPRESSED_IMAGE_SCHEMAS as COMPRESSED_SCHEMAS
from trackreplay.schemas.messages import IMAGE_SCHEMAS
from trackreplay.schemas.messages import RAW_IMAGE_SCHEMAS as RAW_SCHEMAS

# Largest image decoded (pixels), checked from the header before any pixel memory is allocated:
# a 1 KB JPEG may claim 30000x30000. 2**28 pixels (e.g. 16384 x 16384) is far above any camera we
# record; raise it with the environment variable TRACKREPLAY_MAX_IMAGE_PIXELS.
DEFAULT_MAX_PIXELS = 2**28
_PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
_JPEG_SOF = {0xC0, 0xC1, 0xC2, 0xC3, 0xC5, 0xC6, 0xC7, 0xC9, 0xCA, 0xCB, 0xCD, 0xCE, 0xCF}


def max_image_pixels() -> int:
    value = os.environ.get("TRACKREPLAY_MAX_IMAGE_PIXELS")
    try:
        return max(1, int(value)) if value else DEFAULT_MAX_PIXELS
    except ValueError:
        return DEFAULT_MAX_PIXELS


def encoded_size(data: bytes) -> tuple[int, int] | None:
    """(width, height) from a PNG or JPEG header, without decoding; None when the header is not found."""
    if data[:8] == _PNG_MAGIC and len(data) >= 24 and data[12:16] == b"IHDR":
        return struct.unpack(">II", data[16:24])
    if data[:2] != b"\xff\xd8":
        return None
    i = 2
    while i + 9 <= len(data):
        if data[i] != 0xFF:
            return None
        marker = data[i + 1]
        if marker == 0xFF:  # fill byte
            i += 1
            continue
        if marker in _JPEG_SOF:
            height, width = struct.unpack(">HH", data[i + 5:i + 9])
            return width, height
        if marker in (0xD8, 0x01) or 0xD0 <= marker <= 0xD7:  # markers without a length
            i += 2
            continue
        i += 2 + struct.unpack(">H", data[i + 2:i + 4])[0]
    return None


class SizeMismatch(LogError):
    """An image whose header claims another size than the log's earlier images (refused before decoding)."""


def _check_size(width: int, height: int, where: str, what: str, expect: tuple[int, int] | None = None) -> None:
    """The claimed size against the log's frame size ``expect`` (width, height) when known, then against
    the pixel limit: both before any pixel memory is allocated."""
    if expect is not None and (width, height) != tuple(expect):
        raise SizeMismatch(f"{where} is {width}x{height} but earlier images are {expect[0]}x{expect[1]} "
                           f"(its {what}; refused before decoding)")
    limit = max_image_pixels()
    if width * height > limit:
        raise LogError(f"{where}: {what} claims {width}x{height} pixels, more than the {limit} allowed "
                       f"(TRACKREPLAY_MAX_IMAGE_PIXELS raises the limit)")



# Raw encodings (ROS 2 sensor_msgs/image_encodings names, which foxglove.RawImage shares):
# bytes per pixel and the OpenCV conversion to BGR (None: kept as it is, grey or BGR).
# 16-bit grey keeps its high byte (value >> 8): trackers work on 8-bit images.
# Bayer: ROS names the first row's first two pixels, OpenCV the second row's second and third
# (cv_bridge's mapping).
_RAW = {
    "mono8": (1, None), "8UC1": (1, None), "mono16": (2, "mono16"), "16UC1": (2, "mono16"),
    "bgr8": (3, None), "8UC3": (3, None), "rgb8": (3, cv2.COLOR_RGB2BGR),
    "bgra8": (4, cv2.COLOR_BGRA2BGR), "8UC4": (4, cv2.COLOR_BGRA2BGR), "rgba8": (4, cv2.COLOR_RGBA2BGR),
    "bayer_rggb8": (1, cv2.COLOR_BayerBG2BGR), "bayer_bggr8": (1, cv2.COLOR_BayerRG2BGR),
    "bayer_gbrg8": (1, cv2.COLOR_BayerGR2BGR), "bayer_grbg8": (1, cv2.COLOR_BayerGB2BGR),
    "yuv422": (2, cv2.COLOR_YUV2BGR_UYVY), "uyvy": (2, cv2.COLOR_YUV2BGR_UYVY),
    "yuv422_yuy2": (2, cv2.COLOR_YUV2BGR_YUY2), "yuyv": (2, cv2.COLOR_YUV2BGR_YUY2),
}
RAW_ENCODINGS = tuple(_RAW)


def payload(value) -> bytes:
    """A message's ``bytes`` field as bytes: protobuf bytes, a ROS 2 uint8[] (bytes or list), or
    the base64 text of a JSON-encoded message."""
    if isinstance(value, (bytes, bytearray, memoryview)):
        return bytes(value)
    if isinstance(value, str):
        try:
            return base64.b64decode(value, validate=True)
        except (ValueError, binascii.Error):
            raise LogError("image data is text but not base64") from None
    if isinstance(value, np.ndarray):
        return value.astype(np.uint8, copy=False).tobytes()
    return bytes(value)


def decode_image(pb, schema: str, where: str,
                 expect: tuple[int, int] | None = None) -> tuple[np.ndarray, bytes | None, str | None]:
    """Pixels (BGR or grey uint8), the original encoded bytes, and their format.

    ``pb`` is a decoded ``foxglove.CompressedImage`` / ``RawImage`` (protobuf or JSON) or a ROS 2
    ``sensor_msgs/msg/CompressedImage`` / ``Image``. ``where`` names the file, topic and message
    index for error messages. ``expect``: the log's frame size (width, height); a PNG or JPEG header
    or raw image claiming another is refused (:class:`SizeMismatch`) before any pixel is allocated, so
    one frame claiming 16000² in a 640×480 log costs nothing (a header that is not found: after decoding).
    """
    try:
        if schema in COMPRESSED_SCHEMAS:
            return _compressed(payload(pb.data), str(pb.format), where, expect)
        if schema in RAW_SCHEMAS:
            return _raw(pb, where, expect), None, None
    except LogError as err:
        if str(err).startswith(where):
            raise
        raise LogError(f"{where}: {err}") from None
    raise LogError(f"{where}: schema {schema} is not an image schema (expected one of {', '.join(IMAGE_SCHEMAS)})")


def _compressed(data: bytes, format_: str, where: str, expect: tuple[int, int] | None) -> tuple[np.ndarray, bytes, str]:
    # ROS image_transport writes e.g. "rgb8; jpeg compressed bgr8" or "16UC1; compressedDepth png"
    # (the latter with a 12-byte header before the PNG).
    name = format_.lower().split(";")[-1].strip().split(" ")[0].removeprefix("image/") or "image"
    if "compresseddepth" in format_.lower():
        at = data.find(_PNG_MAGIC)
        data = data[at:] if at > 0 else data
        name = "png"
    size = encoded_size(data)
    if size is not None:
        _check_size(*size, where, f"{name} header", expect)
    buf = np.frombuffer(data, dtype=np.uint8)
    image = cv2.imdecode(buf, cv2.IMREAD_UNCHANGED) if buf.size else None
    if image is None:
        raise LogError(f"{where}: {format_ or 'image'} data ({len(data)} bytes) cannot be decoded")
    if image.dtype == np.uint16:
        image = (image >> 8).astype(np.uint8)
    if image.ndim == 3 and image.shape[2] == 4:
        image = cv2.cvtColor(image, cv2.COLOR_BGRA2BGR)
    return image, data, "jpeg" if name == "jpg" else name


def _raw(pb, where: str, expect: tuple[int, int] | None = None) -> np.ndarray:
    encoding = str(pb.encoding)
    spec = _RAW.get(encoding)
    if spec is None:
        raise LogError(f"{where}: raw image encoding {encoding!r} is not supported (supported: {', '.join(RAW_ENCODINGS)})")
    size, conversion = spec
    data = payload(pb.data)
    width, height = int(pb.width), int(pb.height)
    row = width * size
    step = int(pb.step) or row
    if width == 0 or height == 0 or step < row or len(data) < step * (height - 1) + row:
        raise LogError(f"{where}: raw image claims {width}x{height} {encoding} but holds {len(data)} bytes")
    _check_size(width, height, where, "raw image", expect)
    flat = np.frombuffer(data, dtype=np.uint8)
    # Rows `step` apart inside the payload (checked above): a view, so a huge claimed step allocates nothing.
    rows = np.lib.stride_tricks.as_strided(flat, shape=(height, row), strides=(step, 1), writeable=False)
    if conversion == "mono16":
        big = bool(getattr(pb, "is_bigendian", False))
        return np.ascontiguousarray(rows[:, 0::2] if big else rows[:, 1::2])  # the high byte of each pixel
    if size == 1:
        image = rows
    elif conversion in (cv2.COLOR_YUV2BGR_UYVY, cv2.COLOR_YUV2BGR_YUY2):
        image = np.ascontiguousarray(rows).reshape(height, width, 2)
    else:
        image = rows.reshape(height, width, size)
    if conversion is not None:
        image = cv2.cvtColor(np.ascontiguousarray(image), conversion)
    return np.ascontiguousarray(image)


def projection(msg) -> list[float] | None:
    """The 3x4 projection matrix (row-major) of a camera calibration: ``P`` of
    ``foxglove.CameraCalibration`` (protobuf or JSON) or ``p`` of ROS 2 ``sensor_msgs/msg/CameraInfo``."""
    for name in ("P", "p"):
        value = getattr(msg, name, None)
        if value is not None and len(value) == 12:
            return [float(v) for v in value]
    return None
