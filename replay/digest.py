"""The replay digest: sha256 over every frame's tracker outputs, then the trajectory table."""

from __future__ import annotations

import dataclasses
import hashlib
from typing import Any

import numpy as np
import polars as pl

from replay.trajectory import canonical_bytes


def _feed(h: "hashlib._Hash", name: str, value: Any) -> None:
    h.update(name.encode() + b"\0")
    if isinstance(value, np.ndarray):
        arr = np.ascontiguousarray(value)
        h.update(f"{arr.dtype.str}{arr.shape}".encode())
        h.update(arr.tobytes())
    elif isinstance(value, (bool, int, np.integer)):
        h.update(np.int64(value).tobytes())
    elif isinstance(value, (float, np.floating)):
        h.update(np.float64(value).tobytes())
    elif isinstance(value, str):
        h.update(value.encode())
    elif value is None:
        h.update(b"<none>")
    elif dataclasses.is_dataclass(value):
        for f in dataclasses.fields(value):
            _feed(h, f.name, getattr(value, f.name))
    elif isinstance(value, (tuple, list)):
        h.update(np.int64(len(value)).tobytes())
        for i, item in enumerate(value):
            _feed(h, str(i), item)
    elif isinstance(value, dict):
        for key in sorted(value):
            _feed(h, str(key), value[key])
    else:
        raise TypeError(f"cannot digest {type(value).__name__} in field {name}")


class ReplayDigest:
    """Accumulates per-frame outputs in replay order; ``finish`` adds the trajectory table."""

    def __init__(self) -> None:
        self._h = hashlib.sha256(b"trackreplay-digest-v1")

    def add_frame(self, index: int, intermediates: Any) -> None:
        _feed(self._h, f"frame{index}", intermediates)

    def finish(self, table: pl.DataFrame) -> str:
        self._h.update(canonical_bytes(table))
        return self._h.hexdigest()
