"""Turn image messages back into pixels, checking what the log claims."""

from __future__ import annotations

import os
import struct

import cv2
import numpy as np

from trackreplay.schemas.errors import LogError

_RAW_CHANNELS = {"mono8": 1, "8UC1": 1, "bgr8": 3, "rgb8": 3, "8UC3": 3, "bgra8": 4, "rgba8": 4}
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


def _check_size(width: int, height: int, where: str, what: str) -> None:
    limit = max_image_pixels()
    if width * height > limit:
        raise LogError(f"{where}: {what} claims {width}x{height} pixels, more than the {limit} allowed "
                       f"(TRACKREPLAY_MAX_IMAGE_PIXELS raises the limit)")


def decode_image(pb, schema: str, where: str) -> tuple[np.ndarray, bytes | None, str | None]:
    """Pixels (BGR or grey uint8), the original encoded bytes, and their format.

    ``where`` names the file, topic and message index for error messages.
    """
    if schema == "foxglove.CompressedImage":
        size = encoded_size(pb.data)
        if size is not None:
            _check_size(*size, where, f"{pb.format or 'image'} header")
        buf = np.frombuffer(pb.data, dtype=np.uint8)
        image = cv2.imdecode(buf, cv2.IMREAD_UNCHANGED) if buf.size else None
        if image is None:
            raise LogError(f"{where}: {pb.format or 'image'} data ({len(pb.data)} bytes) cannot be decoded")
        if image.ndim == 3 and image.shape[2] == 4:
            image = cv2.cvtColor(image, cv2.COLOR_BGRA2BGR)
        fmt = pb.format.lower().removeprefix("image/")
        return image, bytes(pb.data), "jpeg" if fmt == "jpg" else fmt
    if schema == "foxglove.RawImage":
        channels = _RAW_CHANNELS.get(pb.encoding)
        if channels is None:
            raise LogError(f"{where}: raw image encoding {pb.encoding!r} is not supported (use mono8, bgr8 or rgb8)")
        row = pb.width * channels
        step = pb.step or row
        if pb.width == 0 or pb.height == 0 or step < row or len(pb.data) < step * (pb.height - 1) + row:
            raise LogError(
                f"{where}: raw image claims {pb.width}x{pb.height} {pb.encoding} but holds {len(pb.data)} bytes"
            )
        _check_size(pb.width, pb.height, where, "raw image")
        flat = np.frombuffer(pb.data, dtype=np.uint8)
        # Rows `step` apart inside the payload (checked above): a view, so a huge claimed step allocates nothing.
        image = np.lib.stride_tricks.as_strided(flat, shape=(pb.height, row), strides=(step, 1), writeable=False)
        image = image.reshape(pb.height, pb.width) if channels == 1 else image.reshape(pb.height, pb.width, channels)
        if pb.encoding in ("rgb8",):
            image = cv2.cvtColor(image, cv2.COLOR_RGB2BGR)
        elif channels == 4:
            image = cv2.cvtColor(image, cv2.COLOR_RGBA2BGR if pb.encoding == "rgba8" else cv2.COLOR_BGRA2BGR)
        return np.ascontiguousarray(image), None, None
    raise LogError(f"{where}: schema {schema} is not an image schema (expected foxglove.CompressedImage or foxglove.RawImage)")
