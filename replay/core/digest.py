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
import os
import shutil
import struct
import tempfile
import weakref
from array import array
from collections.abc import Iterator
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np
import polars as pl

from trackreplay.replay.core.trajectory import SpilledTrajectory, canonical_parts, remove_spill


def portable_floats(values: np.ndarray) -> np.ndarray:
    """Float values as hashed: float32 rounding, |v| < 1e-9 to 0, one NaN bit pattern."""
    a = np.asarray(values)
    if a.dtype == np.float32:  # already float32: the same result without the float64 round trip
        out = a.astype("<f4", copy=True)
        out[np.abs(a) <= _TINY32] = 0.0  # |v| < 1e-9 for a float32 v is |v| <= float32(1e-9)
    else:
        a = np.asarray(a, dtype=np.float64)
        out = np.where(np.abs(a) < 1e-9, 0.0, a).astype("<f4")
    out[np.isnan(out)] = np.float32("nan")
    return out


_TINY32 = np.float32(1e-9)  # 9.99999972e-10 < 1e-9, and the next float32 is above 1e-9
_NAN32 = np.float32("nan").tobytes()
_F32 = struct.Struct("<f")
_I64 = struct.Struct("=q")  # native order, as numpy's int64.tobytes()


def _float_bytes(v: float) -> bytes:
    """``portable_floats(np.float64(v)).tobytes()`` for one Python float, without numpy's per-call cost."""
    if v != v:
        return _NAN32
    if abs(v) < 1e-9:
        return b"\0\0\0\0"
    try:
        return _F32.pack(v)  # round to nearest even, as numpy's float64 -> float32 cast
    except OverflowError:  # finite beyond float32: numpy gives ±inf
        return portable_floats(np.float64(v)).tobytes()


def _leaf_bytes(value: Any) -> bytes | None:
    """The hashed bytes of a leaf value (after its name), or None when ``value`` is a container."""
    kind = type(value)
    if kind is float:
        return _float_bytes(value)
    if kind is int or kind is bool:
        try:
            return _I64.pack(value)
        except struct.error:
            return np.int64(value).tobytes()  # raises OverflowError as before
    if kind is str:
        return value.encode()
    if value is None:
        return b"<none>"
    if isinstance(value, np.ndarray):
        arr = np.ascontiguousarray(value)
        if arr.dtype.kind in "fc":
            arr = portable_floats(arr.real if arr.dtype.kind == "f" else np.stack([arr.real, arr.imag]))
        return f"{arr.dtype.str}{arr.shape}".encode() + arr.tobytes()
    if isinstance(value, (bool, int, np.integer)):
        return np.int64(value).tobytes()
    if isinstance(value, (float, np.floating)):
        return _float_bytes(float(value))
    if isinstance(value, str):
        return value.encode()
    return None


_FIELD_NAMES: dict[type, tuple[str, ...]] = {}


def _field_names(cls: type) -> tuple[str, ...]:
    """The fields the digest hashes: all but those marked :data:`~trackreplay.trackers.base.NOT_HASHED`."""
    names = _FIELD_NAMES.get(cls)
    if names is None:
        names = _FIELD_NAMES[cls] = tuple(f.name for f in dataclasses.fields(cls) if f.metadata.get("digest", True))
    return names


def _feed(h: "hashlib._Hash", name: str, value: Any, path: str = "", leaves: list | None = None) -> None:
    """Hash ``value`` under ``name``; with ``leaves``, also append (path, 8-byte hash) per leaf.

    The bytes fed to ``h`` do not depend on ``leaves``: recording per-field hashes leaves the digest as it is.
    """
    leaf = _leaf_bytes(value)
    if leaf is not None:
        h.update(name.encode() + b"\0" + leaf)  # one update: sha256 streams, the digest is the same
        if leaves is not None:
            leaves.append((path, _leaf_hash(leaf), _small(value)))
        return
    h.update(name.encode() + b"\0")
    if dataclasses.is_dataclass(value):
        for f in _field_names(value if isinstance(value, type) else type(value)):
            _feed(h, f, getattr(value, f), _join(path, f), leaves)
    elif isinstance(value, (tuple, list)):
        h.update(np.int64(len(value)).tobytes())
        if leaves is not None:
            leaves.append((_join(path, "len"), np.int64(len(value)).tobytes(), [len(value)]))
        for i, item in enumerate(value):
            _feed(h, str(i), item, _join(path, str(i)), leaves)
    elif isinstance(value, dict):
        for key in sorted(value):
            _feed(h, str(key), value[key], _join(path, str(key)), leaves)
    else:
        raise TypeError(f"cannot digest {type(value).__name__} in field {path or name}")


