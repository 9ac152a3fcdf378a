"""A long replay's memory stays flat: the trajectory and per-frame digests go to Parquet row groups
past a bound, the digest and the tables come out the same, and spilled memory per frame is constant."""

from __future__ import annotations

import gc
import io
import tracemalloc
from pathlib import Path

import numpy as np
import polars as pl
import pyarrow.parquet as pq
import pytest

from trackreplay.replay.core.digest import FrameDigests, ReplayDigest
from trackreplay.replay.core.engine import ReplayRequest, replay
from trackreplay.replay.core.trajectory import (COLUMNS, SpilledTrajectory, TrajectoryRows, canonical_bytes,
                                                canonical_parts, trajectory_table)
from trackreplay.schemas.errors import TrackreplayError


def _rows(n: int, seed: int = 0) -> list[tuple]:
    """Rows in replay order (frame by frame), several trackers and tracks, nulls, non-ASCII status text."""
    rng = np.random.default_rng(seed)
    rows = []
    for i in range(n):
        frame, track = i // 3, int(rng.integers(1, 6))
        lost = rng.random() < 0.2
        xy = [None if lost else float(v) for v in rng.normal(0, 100, 12)]
        rows.append((("golf", "flow", "grüppchen")[i % 3], track, frame, 1_700_000_000_000_000_000 + frame,
                     *xy, "lost" if lost else "measured", None if lost else float(rng.random())))
    return rows


def _spilled(rows: list[tuple], every: int) -> SpilledTrajectory:
    acc = TrajectoryRows(every)
    for k in range(0, len(rows), 7):  # as a replay adds them: a few at a time
        acc.extend(rows[k:k + 7])
    out = acc.finish()
    assert isinstance(out, SpilledTrajectory)
    return out


def test_spilled_table_hashes_and_reads_back_as_the_table_in_memory() -> None:
    rows = _rows(1000)
    table = trajectory_table(rows)
    spilled = _spilled(rows, 128)
    assert spilled.height == 1000 and spilled.row_groups == 8  # 7 full groups of 128 and the rest
    assert b"".join(spilled.canonical_parts(lambda v: v.tobytes())) == canonical_bytes(table)
    rounded = lambda v: v.astype("<f4").tobytes()  # noqa: E731 (the digest's float bytes differ from raw)
    assert b"".join(canonical_parts(spilled, rounded)) == canonical_bytes(table, rounded)
    assert spilled.frame().equals(table) and spilled.scan().collect().equals(table)
    few = TrajectoryRows(4096)
    few.extend(rows)
    assert few.finish().equals(table)  # under the bound: in memory, no file


def test_spill_file_goes_with_its_table() -> None:
    spilled = _spilled(_rows(300), 100)
    path = spilled.path
    assert path.is_file()
    del spilled
    gc.collect()
    assert not path.exists()


