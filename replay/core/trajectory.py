"""The ★ trajectory table: one row per track per frame, and its canonical bytes for digests."""

from __future__ import annotations

import hashlib
import os
import tempfile
import weakref
from collections.abc import Callable, Iterable, Iterator, Sequence
from pathlib import Path

import numpy as np
import polars as pl

from trackreplay.schemas.errors import TrackreplayError
from trackreplay.trackers.base import POSITION_FIELDS, STATUSES, TrackState

FLOAT_COLUMNS = ("x", "y", "w", "h", "X", "Y", "Z", "dx", "dy", "dz", "vx", "vy")
SCHEMA: dict[str, pl.DataType] = {
    "tracker": pl.String,
    "track_id": pl.Int64,
    "frame": pl.Int64,
    "t_ns": pl.Int64,
    **{c: pl.Float64 for c in FLOAT_COLUMNS},
    "status": pl.String,
    "confidence": pl.Float64,
}
COLUMNS = tuple(SCHEMA)
KEY = ("tracker", "track_id", "frame")
# Rows whose t_ns is their frame's own time. Gap filling adds rows (interpolated, or lost beyond
# --max-gap) with times interpolated between their neighbours: exact only without jitter.
TIMED_STATUSES = ("measured", "predicted")


def frame_time_mismatches(a: pl.DataFrame, b: pl.DataFrame, *, missing: bool = False) -> pl.DataFrame:
    """Rows ``frame, t_ns, other_t_ns`` (one per frame, sorted) where table ``a``'s frame is at another
    time in ``b`` (both with ``frame`` and ``t_ns`` columns); with ``missing``, also frames of ``a`` that
    ``b`` lacks (``other_t_ns`` null). Only rows of ``a`` in :data:`TIMED_STATUSES` (every row when it
    has no ``status``) are compared by time. A trajectory, a ground truth and a log number frames alike
    only when every shared frame is the same moment in each."""
    other = b.select(pl.col("frame").cast(a.schema["frame"]), pl.col("t_ns").cast(pl.Int64).alias("other_t_ns"),
                     pl.lit(True).alias("_in_b")).unique("frame", keep="first", maintain_order=True)
    timed = pl.col("status").is_in(TIMED_STATUSES) if "status" in a.columns else pl.lit(True)
    rows = a.select("frame", pl.col("t_ns").cast(pl.Int64), timed.alias("_timed"))
    joined = rows.join(other, on="frame", how="left" if missing else "inner")
    bad = joined.filter(pl.col("_in_b").is_null() | (pl.col("_timed") & (pl.col("t_ns") != pl.col("other_t_ns"))))
    return bad.sort("frame", maintain_order=True).unique("frame", keep="first", maintain_order=True).select(
        "frame", "t_ns", "other_t_ns")


def interpolated_times(frames: np.ndarray, times: np.ndarray, known: np.ndarray) -> np.ndarray:
    """Log times (int64 ns) of ``frames`` where only ``known`` ones are given: those exactly, the others
    linear in the frame number between their known neighbours, rounded to the ns, the ends held.
    Integer arithmetic throughout: float64 has 53 bits, so epoch times (~1.7e18 ns) would lose their
    last bits and no longer name their frames."""
    t = np.where(known, np.asarray(times), 0).astype(np.int64)
    f = np.asarray(frames, dtype=np.int64)
    n = len(t)
    if not known.any() or known.all():
        return t
    idx = np.arange(n)
    prev = np.maximum.accumulate(np.where(known, idx, -1))
    nxt = np.minimum.accumulate(np.where(known, idx, n)[::-1])[::-1]
    inner = ~known & (prev >= 0) & (nxt < n)
    a, b = prev[inner], nxt[inner]
    num, den = (t[b] - t[a]) * (f[inner] - f[a]), f[b] - f[a]
    t[inner] = t[a] + (2 * num + den) // (2 * den)  # rounded half up
    head, tail = ~known & (prev < 0), ~known & (nxt >= n)
    t[head] = t[nxt[head]]
    t[tail] = t[prev[tail]]
    return t


def state_row(tracker: str, frame: int, t_ns: int, state: TrackState) -> tuple:
    return (tracker, state.track_id, frame, t_ns, *(getattr(state, c) for c in FLOAT_COLUMNS), state.status, state.confidence)


def trajectory_table(rows: Iterable[Sequence]) -> pl.DataFrame:
    """Build the table from row tuples in ``COLUMNS`` order, sorted canonically."""
    df = pl.DataFrame(list(rows), schema=SCHEMA, orient="row")
    return canonical_order(df)


def canonical_order(df: pl.DataFrame, extra: tuple[str, ...] = ()) -> pl.DataFrame:
    """The ★ columns (then ``extra`` ones, e.g. ``fill``) in order, rows by tracker, track and frame."""
    return df.select(*COLUMNS, *extra).sort(["tracker", "track_id", "frame"], maintain_order=True)