_NAMES: dict[str, bytes] = {}  # name -> name.encode() + b"\0"
# Field names and list positions repeat every frame; a frame's own name (``frame{index}``) never does,
# so the cache stops growing at this size (it had kept every frame's name: ~115 B a frame of a replay).
_NAMES_KEPT = 4096


def _name(name: str) -> bytes:
    out = _NAMES.get(name)
    if out is None:
        out = name.encode() + b"\0"
        if len(_NAMES) < _NAMES_KEPT and not name.startswith("frame"):
            _NAMES[name] = out
    return out


_DATACLASS_FIELDS: dict[type, tuple[str, ...]] = {}  # dataclass types met by _collect, their field names


def _collect(parts: list, floats: list, name: str, value: Any) -> None:
    """The bytes ``_feed`` would give ``h.update``, appended to ``parts`` (so a frame is one update).

    float64 arrays get a placeholder in ``parts`` and an entry ``(position, array)`` in ``floats``,
    so :func:`_flat_floats` rounds all of a frame's in one numpy pass instead of six calls each.
    The commonest values (floats, strings, dataclasses met before) are handled before the general
    dispatch, and a dataclass's float and string fields without a call each: the same bytes.
    """
    kind = type(value)
    if kind is float:
        parts.append(_name(name) + _float_bytes(value))
    elif kind is np.ndarray and value.dtype.kind == "f" and value.dtype.itemsize == 8 and value.ndim:
        parts.append(_name(name) + f"<f4{value.shape}".encode())  # the header _leaf_bytes gives
        parts.append(None)
        floats.append((len(parts) - 1, value))
    elif kind is str:
        parts.append(_name(name) + value.encode())  # _leaf_bytes of a str
    elif (names := _DATACLASS_FIELDS.get(kind)) is not None:
        parts.append(_name(name))
        for f in names:
            item = getattr(value, f)
            item_kind = type(item)
            if item_kind is float:
                parts.append(_name(f) + _float_bytes(item))
            elif item_kind is str:
                parts.append(_name(f) + item.encode())
            else:
                _collect(parts, floats, f, item)
    elif kind is tuple or kind is list:
        parts.append(_name(name) + _I64.pack(len(value)))
        for i, item in enumerate(value):
            if type(item) is str:
                parts.append(_name(str(i)) + item.encode())
            else:
                _collect(parts, floats, str(i), item)
    else:
        leaf = _leaf_bytes(value)
        if leaf is not None:
            parts.append(_name(name) + leaf)
            return
        parts.append(_name(name))
        if dataclasses.is_dataclass(value):
            names = _field_names(value if isinstance(value, type) else type(value))
            if not isinstance(value, type):  # an instance: its type takes the fast branch from now on
                _DATACLASS_FIELDS[kind] = names
            for f in names:
                _collect(parts, floats, f, getattr(value, f))
        elif isinstance(value, (tuple, list)):
            parts.append(np.int64(len(value)).tobytes())
            for i, item in enumerate(value):
                _collect(parts, floats, str(i), item)
        elif isinstance(value, dict):
            for key in sorted(value):
                _collect(parts, floats, str(key), value[key])
        else:
            raise TypeError(f"cannot digest {type(value).__name__} in field {name}")


def _flat_floats(parts: list, floats: list[tuple[int, np.ndarray]]) -> None:
    """Fill the placeholders of ``floats``: each array's ``portable_floats`` bytes, all rounded at once
    (the rounding is elementwise, so the bytes are those of one call per array)."""
    if len(floats) == 1:
        k, a = floats[0]
        parts[k] = portable_floats(a).tobytes()
        return
    flat = portable_floats(np.concatenate([a.reshape(-1) for _, a in floats])).tobytes()
    at = 0
    for k, a in floats:
        n = 4 * a.size
        parts[k] = flat[at:at + n]
        at += n


SMALL = 32  # numeric fields of at most this many elements keep their values beside their hash


