"""The replay digest: sha256 over every frame's tracker outputs, then the trajectory table.

Floats are hashed after :func:`portable_floats`: rounded to float32 (24-bit mantissa) with
magnitudes below 1e-9 flushed to zero. numpy and OpenCV pick SIMD kernels (AVX2, AVX-512 …) at
run time, and those differ in the last bits of ``exp``, ``sin`` or a reduction; bit-exact hashing
would make the same replay hash differently on two CPUs. Measured on the golden golf log: with
numpy's AVX-512 kernels switched off the trajectory moves by at most 3e-17 px and the raw-bits
digest changes; the rounded digest does not. Any change of a tracker's behaviour is far larger.
"""

from __future__ import annotations

import dataclasses
import hashlib
from typing import Any

import numpy as np
import polars as pl

from trackreplay.replay.trajectory import canonical_bytes


def portable_floats(values: np.ndarray) -> np.ndarray:
    """Float values as hashed: float32 rounding, |v| < 1e-9 to 0, one NaN bit pattern."""
    a = np.asarray(values, dtype=np.float64)
    a = np.where(np.abs(a) < 1e-9, 0.0, a).astype("<f4")
    a[np.isnan(a)] = np.float32("nan")
    return a


def _feed(h: "hashlib._Hash", name: str, value: Any) -> None:
    h.update(name.encode() + b"\0")
    if isinstance(value, np.ndarray):
        arr = np.ascontiguousarray(value)
        if arr.dtype.kind in "fc":
            arr = portable_floats(arr.real if arr.dtype.kind == "f" else np.stack([arr.real, arr.imag]))
        h.update(f"{arr.dtype.str}{arr.shape}".encode())
        h.update(arr.tobytes())
    elif isinstance(value, (bool, int, np.integer)):
        h.update(np.int64(value).tobytes())
    elif isinstance(value, (float, np.floating)):
        h.update(portable_floats(np.float64(value)).tobytes())
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
        self._h = hashlib.sha256(b"trackreplay-digest-v2")

    def add_frame(self, index: int, intermediates: Any) -> None:
        _feed(self._h, f"frame{index}", intermediates)

    def finish(self, table: pl.DataFrame) -> str:
        self._h.update(canonical_bytes(table, float_bytes=lambda v: portable_floats(v).tobytes()))
        return self._h.hexdigest()
