"""An image folder in natural order (frame2 before frame10).

JPEG and PNG files keep their bytes (judged by content, not extension); BMP files are
decoded and re-encoded as the recording asks. Every image must have the first one's size.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import cv2
import numpy as np

from trackreplay.recorder.sources.base import FrameClock, ImageFrame, encoded_format, natural_key
from trackreplay.schemas.errors import SourceError

EXTENSIONS = (".jpg", ".jpeg", ".png", ".bmp")


def list_images(folder: str | Path) -> list[Path]:
    """Image files of ``folder`` (not recursive), naturally sorted."""
    folder = Path(folder)
    if not folder.is_dir():
        raise SourceError(f"image folder {folder} does not exist or is not a folder")
    files = sorted((p for p in folder.iterdir() if p.suffix.lower() in EXTENSIONS and p.is_file()), key=natural_key)
    if not files:
        raise SourceError(f"image folder {folder} holds no {'/'.join(e[1:] for e in EXTENSIONS)} files")
    return files


def decode_image(path: Path, data: bytes) -> np.ndarray:
    """``data`` decoded to uint8 BGR or grey; alpha is dropped."""
    if not data:  # (OpenCV asserts on an empty buffer instead of answering None)
        raise SourceError(f"image {path} is empty (0 bytes)")
    image = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_UNCHANGED)
    if image is None:
        raise SourceError(f"image {path} cannot be decoded (corrupt or not an image)")
    if image.dtype != np.uint8:
        raise SourceError(f"image {path} has {image.dtype} pixels; only 8-bit images are supported")
    if image.ndim == 3 and image.shape[2] == 4:
        image = cv2.cvtColor(image, cv2.COLOR_BGRA2BGR)
    return image


def check_count(files: list[Path], clock: FrameClock, folder: str | Path) -> None:
    if clock.timestamps is not None and len(clock.timestamps) != len(files):
        raise SourceError(
            f"{clock.timestamps_path} has {len(clock.timestamps)} timestamps but {folder} has {len(files)} images"
        )


def read_image_files(files: list[Path], clock: FrameClock) -> Iterator[ImageFrame]:
    """One frame per file, in the given order."""
    size: tuple[int, int] | None = None
    for index, path in enumerate(files):
        try:
            data = path.read_bytes()
        except OSError as err:
            raise SourceError(f"image {path} cannot be read ({err.strerror})") from None
        pixels = decode_image(path, data)
        fmt = encoded_format(data)
        frame = ImageFrame(index, clock.t_ns(index), str(path), pixels, data if fmt else None, fmt)
        if size is None:
            size = frame.size
        elif frame.size != size:
            raise SourceError(
                f"image {path} is {frame.size[0]}x{frame.size[1]} but {files[0].name} is {size[0]}x{size[1]}"
            )
        yield frame


def read_images(folder: str | Path, clock: FrameClock) -> Iterator[ImageFrame]:
    """Frames of ``folder``; the timestamp count is checked before the first frame."""
    files = list_images(folder)
    check_count(files, clock, folder)
    yield from read_image_files(files, clock)
