"""Images as Foxglove messages: JPEG/PNG bytes kept as they are, or raw pixels."""

from __future__ import annotations

import cv2
import numpy as np

from trackreplay.schemas import messages as m
from trackreplay.schemas.records import timestamp

ENCODINGS = ("jpeg", "png", "raw")


def compressed_image(data: bytes, fmt: str, t_ns: int, frame_id: str = "camera") -> m.CompressedImage:
    """Wrap already-encoded bytes (``fmt`` is ``"jpeg"`` or ``"png"``) without touching them."""
    return m.CompressedImage(timestamp=timestamp(t_ns), frame_id=frame_id, data=data, format=fmt)


def image_message(
    image: np.ndarray, encoding: str, t_ns: int, *, frame_id: str = "camera", jpeg_quality: int = 95
) -> m.CompressedImage | m.RawImage:
    """Encode a BGR or grey ``uint8`` image as ``jpeg``, ``png`` or ``raw``."""
    if image.dtype != np.uint8 or image.ndim not in (2, 3):
        raise ValueError(f"expected a uint8 grey or BGR image, got {image.dtype} with shape {image.shape}")
    if encoding == "jpeg":
        ok, buf = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, jpeg_quality])
    elif encoding == "png":
        ok, buf = cv2.imencode(".png", image, [cv2.IMWRITE_PNG_COMPRESSION, 1])
    elif encoding == "raw":
        h, w = image.shape[:2]
        mono = image.ndim == 2
        return m.RawImage(
            timestamp=timestamp(t_ns),
            frame_id=frame_id,
            width=w,
            height=h,
            encoding="mono8" if mono else "bgr8",
            step=w * (1 if mono else 3),
            data=np.ascontiguousarray(image).tobytes(),
        )
    else:
        raise ValueError(f"image encoding must be one of {ENCODINGS}, not {encoding!r}")
    if not ok:
        raise ValueError(f"OpenCV could not encode a {image.shape} image as {encoding}")
    return compressed_image(buf.tobytes(), encoding, t_ns, frame_id)