def _leaf_hash(leaf: bytes) -> bytes:
    """8 bytes naming a leaf's hashed bytes: the bytes themselves when they fit (a scalar: most
    leaves, and no hashing), else their 8-byte blake2b."""
    n = len(leaf)
    if n < 8:
        return leaf + bytes(7 - n) + bytes((n,))
    return leaf if n == 8 else hashlib.blake2b(leaf, digest_size=8).digest()


def _small(value: Any) -> list | None:
    """A numeric leaf of ≤ SMALL elements as a flat list (kept so ``diff`` can give max |Δ|), else None."""
    kind = type(value)
    if kind is float or kind is int or kind is bool:
        return [value]
    if kind is str or value is None:
        return None
    if isinstance(value, np.ndarray):
        if value.size > SMALL or value.dtype.kind not in "biuf":
            return None
        return value.ravel().tolist()
    arr = np.asarray(value)
    return arr.ravel().tolist() if arr.dtype.kind in "biuf" and arr.size <= SMALL else None


def _join(path: str, name: str) -> str:
    return f"{path}.{name}" if path else name


def leaf_values(value: Any, path: str = "") -> Iterator[tuple[str, Any]]:
    """(path, value) of every leaf, in the order and with the paths the per-field hashes use."""
    if _leaf_bytes(value) is not None:
        yield path, value
    elif dataclasses.is_dataclass(value):
        for name in _field_names(type(value)):
            yield from leaf_values(getattr(value, name), _join(path, name))
    elif isinstance(value, (tuple, list)):
        yield _join(path, "len"), len(value)
        for i, item in enumerate(value):
            yield from leaf_values(item, _join(path, str(i)))
    elif isinstance(value, dict):
        for key in sorted(value):
            yield from leaf_values(value[key], _join(path, str(key)))
    else:
        raise TypeError(f"cannot digest {type(value).__name__} in field {path}")


# Per-frame digests a replay keeps in memory (~1 KB a frame) before they go to a temporary Parquet file
# (docs/memory.md).
SPILL_FRAMES = 512


FILE_ROWS = 4096  # rows of a sidecar read at a time (FrameDigests.from_file; larger blocks peak higher)


