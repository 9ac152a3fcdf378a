"""``trackreplay diff A.rrd B.rrd``: the first frame where two Rerun recordings differ, and where.

An .rrd holds what a replay's views logged, so this compares what a person would see: every
entity's components, frame by frame on the ``frame`` timeline (static data first), whatever the
chunking (two writers may cut the same rows into different chunks). Cells are compared as Arrow
values; numeric ones that differ report max |Δ|. "Tracks" are the entities under ``/tracks``,
which is where every view draws the trajectory.
"""

from __future__ import annotations

import hashlib
from collections import defaultdict
from pathlib import Path

import numpy as np
import pyarrow as pa

from trackreplay.replay.analysis.diff import Divergence, FieldDiff
from trackreplay.schemas.errors import TrackreplayError

INDEX_COLUMNS = {"rerun.controls.RowId", "frame", "log_time", "log_tick"}
STATIC = -(2**63)  # sorts before every frame


def _numbers(cell: pa.Array) -> np.ndarray | None:
    """A cell's values as one flat float64 array (lists flattened, struct fields side by side), or None."""
    arr = cell
    while pa.types.is_list(arr.type) or pa.types.is_large_list(arr.type) or pa.types.is_fixed_size_list(arr.type):
        arr = arr.flatten()
    if pa.types.is_struct(arr.type):
        fields = [_numbers(arr.field(i)) for i in range(arr.type.num_fields)]
        if any(f is None for f in fields) or len({f.size for f in fields}) > 1:
            return None
        return np.stack(fields, axis=-1).reshape(-1) if fields else np.zeros(0)
    if pa.types.is_integer(arr.type) or pa.types.is_floating(arr.type) or pa.types.is_boolean(arr.type):
        return np.asarray(arr.to_numpy(zero_copy_only=False), dtype=np.float64)
    return None


def _fingerprint(cell: pa.Array) -> bytes:
    compact = pa.concat_arrays([cell])  # a slice shares its parent's buffers: copy it out first
    h = hashlib.sha1(str(compact.type).encode())
    sink = pa.BufferOutputStream()
    with pa.ipc.new_stream(sink, pa.schema([("v", compact.type)])) as writer:
        writer.write_batch(pa.record_batch([compact], names=["v"]))
    h.update(sink.getvalue().to_pybytes())
    return h.digest()


def rrd_cells(path: Path) -> dict[tuple[str, str], dict[int, list[pa.Array]]]:
    """(entity path, component) -> frame (``STATIC`` for static data) -> the cells logged there."""
    import rerun.chunk as rc

    if not Path(path).exists():
        raise TrackreplayError(f"{path} does not exist")
    cells: dict[tuple[str, str], dict[int, list[pa.Array]]] = defaultdict(lambda: defaultdict(list))
    try:
        chunks = list(rc.RrdReader(str(path)).stream())
    except Exception as err:  # the reader raises its own error types for a file that is not an .rrd
        raise TrackreplayError(f"{path} is not a readable .rrd file ({type(err).__name__}: {err})") from None
    for chunk in chunks:
        batch = chunk.to_record_batch()
        names = batch.schema.names
        if chunk.is_static:
            frames = [STATIC] * batch.num_rows
        elif "frame" in names:
            frames = batch.column(names.index("frame")).to_pylist()
        else:
            continue  # on other timelines only: not comparable frame by frame
        entity = str(chunk.entity_path)
        for k, name in enumerate(names):
            if name in INDEX_COLUMNS:
                continue
            column = batch.column(k)
            for i, frame in enumerate(frames):
                if column[i].is_valid:
                    cells[(entity, name)][frame].append(column.slice(i, 1))
    for per_frame in cells.values():  # static data: the last write is what a viewer shows
        if STATIC in per_frame:
            per_frame[STATIC] = per_frame[STATIC][-1:]
    return cells


def _compare(a: list[pa.Array], b: list[pa.Array]) -> FieldDiff | None:
    if len(a) == len(b) and all(x.equals(y) for x, y in zip(a, b)):
        return None
    if sorted(map(_fingerprint, a)) == sorted(map(_fingerprint, b)):
        return None  # the same rows in another order (another chunking)
    if len(a) != len(b):
        return FieldDiff("", None, f"{len(a)} vs {len(b)} rows")
    deltas = []
    for x, y in zip(a, b):
        nx, ny = _numbers(x), _numbers(y)
        if nx is None or ny is None:
            return FieldDiff("", None, "")
        if nx.shape != ny.shape:
            return FieldDiff("", None, f"{nx.size} vs {ny.size} values")
        both = np.isfinite(nx) & np.isfinite(ny)
        deltas.append(float(np.max(np.abs(nx[both] - ny[both]))) if both.any() else 0.0)
    return FieldDiff("", max(deltas) if deltas else None)


def diff_rrd(a: Path, b: Path) -> Divergence:
    """First frame (static data first) where A and B hold different cells, and which entities/components."""
    ca, cb = rrd_cells(Path(a)), rrd_cells(Path(b))
    keys = sorted(set(ca) | set(cb))
    frames_a = {f for k in ca for f in ca[k] if f != STATIC}
    frames_b = {f for k in cb for f in cb[k] if f != STATIC}
    frames = sorted({f for k in keys for f in (set(ca.get(k, {})) | set(cb.get(k, {})))})
    first, fields, tracks_diverge_at = None, [], None
    for frame in frames:
        found = []
        for key in keys:
            da = ca.get(key, {}).get(frame, [])
            db = cb.get(key, {}).get(frame, [])
            if not da and not db:
                continue
            diff = _compare(da, db)
            if diff is not None:
                found.append(FieldDiff(f"{key[0]} {key[1]}", diff.max_abs_delta,
                                       diff.note or ("only in A" if not db else "only in B" if not da else "")))
        if found and first is None:
            first, fields = frame, found
        if any(f.field.startswith("/tracks") for f in found):
            tracks_diverge_at = frame
            break
    shown = None if first is None else ("static" if first == STATIC else first)
    until = None
    if tracks_diverge_at is not None:
        earlier = [f for f in frames if f < tracks_diverge_at and f != STATIC]
        until = earlier[-1] if earlier else -1
    return Divergence(len(frames_a), len(frames_b), shown, tuple(fields), until, tracks_diverge_at is not None,
                      trajectory_name="tracks as drawn (/tracks: boxes and points, not every trajectory column)")