def canonical_bytes(df: pl.DataFrame, float_bytes: Callable[[np.ndarray], bytes] = lambda v: v.tobytes()) -> bytes:
    """A byte string that depends only on the table's values (column order fixed, nulls marked).

    ``float_bytes`` turns a float64 column into bytes (the replay digest rounds first).
    """
    df = canonical_order(df)
    parts: list[bytes] = [",".join(COLUMNS).encode(), np.int64(df.height).tobytes()]
    for name in COLUMNS:
        col = df.get_column(name)
        nulls = col.is_null().to_numpy()
        parts.append(np.packbits(nulls).tobytes())
        if SCHEMA[name] == pl.String:
            parts.append("\0".join(col.fill_null("").to_list()).encode())
        elif SCHEMA[name] == pl.Int64:
            parts.append(col.fill_null(0).to_numpy().astype("<i8").tobytes())
        else:
            values = col.fill_null(0.0).to_numpy().astype("<f8")
            parts.append(float_bytes(values))
    return b"".join(len(p).to_bytes(8, "little") + p for p in parts)


def table_digest(df: pl.DataFrame) -> str:
    return hashlib.sha256(canonical_bytes(df)).hexdigest()


def conform(df: pl.DataFrame, source: str, where: Callable[[int], str] = lambda i: f"row {i + 1}") -> pl.DataFrame:
    """``df`` as read from ``source``, cast to :data:`SCHEMA` and checked (types, key columns present,
    known statuses, lost rows without a position, one row per track and frame), else a
    :class:`TrackreplayError` naming ``source`` and ``where(i)`` of the first offending row ``i``."""
    absent = [c for c in COLUMNS if c not in df.columns]
    if absent:
        raise TrackreplayError(f"{source} lacks trajectory columns: {', '.join(absent)}")
    df = df.select(_cast(df, name, dtype, source, where) for name, dtype in SCHEMA.items())
    _refuse(df, pl.any_horizontal(pl.col(c).is_null() for c in ("tracker", "track_id", "frame", "status")), source, where,
            lambda r: f"no {next(c for c in ('tracker', 'track_id', 'frame', 'status') if r[c] is None)} "
                      "(every row needs tracker, track_id, frame and status)")
    _refuse(df, pl.col("frame") < 0, source, where, lambda r: f"frame {r['frame']} is negative (frames count from 0)")
    _refuse(df, ~pl.col("status").is_in(STATUSES), source, where,
            lambda r: f"status {r['status']!r} is not one of {', '.join(STATUSES)}")
    placed = [c for c in POSITION_FIELDS if c in SCHEMA]
    _refuse(df, (pl.col("status") == "lost") & pl.any_horizontal(pl.col(c).is_not_null() for c in placed), source, where,
            lambda r: f"a lost row of track {r['track_id']} on frame {r['frame']} carries a position "
                      f"({next(c for c in placed if r[c] is not None)}); lost rows have none")
    first = pl.struct(KEY).is_first_distinct()
    _refuse(df, ~first, source, where, lambda r: f"a second row for track {r['track_id']} ({r['tracker']}) on frame "
                                                 f"{r['frame']}: one row per track and frame")
    return df


def _cast(df: pl.DataFrame, name: str, dtype: pl.DataType, source: str, where: Callable[[int], str]) -> pl.Series:
    """Column ``name`` as ``dtype``; a value that is not one (text in a number column, a fraction in an
    integer column) is refused."""
    col = df.get_column(name)
    if col.dtype == dtype:
        return col
    out = col.cast(dtype, strict=False)
    bad = col.is_not_null() & out.is_null()
    if dtype == pl.Int64 and col.dtype.is_float():
        bad = bad | (col.is_not_null() & (col != col.floor()).fill_null(True))
    if bad.any():
        i = int(bad.arg_max())
        kind = "an integer" if dtype == pl.Int64 else "a number"
        raise TrackreplayError(f"{source} {where(i)}: {name} is {col[i]!r}, not {kind}")
    return out


def _refuse(df: pl.DataFrame, bad: pl.Expr, source: str, where: Callable[[int], str], says: Callable[[dict], str]) -> None:
    """Raise for the first row where ``bad`` holds: ``source where(i): says(row)``."""
    hits = df.with_row_index("_i").filter(bad.fill_null(False))
    if hits.height:
        row = hits.row(0, named=True)
        raise TrackreplayError(f"{source} {where(row['_i'])}: {says(row)}")


# A replay keeps this many trajectory rows in memory; beyond it they go to a temporary Parquet file, one
# row group per this many rows, so the replay's memory does not grow with the log (docs/memory.md).
SPILL_ROWS = 2048