class FrameDigests:
    """Per-frame, per-field hashes of a replay, recorded beside the digest (which they leave unchanged).

    Each frame keeps its field paths (one interned tuple shared by frames with the same layout), the
    concatenated 8-byte blake2b hashes of the fields, and the values of small numeric fields (≤ SMALL
    elements: track states, filter states, velocities) as one float64 blob, so memory stays small.
    Paths are ``intermediates.<field>…`` and ``states.<i>.<field>`` (``states.len`` the track count).

    With ``spill_frames``, every ``spill_frames`` frames go to a temporary Parquet file as one row group
    of :meth:`table`'s rows, so a long replay holds at most that many frames (and 8 bytes per frame for
    ``frames``); :meth:`fields` and :meth:`values` of a spilled frame read its row group back (one kept).
    """

    def __init__(self, spill_frames: int | None = None) -> None:
        self.frames: array[int] = array("q")
        self._paths: list[tuple[str, ...]] = []  # of the frames in memory: frames[self._spilled:]
        self._hashes: list[bytes] = []
        self._sizes: list[tuple[int, ...]] = []  # per field: number of kept values, -1 for none
        self._values: list[bytes] = []
        self._layouts: dict[tuple, tuple] = {}
        self._spill_frames = spill_frames
        self._spilled = 0
        self._writer = None
        self._path: str | None = None
        self._group: tuple[int, FrameDigests] | None = None  # the spilled row group read back last
        self._file: str | None = None  # a sidecar read a block of frames at a time (:meth:`from_file`)
        self._ends: np.ndarray | None = None  # its rows' end of each frame
        self._blocks: Iterator[tuple[int, FrameDigests]] | None = None
        self._rows = FILE_ROWS

    def add(self, index: int, leaves: list[tuple[str, bytes, Any]]) -> None:
        """One frame: (path, 8-byte hash, kept values — a flat list or array of numbers, or None) per field."""
        if self._file is not None:
            raise RuntimeError("per-frame digests read from a file take no frames")
        paths = tuple(p for p, _, _ in leaves)
        sizes = tuple(-1 if v is None else len(v) for _, _, v in leaves)
        flat: list = []
        for _, _, v in leaves:
            if v is not None:
                flat.extend(v)
        self.frames.append(index)
        self._paths.append(self._layouts.setdefault(paths, paths))
        self._sizes.append(self._layouts.setdefault(sizes, sizes))
        self._hashes.append(b"".join(d for _, d, _ in leaves))
        self._values.append(np.array(flat, dtype=np.float64).tobytes())
        if self._spill_frames is not None and len(self._paths) >= self._spill_frames:
            self._spill()

    def _spill(self) -> None:
        import pyarrow.parquet as pq

        if self._writer is not None and not self._writer.is_open:
            raise RuntimeError("per-frame digests added after their spilled table was read")
        table = self._memory_table().to_arrow()
        if self._writer is None:
            fd, self._path = tempfile.mkstemp(prefix="trackreplay-frame-digests-", suffix=".parquet")
            os.close(fd)
            weakref.finalize(self, remove_spill, self._path)
            self._writer = pq.ParquetWriter(self._path, table.schema)
        self._writer.write_table(table, row_group_size=max(table.num_rows, 1))
        # the group just written stays readable without the file (still open for writing): diff's
        # lock step reads the last frame after each one
        group = FrameDigests()
        group.frames = self.frames[self._spilled:]
        group._paths, group._hashes, group._sizes, group._values = self._paths, self._hashes, self._sizes, self._values
        self._group = (self._spilled // self._spill_frames, group)
        self._spilled += len(self._paths)
        self._paths, self._hashes, self._sizes, self._values = [], [], [], []

    def _frame(self, i: int) -> tuple[FrameDigests, int]:
        """Where the i-th recorded frame is: (a FrameDigests holding it, its position there)."""
        i = range(len(self.frames))[i]  # (negative from the end; IndexError past it)
        if self._file is not None:
            return self._file_frame(i)
        if i >= self._spilled:
            return self, i - self._spilled
        import pyarrow.parquet as pq

        group = i // self._spill_frames
        if self._group is None or self._group[0] != group:
            self._finish_spill()  # (no frame is added after an earlier one is read)
            part = pl.from_arrow(pq.ParquetFile(self._path).read_row_group(group))
            self._group = (group, FrameDigests.from_table(part))
        return self._group[1], i - group * self._spill_frames

    def values(self, i: int) -> dict[str, np.ndarray]:
        """Field path -> kept values (flattened float64) of the i-th recorded frame."""
        holder, i = self._frame(i)
        flat = np.frombuffer(holder._values[i], dtype=np.float64)
        out, at = {}, 0
        for path, n in zip(holder._paths[i], holder._sizes[i]):
            if n >= 0:
                out[path] = flat[at:at + n]
                at += n
        return out

    def __len__(self) -> int:
        return len(self.frames)

    def fields(self, i: int) -> dict[str, str]:
        """Field path -> hex hash of the i-th recorded frame."""
        holder, i = self._frame(i)
        blob = holder._hashes[i]
        return {p: blob[8 * k:8 * k + 8].hex() for k, p in enumerate(holder._paths[i])}

    def table(self) -> pl.DataFrame:
        """Long table (the sidecar): frame, field (categorical), hash (the 8 bytes as a big-endian
        UInt64), values (kept values, null for larger fields), one row per field per frame. Built
        from the stored blobs in a few vectorised steps, without a Python object per row. Spilled
        frames are read back: for a long replay, :meth:`write_table` writes it without holding it.
        """
        if self._file is not None:
            return pl.read_parquet(self._file)
        if not self._spilled:
            return self._memory_table()
        self._finish_spill()
        return pl.read_parquet(self._path)

    def write_table(self, out: BinaryIO) -> None:
        """:meth:`table` to an open binary file as Parquet; once spilled, the spill file's bytes (its last
        row group the frames still in memory), copied without decoding."""
        if not self._spilled and self._file is None:
            self._memory_table().write_parquet(out)
            return
        self._finish_spill()
        with open(self._file or self._path, "rb") as spill:
            shutil.copyfileobj(spill, out, 1 << 20)

    def _finish_spill(self) -> None:
        """The frames still in memory go to the spill file as its last row group, and it is closed
        (for reading; the frames stay readable by :meth:`fields` and :meth:`values`)."""
        if self._writer is not None and self._writer.is_open:
            if self._paths:
                self._spill()
            self._writer.close()

    def _memory_table(self) -> pl.DataFrame:
        """:meth:`table` of the frames held in memory."""
        import pyarrow as pa

        names: dict[str, int] = {}
        codes_of: dict[int, np.ndarray] = {}
        for paths in self._layouts.values():
            if paths and isinstance(paths[0], str) and id(paths) not in codes_of:
                codes_of[id(paths)] = np.array([names.setdefault(p, len(names)) for p in paths], dtype=np.int32)
        counts = np.array([len(p) for p in self._paths], dtype=np.int64)
        empty_i32 = np.zeros(0, dtype=np.int32)
        codes = np.concatenate([codes_of.get(id(p), empty_i32) for p in self._paths] or [empty_i32])
        sizes = np.concatenate([np.asarray(z, dtype=np.int64) for z in self._sizes] or [np.zeros(0, np.int64)])
        hashes = np.frombuffer(b"".join(self._hashes), dtype=">u8").astype(np.uint64)
        flat = np.frombuffer(b"".join(self._values), dtype=np.float64)
        offsets = np.zeros(len(sizes) + 1, dtype=np.int64)
        np.cumsum(np.maximum(sizes, 0), out=offsets[1:])
        values = pa.LargeListArray.from_arrays(pa.array(offsets), pa.array(flat), mask=pa.array(sizes < 0))
        fields = pa.DictionaryArray.from_arrays(pa.array(codes), pa.array(list(names), pa.string()))
        return pl.DataFrame({
            "frame": np.repeat(np.asarray(self.frames[self._spilled:], dtype=np.int64), counts),
            "field": pl.from_arrow(fields).cast(pl.String),
            "hash": hashes,
            "values": pl.from_arrow(values).cast(pl.List(pl.Float64)),
        })

    @classmethod
    def from_file(cls, path: str | Path, rows: int = FILE_ROWS) -> FrameDigests | None:
        """A sidecar (:meth:`table` as Parquet) read a block of frames at a time: its frame indices now
        (its ``frame`` column, a batch at a time: 16 bytes a frame), the fields, hashes and values of
        about ``rows`` rows when a frame among them is asked for (one block kept; asked in order, as
        ``diff`` asks, the file is read once; a frame before the block kept reads it again from the start).
        The same frames, fields and values as :meth:`from_table` of the whole file. None when the file
        does not read so, or a frame's rows are not together (then read it whole)."""
        import pyarrow.parquet as pq
        from pyarrow.lib import ArrowException

        try:
            reader = pq.ParquetFile(path, pre_buffer=False, buffer_size=1 << 16)
            if not {"frame", "field", "hash"} <= set(reader.schema_arrow.names):
                return None
            values, lengths = [], []
            for batch in reader.iter_batches(batch_size=rows, columns=["frame"], use_threads=False):
                f = batch.column(0).to_numpy(zero_copy_only=False).astype(np.int64)
                if not len(f):
                    continue
                cut = np.flatnonzero(np.diff(f)) + 1  # runs of one frame
                v, n = f[np.concatenate([[0], cut])], np.diff(np.concatenate([[0], cut, [len(f)]]))
                if values and values[-1][-1] == v[0]:  # a frame across two batches
                    lengths[-1][-1] += n[0]
                    v, n = v[1:], n[1:]
                if len(v):
                    values.append(v)
                    lengths.append(n)
            reader.close()
        except (ArrowException, OSError, ValueError):
            return None
        frames = np.concatenate(values) if values else np.zeros(0, np.int64)
        if np.unique(frames).size != frames.size:  # a frame's rows apart: from_table groups them
            return None
        out = cls()
        out.frames = array("q", frames.tobytes())
        out._file, out._ends = str(path), np.cumsum(np.concatenate(lengths) if lengths else np.zeros(0, np.int64))
        out._rows = rows
        return out

    def _file_frame(self, i: int) -> tuple[FrameDigests, int]:
        """:meth:`_frame` of a sidecar read in blocks (:meth:`from_file`)."""
        if self._group is not None and self._group[0] <= i < self._group[0] + len(self._group[1]):
            return self._group[1], i - self._group[0]
        if self._blocks is None or self._group is None or i < self._group[0]:
            self._blocks = self._read_blocks()
        for start, block in self._blocks:
            if i < start + len(block):
                self._group = (start, block)
                return block, i - start
        raise IndexError(i)

    def _read_blocks(self) -> Iterator[tuple[int, FrameDigests]]:
        """The sidecar's whole frames as they come, ``self._rows`` rows at a time: (first frame's position, its block)."""
        import pyarrow.parquet as pq

        reader = pq.ParquetFile(self._file, pre_buffer=False, buffer_size=1 << 16)
        pending: list[pl.DataFrame] = []
        done = held = 0  # frames given, rows held
        try:
            for batch in reader.iter_batches(batch_size=self._rows, use_threads=False):
                pending.append(pl.from_arrow(batch))
                held += batch.num_rows
                first_row = int(self._ends[done - 1]) if done else 0
                whole = int(np.searchsorted(self._ends, first_row + held, side="right"))  # frames complete
                if whole > done:
                    rows = int(self._ends[whole - 1]) - first_row
                    table = pl.concat(pending, rechunk=False)
                    pending, held = [table.slice(rows)], held - rows
                    yield done, FrameDigests.from_table(table.head(rows))
                    done = whole
        finally:
            reader.close()

    @classmethod
    def from_table(cls, table: pl.DataFrame) -> FrameDigests:
        out = cls()
        if "values" not in table.columns:
            table = table.with_columns(pl.lit(None, dtype=pl.List(pl.Float64)).alias("values"))
        as_bytes = ((lambda h: int(h).to_bytes(8, "big")) if table.schema["hash"].is_integer()
                    else bytes.fromhex)  # UInt64 (now) or hex text (the first sidecars)
        for (index,), part in table.group_by("frame", maintain_order=True):
            out.add(int(index), [(f, as_bytes(h), None if v is None else np.asarray(v, np.float64))
                                 for f, h, v in zip(part["field"], part["hash"], part["values"])])
        return out


_FRAME_ROOTS = {"0": "intermediates", "1": "states"}


_FRAME_PATHS: dict[str, str] = {}


def _frame_path(path: str) -> str:
    """``0.particles.weights`` -> ``intermediates.particles.weights``, ``1.0.x`` -> ``states.0.x``."""
    out = _FRAME_PATHS.get(path)
    if out is None:
        root, _, rest = path.partition(".")
        out = _FRAME_PATHS[path] = _join(_FRAME_ROOTS.get(root, root), rest)
    return out


class ReplayDigest:
    """Accumulates per-frame outputs in replay order; ``finish`` adds the trajectory table."""

    def __init__(self, per_frame: bool = False, spill_frames: int | None = SPILL_FRAMES) -> None:
        self._h = hashlib.sha256(b"trackreplay-digest-v2")
        self.frames: FrameDigests | None = FrameDigests(spill_frames) if per_frame else None

    def add_frame(self, index: int, intermediates: Any) -> None:
        """Hash one frame's outputs; with ``per_frame``, also record its per-field hashes.

        ``intermediates`` is what the engine passes: the tuple ``(intermediates, states)``, whose
        fields are recorded as ``intermediates.…`` and ``states.…``.
        """
        if self.frames is None:  # the bytes of _feed, gathered into one update
            parts: list = []
            floats: list = []
            _collect(parts, floats, f"frame{index}", intermediates)
            if floats:
                _flat_floats(parts, floats)
            self._h.update(b"".join(parts))
            return
        leaves: list[tuple[str, bytes, np.ndarray | None]] = []
        _feed(self._h, f"frame{index}", intermediates, "", leaves)
        self.frames.add(index, [(_frame_path(p), d, v) for p, d, v in leaves if p != "len"])

    def add_lost(self, lost: list[tuple[str, int, int]]) -> None:
        """Frames the replay had to skip ``(topic, index, t_ns)``: a replay of a damaged log never
        shares the digest of the intact one (nothing is fed when none were lost)."""
        if lost:
            _feed(self._h, "lost", [f"{topic}#{index}@{t_ns}" for topic, index, t_ns in lost])

    def finish(self, table: pl.DataFrame | SpilledTrajectory) -> str:
        """The digest, after the trajectory table (in memory, or spilled: hashed a column at a time)."""
        for part in canonical_parts(table, float_bytes=lambda v: portable_floats(v).tobytes()):
            self._h.update(part)
        return self._h.hexdigest()
