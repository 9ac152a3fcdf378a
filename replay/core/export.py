"""Gap filling and writing of the ★ trajectory table (Parquet, CSV, MOTChallenge txt)."""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import polars as pl

from trackreplay.recorder.atomic import claim_partial
from trackreplay.schemas.errors import OutputError, TrackreplayError
from trackreplay.replay.core.trajectory import COLUMNS, FLOAT_COLUMNS, SCHEMA, canonical_order, conform, interpolated_times

METHODS = ("linear", "cubic")
FORMATS = {".parquet": "parquet", ".csv": "csv", ".txt": "mot"}


def _gap_runs(missing: np.ndarray) -> list[tuple[int, int]]:
    """(start, stop) of runs of True that have valid samples on both sides."""
    runs: list[tuple[int, int]] = []
    i, n = 0, missing.size
    while i < n:
        if missing[i]:
            j = i
            while j < n and missing[j]:
                j += 1
            if i > 0 and j < n:
                runs.append((i, j))
            i = j
        else:
            i += 1
    return runs


def _interpolate(known_f: np.ndarray, known_v: np.ndarray, at: np.ndarray, method: str) -> tuple[np.ndarray, np.ndarray]:
    """Values at frames ``at`` from the known samples and their rate (per frame) there: the segment's
    slope for linear, the spline's derivative for cubic (natural, from 4 samples; linear below)."""
    if known_f.size < 2:  # (a piece of a track holding one of its known values: numpy.interp holds it)
        return np.full(at.shape, known_v[0]), np.zeros(at.shape)
    if method == "cubic" and known_f.size >= 4:
        # (imported when a cubic fill asks: scipy costs ~44 MB of RSS)
        from scipy.interpolate import CubicSpline

        spline = CubicSpline(known_f, known_v, bc_type="natural")
        return spline(at), spline(at, 1)
    k = np.clip(np.searchsorted(known_f, at), 1, known_f.size - 1)
    slope = (known_v[k] - known_v[k - 1]) / (known_f[k] - known_f[k - 1])
    return np.interp(at, known_f, known_v), slope


def _fill_track(track: pl.DataFrame, method: str, max_gap: int, known_counts: dict[str, int] | None = None) -> pl.DataFrame:
    """One track's rows on every frame of its span, gaps filled. ``known_counts``: a piece of a longer
    track (:func:`export_trajectory`) interpolates the columns the whole track holds on 2 known rows."""
    first, last = track["frame"].min(), track["frame"].max()
    frames = pl.DataFrame({"frame": np.arange(first, last + 1, dtype=np.int64)})
    full = frames.join(track, on="frame", how="left")
    head = track.row(0, named=True)
    full = full.with_columns(
        pl.lit(head["tracker"]).alias("tracker"),
        pl.lit(head["track_id"], dtype=pl.Int64).alias("track_id"),
        pl.col("status").fill_null("lost"),
    )
    full = full.with_columns(pl.Series("t_ns", interpolated_times(full["frame"].to_numpy(), full["t_ns"].fill_null(0).to_numpy(),
                                                                  full["t_ns"].is_not_null().to_numpy()), dtype=pl.Int64))
    x = full["x"].to_numpy().astype(float)
    missing = np.isnan(x) | (full["status"].to_numpy() == "lost")
    fill = np.zeros(missing.size, bool)
    for a, b in _gap_runs(missing):
        if b - a <= max_gap:
            fill[a:b] = True
    if not fill.any():
        return full.select(COLUMNS)
    f = full["frame"].to_numpy().astype(float)
    known = ~missing
    columns, rates = {}, {}
    for name in FLOAT_COLUMNS:
        values = full[name].to_numpy().astype(float)
        ok = known & ~np.isnan(values)
        if (ok.sum() if known_counts is None else known_counts[name]) < 2 or not ok.any():
            continue
        values[fill], rates[name] = _interpolate(f[ok], values[ok], f[fill], method)
        columns[name] = values
    for v, p in (("vx", "x"), ("vy", "y")):  # a filled row moves as its own positions do, not as the neighbours' velocities
        if v in columns and p in rates:
            columns[v][fill] = rates[p]
    if all(k in columns for k in ("dx", "dy", "dz")):  # lines of sight stay unit vectors
        d = np.stack([columns["dx"], columns["dy"], columns["dz"]])
        d[:, fill] /= np.linalg.norm(d[:, fill], axis=0)
        columns["dx"], columns["dy"], columns["dz"] = d
    status = np.where(fill, "interpolated", full["status"].to_numpy())
    return full.with_columns(
        *(pl.Series(k, v, dtype=pl.Float64, nan_to_null=True) for k, v in columns.items()),
        pl.Series("status", status, dtype=pl.String),
    ).select(COLUMNS)


