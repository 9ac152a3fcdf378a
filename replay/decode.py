"""Turn image messages back into pixels, checking what the log claims."""

from __future__ import annotations

import cv2
import numpy as np

from trackreplay.schemas.errors import LogError

_RAW_CHANNELS = {"mono8": 1, "8UC1": 1, "bgr8": 3, "rgb8": 3, "8UC3": 3, "bgra8": 4, "rgba8": 4}


def decode_image(pb, schema: str, where: str) -> tuple[np.ndarray, bytes | None, str | None]:
    """Pixels (BGR or grey uint8), the original encoded bytes, and their format.

    ``where`` names the file, topic and message index for error messages.
    """
    if schema == "foxglove.CompressedImage":
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
        flat = np.frombuffer(pb.data, dtype=np.uint8)
        padded = np.pad(flat, (0, max(0, step * pb.height - flat.size)))
        image = padded[: step * pb.height].reshape(pb.height, step)[:, :row]
        image = image.reshape(pb.height, pb.width) if channels == 1 else image.reshape(pb.height, pb.width, channels)
        if pb.encoding in ("rgb8",):
            image = cv2.cvtColor(image, cv2.COLOR_RGB2BGR)
        elif channels == 4:
            image = cv2.cvtColor(image, cv2.COLOR_RGBA2BGR if pb.encoding == "rgba8" else cv2.COLOR_BGRA2BGR)
        return np.ascontiguousarray(image), None, None
    raise LogError(f"{where}: schema {schema} is not an image schema (expected foxglove.CompressedImage or foxglove.RawImage)")