class TrajectoryRows:
    """A replay's rows as they come: in memory up to ``spill_rows``, then appended to a temporary
    Parquet file in row groups of ``spill_rows`` rows. :meth:`finish` gives the table (in memory) or a
    :class:`SpilledTrajectory` (on disk): the same rows either way."""

    def __init__(self, spill_rows: int = SPILL_ROWS) -> None:
        if spill_rows < 1:
            raise ValueError(f"spill_rows must be at least 1, not {spill_rows}")
        self._rows: list[tuple] = []
        self._spill_rows = spill_rows
        self._writer = None
        self._path: Path | None = None

    def extend(self, rows: Iterable[Sequence]) -> None:
        self._rows.extend(rows)
        if len(self._rows) >= self._spill_rows:
            self._spill()

    def _spill(self) -> None:
        import pyarrow.parquet as pq

        table = pl.DataFrame(self._rows, schema=SCHEMA, orient="row").to_arrow()
        if self._writer is None:
            fd, name = tempfile.mkstemp(prefix="trackreplay-trajectory-", suffix=".parquet")
            os.close(fd)
            self._path = Path(name)
            self._writer = pq.ParquetWriter(name, table.schema)
        self._writer.write_table(table, row_group_size=max(len(self._rows), 1))
        self._rows = []

    def finish(self) -> pl.DataFrame | SpilledTrajectory:
        if self._writer is None:
            return trajectory_table(self._rows)
        if self._rows:
            self._spill()
        self._writer.close()
        return SpilledTrajectory(self._path, owned=True)


class SpilledTrajectory:
    """A trajectory table in a Parquet file (rows in replay order), read back a column or a row group at
    a time: :meth:`canonical_parts` (the digest) holds 3 integers per row and one column, never the table.
    ``owned``: the file is a temporary one, removed when this object goes."""

    def __init__(self, path: Path, owned: bool = False) -> None:
        import pyarrow.parquet as pq

        self.path = Path(path)
        meta = pq.ParquetFile(self.path).metadata
        self.height = meta.num_rows
        self.row_groups = meta.num_row_groups
        if owned:
            weakref.finalize(self, remove_spill, str(self.path))

    def scan(self) -> pl.LazyFrame:
        """The rows in canonical order, lazily (polars reads the file when collected)."""
        return pl.scan_parquet(self.path).select(*COLUMNS).sort(["tracker", "track_id", "frame"], maintain_order=True)

    def frame(self) -> pl.DataFrame:
        """The whole table in memory, in canonical order (as an unspilled replay returns it)."""
        return canonical_order(pl.read_parquet(self.path))

    def _column(self, name: str) -> pl.Series:
        return pl.read_parquet(self.path, columns=[name]).get_column(name)

    def _canonical_order(self) -> np.ndarray:
        """Row positions in canonical order (a stable sort by tracker, track and frame, as
        :func:`canonical_order`), from integer keys: ~28 bytes a row while it runs."""
        keys = pl.read_parquet(self.path, columns=list(KEY))
        if keys.null_count().sum_horizontal().item():  # (never in a replay's rows) polars orders nulls
            return keys.with_row_index("_i").sort(list(KEY), maintain_order=True).get_column("_i").to_numpy()
        names = sorted(keys.get_column("tracker").unique().to_list())  # code point order: UTF-8 byte order
        rank = keys.get_column("tracker").replace_strict(names, range(len(names)), return_dtype=pl.UInt32).to_numpy()
        frame, track = keys.get_column("frame").to_numpy(), keys.get_column("track_id").to_numpy()
        del keys
        return np.lexsort((frame, track, rank))  # stable, last key first

    def canonical_parts(self, float_bytes: Callable[[np.ndarray], bytes]) -> Iterator[bytes]:
        """The bytes of :func:`canonical_bytes` of this table, in pieces, reading one column at a time."""
        order = self._canonical_order()
        yield from _framed([",".join(COLUMNS).encode(), np.int64(self.height).tobytes()])
        for name in COLUMNS:
            col = self._column(name).gather(order)
            yield from _framed([np.packbits(col.is_null().to_numpy()).tobytes()])
            if SCHEMA[name] == pl.String:
                yield from _joined_strings(col.fill_null(""))
            elif SCHEMA[name] == pl.Int64:
                yield from _framed([col.fill_null(0).to_numpy().astype("<i8").tobytes()])
            else:
                yield from _framed([float_bytes(col.fill_null(0.0).to_numpy().astype("<f8"))])


def remove_spill(path: str) -> None:
    """Remove a temporary spill file (at most once; gone already is fine)."""
    try:
        os.unlink(path)
    except FileNotFoundError:
        pass


def _framed(parts: list[bytes]) -> Iterator[bytes]:
    for p in parts:
        yield len(p).to_bytes(8, "little")
        yield p


def _joined_strings(col: pl.Series, block: int = 65_536) -> Iterator[bytes]:
    """``"\\0".join(col).encode()`` framed as :func:`canonical_bytes` frames it, ``block`` strings at a time."""
    n = col.len()
    yield (int(col.str.len_bytes().sum() or 0) + max(n - 1, 0)).to_bytes(8, "little")
    for start in range(0, n, block):
        text = "\0".join(col.slice(start, block).to_list())
        yield (text if start == 0 else "\0" + text).encode()


def canonical_parts(table: pl.DataFrame | SpilledTrajectory,
                    float_bytes: Callable[[np.ndarray], bytes] = lambda v: v.tobytes()) -> Iterator[bytes]:
    """:func:`canonical_bytes` of a table in memory or spilled, as pieces whose concatenation it is."""
    if isinstance(table, SpilledTrajectory):
        yield from table.canonical_parts(float_bytes)
    else:
        yield canonical_bytes(table, float_bytes)