def fill_gaps(df: pl.DataFrame, method: str = "linear", max_gap: int = 15) -> pl.DataFrame:
    """Interpolate interior gaps of at most ``max_gap`` frames per track; longer gaps stay ``lost``.

    Missing frames between a track's first and last row become rows; filled rows get
    ``status = "interpolated"``. ``cubic`` uses a natural cubic spline through the known samples.
    A filled row's ``vx, vy`` are its positions' rate (the segment's slope, or the spline's
    derivative), in px/frame; its ``t_ns`` is interpolated between the neighbours' (exact only
    without jitter: eval and smooth do not compare it with the log's).
    """
    if method not in METHODS:
        raise TrackreplayError(f"interpolation method must be one of {', '.join(METHODS)}, not {method!r}")
    if df.is_empty():
        return df
    parts = [
        _fill_track(track, method, max_gap)
        for _, track in df.sort(["tracker", "track_id", "frame"]).group_by(["tracker", "track_id"], maintain_order=True)
    ]
    return canonical_order(pl.concat(parts))


def write_mot(df: pl.DataFrame, path: Path) -> None:
    """MOTChallenge: ``frame,id,bb_left,bb_top,bb_width,bb_height,conf,x,y,z``, 1-based frames **and
    pixels** (the top-left pixel is (1, 1) there, (0, 0) here): ``bb_left = x - w/2 + 1``.
    ``recorder.sources.groundtruth.read_mot`` undoes it, so MOT ground truth imported, tracked
    and exported compares in ``motmetrics`` without a 1 px offset."""
    _mot_lines(df).write_csv(path, include_header=False, float_precision=3)


def _mot_lines(df: pl.DataFrame) -> pl.DataFrame:
    """:func:`write_mot`'s rows of ``df``, by frame and id (rows of one frame and id in ``df``'s order)."""
    rows = df.filter(pl.col("x").is_not_null() & (pl.col("status") != "lost")).with_columns(
        w=pl.col("w").fill_null(1.0), h=pl.col("h").fill_null(1.0)
    )
    return rows.select(
        (pl.col("frame") + 1).alias("frame"),
        pl.col("track_id").alias("id"),
        (pl.col("x") - pl.col("w") / 2 + 1).alias("bb_left"),
        (pl.col("y") - pl.col("h") / 2 + 1).alias("bb_top"),
        pl.col("w").alias("bb_width"),
        pl.col("h").alias("bb_height"),
        pl.when(pl.col("status") == "measured").then(1.0).otherwise(0.5).alias("conf"),
        pl.col("X").fill_null(-1.0).alias("x"),
        pl.col("Y").fill_null(-1.0).alias("y"),
        pl.col("Z").fill_null(-1.0).alias("z"),
    ).sort(["frame", "id"], maintain_order=True)


def trajectory_format(path: str | Path) -> str:
    """The format a trajectory path's suffix asks for (checked before a replay, so a wrong name
    does not cost the whole replay first)."""
    kind = FORMATS.get(Path(path).suffix.lower())
    if kind is None:
        raise TrackreplayError(f"{path}: unknown trajectory format; use .parquet, .csv or .txt (MOTChallenge)")
    return kind