def test_replay_spilling_gives_the_same_digest_table_and_frame_digests(short_sim: Path) -> None:
    whole = replay(ReplayRequest(log=short_sim, tracker="flow", frame_digests=True))
    spilled = replay(ReplayRequest(log=short_sim, tracker="flow", frame_digests=True, spill_rows=8, spill_frames=5))
    assert isinstance(whole.table, pl.DataFrame) and isinstance(spilled.table, SpilledTrajectory)
    assert spilled.digest == whole.digest
    assert spilled.rows == whole.rows == whole.trajectory.height
    assert pq.ParquetFile(spilled.table.path).metadata.row_group(0).num_rows == 8  # rows went out in row groups
    assert spilled.trajectory.equals(whole.trajectory)
    assert spilled.scan_trajectory().collect().equals(whole.trajectory)
    assert spilled.summary(short_sim)["rows"] == whole.summary(short_sim)["rows"]
    a, b = whole.frame_digests, spilled.frame_digests
    assert b._spilled == 5 * (len(b) // 5) > 0 and len(b._paths) < 5  # at most spill_frames frames held
    assert list(a.frames) == list(b.frames)
    for i in (0, 4, 5, 11, len(a) - 1, -1):
        assert a.fields(i) == b.fields(i)
        va, vb = a.values(i), b.values(i)
        assert va.keys() == vb.keys() and all(np.array_equal(va[k], vb[k], equal_nan=True) for k in va)
    assert b.table().equals(a.table())
    out = io.BytesIO()
    b.write_table(out)
    out.seek(0)
    assert pl.read_parquet(out).equals(a.table())


def test_the_last_frame_stays_readable_while_frames_spill() -> None:
    """``diff_runs`` reads each side's last frame after adding it, in lock step, while the replay goes on."""
    spilling, whole = FrameDigests(spill_frames=4), FrameDigests()
    for i in range(11):
        leaves = [("states.len", bytes(8), [1.0]), ("intermediates.x", i.to_bytes(8, "big"), [float(i)])]
        spilling.add(i, leaves)
        whole.add(i, leaves)
        assert spilling.fields(-1) == whole.fields(-1)
    assert spilling._spilled == 8 and spilling.fields(2) == whole.fields(2)
    assert spilling.table().equals(whole.table())


@pytest.mark.parametrize("field", ["spill_rows", "spill_frames"])
def test_spill_bounds_must_be_positive(short_sim: Path, field: str) -> None:
    with pytest.raises(TrackreplayError, match=field):
        ReplayRequest(log=short_sim, tracker="flow", **{field: 0})


def _peak_traced(frames: int) -> tuple[int, int]:
    """Peak traced bytes of a replay's bookkeeping (rows, digest, per-frame digests) over ``frames``
    synthetic frames of one track, spilling every 500 rows / 200 frames: (during the frames, at the
    digest's final pass over the spilled table)."""
    rows = TrajectoryRows(500)
    digest = ReplayDigest(per_frame=True, spill_frames=200)
    tracemalloc.start()
    for i in range(frames):
        state = {"x": float(i % 97), "y": 0.5 * i, "weights": np.full(40, i % 7, np.float64), "status": "measured"}
        digest.add_frame(i, (state, ()))
        rows.extend([("flow", 1, i, i * 33_333_333, *([float(i)] * 12), "measured", 1.0)])
    during = tracemalloc.get_traced_memory()[1]
    tracemalloc.reset_peak()
    digest.finish(rows.finish())
    final = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return during, final


@pytest.mark.slow  # 6 s: the default suite took 4 min 13 s on a fresh clone (budget 4 min); CI runs -m slow
def test_bookkeeping_memory_does_not_grow_with_the_log() -> None:
    _peak_traced(200)  # (caches filled once per process)
    small, large = _peak_traced(1_000), _peak_traced(10_000)
    # 10x the frames: the same row groups held (kept in lists as before the spill, 10k frames held ~12 MB);
    # the frame numbers of the per-frame digests, 8 bytes a frame, are all that grows
    assert large[0] < small[0] + 8 * 9_000 + 50_000, (small, large)
    # the digest's final pass holds the canonical order and one column: under 100 bytes a row
    assert large[1] < small[1] + 100 * 9_000, (small, large)


def _digests(frames: int = 40) -> FrameDigests:
    """Frames of different layouts (a track appearing, a large field without values, a frame index skipped)."""
    rng = np.random.default_rng(2)
    out = FrameDigests()
    for i in range(frames):
        leaves = [("states.len", bytes(8), [float(i % 3)]),
                  ("intermediates.image", rng.bytes(8), None)]
        leaves += [(f"states.{k}.x", rng.bytes(8), list(rng.normal(size=2))) for k in range(i % 3)]
        out.add(2 * i + (i > 20), leaves)
    return out


@pytest.mark.parametrize("rows", [1, 3, 8, 1000])
def test_a_sidecar_read_a_block_at_a_time_gives_the_whole_reads_frames(tmp_path: Path, rows: int) -> None:
    """Issue 33 (`diff`): a sidecar read ``rows`` rows at a time (row groups cutting frames, a frame across
    reads) gives every frame's fields and values as the whole table does, asked in order or not."""
    import pyarrow.parquet as pq
    from trackreplay.replay.analysis.diff import read_sidecar

    table = _digests().table()
    path = tmp_path / "s.frames.parquet"
    pq.write_table(table.to_arrow(), path, row_group_size=7)
    whole = FrameDigests.from_table(table)
    part = FrameDigests.from_file(path, rows=rows)
    assert part is not None and part.frames == whole.frames and len(part) == len(whole)
    for i in [*range(len(whole)), 5, -1, 0, 30, 2]:
        assert part.fields(i) == whole.fields(i)
        assert part.values(i).keys() == whole.values(i).keys()
        assert all(np.array_equal(v, whole.values(i)[k]) for k, v in part.values(i).items())
    assert part.table().equals(table)
    assert read_sidecar(path)._file is not None
    apart = tmp_path / "apart.frames.parquet"  # a frame's rows not together: read whole, as from_table groups them
    pl.concat([table, table.head(2)]).write_parquet(apart)
    assert FrameDigests.from_file(apart) is None
    assert read_sidecar(apart).frames == FrameDigests.from_table(pl.read_parquet(apart)).frames
    with pytest.raises(IndexError):
        part.fields(len(whole))
