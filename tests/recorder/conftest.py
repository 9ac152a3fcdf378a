"""Small inputs generated in tmp_path, and a reader that decodes a whole (small) log."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pytest
from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory


@dataclass(frozen=True)
class Msg:
    topic: str
    schema: str
    log_time: int
    pb: Any


def read_all(path: Path) -> list[Msg]:
    with open(path, "rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        assert reader.get_summary() is not None  # a valid, finished log
        return [
            Msg(ch.topic, schema.name, msg.log_time, pb)
            for schema, ch, msg, pb in reader.iter_decoded_messages(log_time_order=True)
        ]


def pattern(i: int, w: int = 64, h: int = 48) -> np.ndarray:
    """A distinct, JPEG-friendly BGR image per index."""
    yy, xx = np.mgrid[0:h, 0:w]
    img = np.stack([(xx * 4 + i * 7) % 256, (yy * 5 + i * 11) % 256, np.full_like(xx, (i * 29) % 256)], axis=-1)
    return img.astype(np.uint8)


@pytest.fixture
def log_messages() -> Callable[[Path], list[Msg]]:
    return read_all


@pytest.fixture
def make_images() -> Callable[..., Path]:
    def make(folder: Path, n: int, ext: str = "jpg", size: tuple[int, int] = (64, 48), names: str = "frame{i}") -> Path:
        folder.mkdir(parents=True, exist_ok=True)
        for i in range(n):
            cv2.imwrite(str(folder / f"{names.format(i=i)}.{ext}"), pattern(i, *size))
        return folder

    return make


@pytest.fixture
def make_video() -> Callable[..., Path]:
    def make(path: Path, n: int, fps: float = 25.0, size: tuple[int, int] = (64, 48), fourcc: str = "FFV1") -> Path:
        vw = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*fourcc), fps, size)
        assert vw.isOpened()
        for i in range(n):
            vw.write(pattern(i, *size))
        vw.release()
        return path

    return make


def decode(pb: Any, schema: str) -> np.ndarray:
    if schema == "foxglove.RawImage":
        ch = 1 if pb.encoding == "mono8" else 3
        return np.frombuffer(pb.data, np.uint8).reshape(pb.height, pb.width, ch).squeeze()
    return cv2.imdecode(np.frombuffer(pb.data, np.uint8), cv2.IMREAD_UNCHANGED)


@pytest.fixture
def decode_image() -> Callable[[Any, str], np.ndarray]:
    return decode