def write_trajectory(df: pl.DataFrame, path: str | Path) -> Path:
    """Write by suffix: ``.parquet`` (default format), ``.csv`` or ``.txt`` (MOTChallenge)."""
    path = Path(path)
    kind = trajectory_format(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = claim_partial(path)  # this process's own; the final name appears only for a complete file
    try:
        if kind == "parquet":
            df.write_parquet(tmp)
        elif kind == "csv":
            df.write_csv(tmp)
        else:
            write_mot(df, tmp)
        os.replace(tmp, path)
    except (OSError, pl.exceptions.PolarsError) as err:  # polars reports a full disk as ComputeError
        tmp.unlink(missing_ok=True)
        raise OutputError(f"cannot write {path} ({err})") from None
    return path


def read_trajectory(path: str | Path, keep_fill: bool = False) -> pl.DataFrame:
    """Read a trajectory written by :func:`write_trajectory` (Parquet or CSV), checked as the ★ table
    (:func:`~trackreplay.replay.core.trajectory.conform`); an empty one is refused (nothing to work on).
    ``keep_fill``: also the ``fill`` column ``smooth`` and ``flight --rescan`` write, where the table has one
    (how a row was obtained: a frame ``rescan`` found is no measurement of the tracker's)."""
    path = Path(path)
    if not path.is_file():
        raise TrackreplayError(f"{path} does not exist")
    suffix = path.suffix.lower()
    if suffix not in (".parquet", ".csv"):
        raise TrackreplayError(f"{path}: trajectories are read from .parquet or .csv")
    if suffix == ".csv" and (pieces := _csv_in_pieces(path, keep_fill)) is not None:
        return pieces
    try:
        # CSV cells are read as text and cast by conform, which names the line of a bad one
        df = pl.read_parquet(path) if suffix == ".parquet" else pl.read_csv(path, infer_schema=False)
    except (pl.exceptions.PolarsError, OSError) as err:
        raise TrackreplayError(f"{path} is not a readable trajectory table ({_first_line(err)})") from None
    if "confidence" not in df.columns:  # tables written before the column existed
        df = df.with_columns(pl.lit(None, dtype=pl.Float64).alias("confidence"))
    where = (lambda i: f"row {i + 1}") if suffix == ".parquet" else (lambda i: f"line {i + 2}")  # CSV line 1: header
    fill = df.get_column("fill").cast(pl.String, strict=False) if keep_fill and "fill" in df.columns else None
    df = conform(df, str(path), where)  # (the rows in the same order: the fill column goes back beside them)
    if df.is_empty():
        raise TrackreplayError(f"{path} holds no rows: an empty trajectory")
    if fill is not None:
        return canonical_order(df.with_columns(fill), extra=("fill",))
    return canonical_order(df)


CSV_BYTES = 1 << 18  # bytes of a CSV trajectory read as text, cast and checked at a time


def _csv_in_pieces(path: Path, keep_fill: bool) -> pl.DataFrame | None:
    """:func:`read_trajectory` of a CSV file read ``CSV_BYTES`` at a time (whole lines, the header put
    before each piece), each piece cast and checked (``conform``) as the whole table is: only the typed
    rows are kept, not the whole file as text (~50 bytes a cell at the peak, ``benchmarks/bench_long_log.py
    --csv-only``). None when any check fails, the file does not read, it holds no rows, or it has a quoted
    cell (a quoted line break would not split at a line): the whole read then names the defect in its own
    sentence."""
    parts, fills = [], []
    try:
        for part, fill in _csv_parts(path, keep_fill):
            parts.append(part)
            if fill is not None:
                fills.append(fill)
    except _ReadWhole:
        return None
    if not parts:
        return None
    df = pl.concat(parts, rechunk=False)
    del parts
    if not df.select(pl.struct("tracker", "track_id", "frame").is_first_distinct().all()).item():
        return None  # a track's frame twice, in two pieces
    if fills:
        df = df.with_columns(pl.concat(fills))
    extra = ("fill",) if fills else ()
    return df.select(*COLUMNS, *extra) if _in_canonical_order(df) else canonical_order(df, extra=extra)


class _ReadWhole(Exception):
    """A CSV file :func:`_csv_parts` cannot read in pieces: read it whole (which names its defect)."""


def _csv_parts(path: Path, keep_fill: bool = False) -> Iterator[tuple[pl.DataFrame, pl.Series | None]]:
    """A CSV trajectory ``CSV_BYTES`` at a time, each piece cast and checked (``conform``), with its ``fill``
    column (``keep_fill``, where it has one), in the file's order; :class:`_ReadWhole` when a check fails, the
    file does not read or it has a quoted cell. A track's frame in two pieces is not checked here."""
    import io

    try:
        with open(path, "rb") as fh:
            header = fh.readline()
            if not header.endswith(b"\n") or b'"' in header:
                raise _ReadWhole
            rest = b""
            while True:
                block = fh.read(CSV_BYTES)
                text = rest + block
                cut = len(text) if not block else text.rfind(b"\n") + 1
                piece, rest = text[:cut], text[cut:]
                if b'"' in piece:
                    raise _ReadWhole
                if piece.strip():
                    part = pl.read_csv(io.BytesIO(header + piece), infer_schema=False)
                    if "confidence" not in part.columns:  # tables written before the column existed
                        part = part.with_columns(pl.lit(None, dtype=pl.Float64).alias("confidence"))
                    fill = part.get_column("fill").cast(pl.String, strict=False) if keep_fill and "fill" in part.columns else None
                    yield conform(part, str(path)), fill
                if not block:
                    break
    except (TrackreplayError, pl.exceptions.PolarsError, OSError):
        raise _ReadWhole from None


def csv_as_parquet(path: str | Path, target: str | Path) -> bool:
    """A CSV trajectory written to ``target`` as Parquet a piece at a time (:func:`_csv_parts`: each piece
    cast and checked as :func:`read_trajectory` checks the whole table; a row group a piece), for the
    tools that read a checked Parquet file in pieces (``export``). False when the file cannot be read so
    (nothing usable is left in ``target``): then read it whole, which names the defect."""
    written = False
    try:
        with PieceWriter(Path(target), "parquet") as out:
            for part, _ in _csv_parts(Path(path)):
                out.write(part)
                written = written or part.height > 0
    except (_ReadWhole, OSError, pl.exceptions.PolarsError):
        return False
    return written


def _in_canonical_order(df: pl.DataFrame) -> bool:
    """Whether ``df``'s rows are already in canonical order (then not sorted: a copy of a long table)."""
    later, same = None, None
    for c in ("tracker", "track_id", "frame"):
        gt, eq = pl.col(c) > pl.col(c).shift(1), pl.col(c) == pl.col(c).shift(1)
        later, same = (gt, eq) if later is None else (later | (same & gt), same & eq)
    return bool(df.select((later | same).fill_null(True).all()).item())


def _first_line(err: Exception) -> str:
    """The gist of a library's message (polars explains at length, over several paragraphs)."""
    lines = [line.strip() for line in str(err).splitlines() if line.strip()]
    return lines[0].rstrip(".:") if lines else type(err).__name__


# A spilled trajectory is exported this many frames of a track (or whole short tracks) at a time, so
# the export's memory does not grow with the log (docs/memory.md).
EXPORT_ROWS = 4096


def _known(column: str) -> pl.Expr:
    """A known row (positioned, not lost) that holds ``column`` (gap filling's ``ok``)."""
    return (pl.col("x").fill_nan(None).is_not_null() & (pl.col("status").fill_null("lost") != "lost")
            & pl.col(column).fill_nan(None).is_not_null())


def _tracks_of(path: Path, cast: bool = False) -> pl.DataFrame:
    """Per track (canonical order): its first and last frame, its rows, and how many known rows hold
    each float column (gap filling interpolates a column from 2 of them: a piece must do the same)."""
    return (_scan(path, cast).group_by("tracker", "track_id")
            .agg(pl.col("frame").min().alias("_lo"), pl.col("frame").max().alias("_hi"),
                 *(_known(c).sum().alias(c) for c in FLOAT_COLUMNS))
            .collect(engine="streaming").sort("tracker", "track_id"))


def _anchor(counts: dict) -> pl.Expr:
    """A row a long track may be cut at, both pieces holding it: known, with its time and every column
    the track interpolates, so each side fills as the whole track would."""
    ok = _known("x") & pl.col("t_ns").is_not_null()
    for c in FLOAT_COLUMNS:
        if counts[c] >= 2:
            ok = ok & pl.col(c).fill_nan(None).is_not_null()
    return ok


class CheckedParquet:
    """A trajectory file (``trackreplay export TRAJ``) already checked a piece at a time as
    :func:`read_trajectory` checks it whole (:func:`~trackreplay.replay.analysis.eval.checked_scan`):
    exported a piece at a time like a replay's spill file, each piece cast to the ★ table as
    :func:`read_trajectory` casts the whole (``conform``; the ``fill`` column and others left out)."""

    def __init__(self, path: Path) -> None:
        self.path = Path(path)

    def frame(self) -> pl.DataFrame:
        return read_trajectory(self.path)


def _pieces(path: Path, rows: int, split: bool, cast: bool = False) -> Iterator[tuple[pl.DataFrame, bool, dict | None]]:
    """A spilled trajectory in pieces, canonical order: (rows, drop its first row (the previous piece's
    last), a piece of one track: the track's known rows per column). Whole short tracks together up to
    ``rows`` frames; a longer track (``split``) about ``rows`` frames at a time, cut at anchors.
    ``cast``: each piece as :func:`read_trajectory` gives its rows (a user's file, not a spill file)."""
    tracks = _tracks_of(path, cast)
    batch: list[tuple[str, int]] = []
    size = 0
    for track in tracks.iter_rows(named=True):
        key, span = (track["tracker"], track["track_id"]), track["_hi"] - track["_lo"] + 1
        if split and span > rows:
            if batch:  # the tracks before it first: canonical order
                yield _read(path, _tracks(batch), cast), False, None
                batch, size = [], 0
            yield from _track_pieces(path, key, track, rows, cast)
            continue
        batch.append(key)
        size += span
        if size >= rows:
            yield _read(path, _tracks(batch), cast), False, None
            batch, size = [], 0
    if batch:
        yield _read(path, _tracks(batch), cast), False, None


def _track_pieces(path: Path, key: tuple[str, int], track: dict, rows: int,
                  cast: bool = False) -> Iterator[tuple[pl.DataFrame, bool, dict]]:
    """One long track about ``rows`` frames at a time: each piece ends at the first anchor ``rows`` or
    more frames after its start (the next begins there); the last one at the track's end."""
    counts = {c: track[c] for c in FLOAT_COLUMNS}
    same = (pl.col("tracker") == key[0]) & (pl.col("track_id") == key[1])
    start, hi, first = track["_lo"], track["_hi"], True
    while True:
        reach = rows
        while True:  # read on until a cut is found or the track ends
            part = _read(path, same & pl.col("frame").is_between(start, start + 2 * reach), cast)
            cuts = part.filter(pl.col("frame").is_between(start + rows, hi, closed="left") & _anchor(counts))
            if cuts.height or start + 2 * reach >= hi:
                break
            reach *= 2
        if not cuts.height:  # the rest of the track is the last piece
            yield part, not first, counts
            return
        end = int(cuts["frame"][0])
        yield part.filter(pl.col("frame") <= end), not first, counts
        start, first = end, False


def checked_tracks(path: str | Path, rows: int = EXPORT_ROWS) -> Iterator[pl.DataFrame]:
    """A trajectory file :func:`~trackreplay.replay.analysis.eval.checked_scan` accepted, whole tracks at a
    time (canonical order; short tracks together up to ``rows`` frames, a longer one alone), each as
    :func:`read_trajectory` gives those rows: the tracks of the whole table, a few at a time."""
    for part, _, _ in _pieces(Path(path), rows, split=False, cast=True):
        yield part


def parquet_batches(path: str | Path, rows: int) -> Iterator[pl.DataFrame]:
    """A Parquet file's rows ``rows`` at a time, as read (``confidence`` added where the file predates it),
    not cast: pyarrow decodes a batch of each column at a time, where a polars scan decodes a whole row
    group (a file written at once is one row group of up to 2¹⁸ rows: ~35 MB of trajectory at 200k rows)."""
    import pyarrow.parquet as pq

    reader = pq.ParquetFile(path, pre_buffer=False, buffer_size=1 << 16)  # (a column chunk read in 64 KB pieces)
    try:
        for batch in reader.iter_batches(batch_size=rows, use_threads=False):
            df = pl.from_arrow(batch)
            if "confidence" not in df.columns:  # tables written before the column existed
                df = df.with_columns(pl.lit(None, dtype=pl.Float64).alias("confidence"))
            yield df
    finally:
        reader.close()


class NotCanonical(Exception):
    """A trajectory file whose rows are not in canonical order, or that repeats a track's frame."""


def ordered_tracks(path: str | Path, rows: int = EXPORT_ROWS, batch: int = 4096) -> Iterator[pl.DataFrame]:
    """The tracks of a Parquet trajectory file in canonical order, read once from the start ``batch`` rows
    at a time (:func:`parquet_batches`), each batch cast and checked as :func:`read_trajectory` checks the
    whole (``conform``; its :class:`TrackreplayError` raised as the batch's): whole tracks at a time, short ones
    together up to ``rows`` rows (and the rest of the batch that reached them), a longer one alone (its
    batches as the table's chunks, not copied together). :class:`NotCanonical` as soon as a row is not
    after the one before it (tracker, track, frame): then read the file whole."""
    done: list[pl.DataFrame] = []
    size = 0
    current: list[pl.DataFrame] = []  # the rows so far of the track the last batch ended in
    last_key: pl.DataFrame | None = None
    for df in parquet_batches(path, batch):
        df = conform(df, str(path)).select(COLUMNS)
        if not df.height:
            continue
        keys = df.select(KEYS)
        if not _strictly_ordered(keys if last_key is None else pl.concat([last_key, keys])):
            raise NotCanonical(str(path))
        last_key = keys.tail(1)
        tracker, track_id = df["tracker"][-1], df["track_id"][-1]
        last = df.select(((pl.col("tracker") == tracker) & (pl.col("track_id") == track_id)).sum()).item()
        cut = df.height - last  # (sorted: the last track's rows end the batch)
        if cut or (current and (current[0]["tracker"][0], current[0]["track_id"][0]) != (tracker, track_id)):
            done += [*current, df.head(cut)]
            size += sum(c.height for c in current) + cut
            current = []
        current.append(df.slice(cut))
        if size >= rows:
            _release_arrow()
            yield pl.concat(done, rechunk=False)
            done, size = [], 0
    done += current
    _release_arrow()
    if done:
        yield pl.concat(done, rechunk=False)


def _release_arrow() -> None:
    """Pyarrow's pool gives back the pages its decoding left free (before the piece is smoothed)."""
    import pyarrow as pa

    pa.default_memory_pool().release_unused()


KEYS = ("tracker", "track_id", "frame")


def _strictly_ordered(keys: pl.DataFrame) -> bool:
    """Whether every row of ``keys`` (:data:`KEYS`, no nulls) comes after the one before it."""
    later, same = None, None
    for c in KEYS:
        gt, eq = pl.col(c) > pl.col(c).shift(1), pl.col(c) == pl.col(c).shift(1)
        later, same = (gt, eq) if later is None else (later | (same & gt), same & eq)
    return bool(keys.select(later.fill_null(True).all()).item())


def _tracks(keys: list[tuple[str, int]]) -> pl.Expr:
    return pl.struct("tracker", "track_id").is_in(pl.Series([{"tracker": t, "track_id": i} for t, i in keys]).implode())


def _scan(path: Path, cast: bool = False) -> pl.LazyFrame:
    """The file's rows lazily; with ``cast``, its ★ columns as :data:`SCHEMA` types (a file whose
    every piece ``conform`` accepted: the same values as the strict cast)."""
    scan = pl.scan_parquet(path)
    if not cast:
        return scan
    names = scan.collect_schema().names()
    return scan.select(pl.col(c).cast(t, strict=False) if c in names else pl.lit(None, dtype=t).alias(c)
                       for c, t in SCHEMA.items())


def _read(path: Path, where: pl.Expr, cast: bool = False) -> pl.DataFrame:
    df = _scan(path, cast).filter(where).collect()
    return canonical_order(conform(df, str(path)) if cast else df)


def export_trajectory(table, path: str | Path, method: str = "linear", max_gap: int = 15,
                      rows: int = EXPORT_ROWS) -> tuple[int, int]:
    """Gap-fill ``table`` (``method`` ``none``: as it is) and write it (:func:`write_trajectory`'s
    formats); ``(rows, interpolated rows)`` written. A :class:`SpilledTrajectory` (or a checked
    trajectory file, :class:`CheckedParquet`) is read, filled and
    written a piece at a time (whole short tracks, a long track ``rows`` frames at a time, cut at a known
    row both pieces hold) in Parquet or CSV: the same rows as filling the whole table, in memory
    bounded by ``rows`` instead of the log. Cubic splines span their whole track: a track is not cut
    then. MOTChallenge (sorted by frame) is written from the filled pieces, written first to a temporary
    Parquet file, then read back ``MOT_FRAMES`` frames at a time (a filter pushed down to the scan)."""
    from trackreplay.replay.core.trajectory import SpilledTrajectory

    if method not in (*METHODS, "none"):
        raise TrackreplayError(f"interpolation method must be one of {', '.join(METHODS)}, not {method!r}")
    kind = trajectory_format(path)
    streamed = isinstance(table, (SpilledTrajectory, CheckedParquet))
    if not streamed:
        df = table if method == "none" else fill_gaps(table, method, max_gap)
        write_trajectory(df, path)
        return df.height, df.filter(pl.col("status") == "interpolated").height
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = claim_partial(path)
    filled_file = None
    try:
        if kind == "mot":
            fd, name = tempfile.mkstemp(prefix="trackreplay-export-", suffix=".parquet")
            os.close(fd)
            filled_file = Path(name)
            counts = _write_filled(table, filled_file, "parquet", method, max_gap, rows)
            _write_mot_in_frames(filled_file, tmp)
        else:
            counts = _write_filled(table, tmp, kind, method, max_gap, rows)
        os.replace(tmp, path)
    except (OSError, pl.exceptions.PolarsError) as err:
        tmp.unlink(missing_ok=True)
        raise OutputError(f"cannot write {path} ({err})") from None
    finally:
        if filled_file is not None:
            filled_file.unlink(missing_ok=True)
    return counts


def _write_filled(table, target: Path, kind: str, method: str, max_gap: int, rows: int) -> tuple[int, int]:
    """:func:`export_trajectory`'s pieces, filled, written to ``target`` (Parquet or CSV) one after the other."""
    written = filled = 0
    with PieceWriter(target, kind) as out:
        cast = isinstance(table, CheckedParquet)
        for part, drop_first, counts in _pieces(table.path, rows, split=method != "cubic", cast=cast):
            if method != "none" and counts is not None:  # a piece of one track
                part = canonical_order(_fill_track(part, method, max_gap, counts))
            elif method != "none":
                part = fill_gaps(part, method, max_gap)
            part = part.slice(1) if drop_first else part
            out.write(part)
            written, filled = written + part.height, filled + part.filter(pl.col("status") == "interpolated").height
    return written, filled


MOT_FRAMES = 4096  # frames of MOTChallenge lines written at a time


def _write_mot_in_frames(filled: Path, target: Path, frames: int | None = None) -> None:
    """:func:`write_mot` of the table in ``filled`` (canonical order), ``frames`` frames at a time: the lines of
    the whole table, in its order (each window's rows in the file's order, then sorted by frame and id)."""
    frames = frames or MOT_FRAMES
    scan = pl.scan_parquet(filled)
    lo, hi = scan.select(pl.col("frame").min().alias("lo"), pl.col("frame").max().alias("hi")).collect().row(0)
    with open(target, "wb") as fh:
        if lo is None:
            _mot_lines(scan.collect()).write_csv(fh, include_header=False, float_precision=3)
            return
        for start in range(lo, hi + 1, frames):
            part = scan.filter(pl.col("frame").is_between(start, start + frames - 1)).collect()
            _mot_lines(part).write_csv(fh, include_header=False, float_precision=3)


WRITE_ROWS = 1 << 15  # rows of a Parquet row group PieceWriter writes (at most)


class PieceWriter:
    """Parquet (a row group per piece) or CSV (one header) written a piece at a time; with no piece at
    all, the header of ``schema`` alone."""

    def __init__(self, path: Path, kind: str, schema: dict | None = None) -> None:
        self.path, self.kind, self._writer, self._fh = path, kind, None, None
        self.schema = SCHEMA if schema is None else schema

    def __enter__(self) -> PieceWriter:
        if self.kind == "csv":
            self._fh = open(self.path, "wb")
        return self

    def write(self, part: pl.DataFrame) -> None:
        if self.kind == "csv":
            part.write_csv(self._fh, include_header=self._writer is None)
            self._writer = True
            return
        import pyarrow.parquet as pq

        table = part.to_arrow()
        if self._writer is None:
            self._writer = pq.ParquetWriter(self.path, table.schema, compression="zstd")
        self._writer.write_table(table, row_group_size=WRITE_ROWS)  # (a row group is encoded whole in memory)

    def __exit__(self, *exc) -> None:
        if self._fh is not None:
            if self._writer is None:  # no rows at all: the header alone
                pl.DataFrame(schema=self.schema).write_csv(self._fh)
            self._fh.close()
        elif self._writer is not None:
            self._writer.close()
        elif exc[0] is None:
            pl.DataFrame(schema=self.schema).write_parquet(self.path)
