"""`trackreplay smooth TRAJ LOG --out SMOOTH.parquet`: RTS smoothing of every track over the whole log."""

from __future__ import annotations

import argparse
from pathlib import Path

from trackreplay.replay.cli.commands.values import non_negative_int

SUFFIXES = (".parquet", ".csv")


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = sub.add_parser("smooth", help="smooth every track over the whole log (offline RTS) and fill its gaps; "
                       "`replay --smooth` also uses the trackers' raw measurements (better for flow and groups)")
    p.add_argument("trajectory", type=Path, help="trajectory from `replay --export` (.parquet or .csv, not gap-filled)")
    p.add_argument("log", type=Path, help="the log it was replayed from (frame times, camera poses)")
    p.add_argument("--out", type=Path, required=True, help="smoothed trajectory: .parquet or .csv")
    p.add_argument("--max-gap", type=non_negative_int, default=15, help="longest gap (frames) the smoother fills; longer stays lost")
    p.set_defaults(func=run)
    return p


def _replayed_from(table, times, log: Path) -> None:
    """Every row's frame is that frame of ``log`` (the same time): a trajectory of another log would
    be smoothed with this one's frame times and camera poses and look right."""
    from trackreplay.replay.analysis.eval import mismatches_in_pieces

    if "t_ns" not in table.columns or table.is_empty():
        return
    _refuse_mismatches(mismatches_in_pieces(table, _log_frames(times), missing=True), log)  # (a whole join: ~30 MB)


def _log_frames(times):
    """The log's ``frame, t_ns`` table."""
    import polars as pl
    from trackreplay.replay.analysis.smooth import FrameTimes

    frames, stamps = (times.frames, times.times) if isinstance(times, FrameTimes) else (list(times), list(times.values()))
    return pl.DataFrame({"frame": frames, "t_ns": stamps}, schema={"frame": pl.Int64, "t_ns": pl.Int64})


def _refuse_mismatches(bad, log: Path) -> None:
    """The frames that disagree with the log (``frame, t_ns, other_t_ns``, by frame), refused in one sentence."""
    from trackreplay.schemas.errors import TrackreplayError

    if bad.height:
        f, t, lt = bad.row(0)
        where = f"at t={lt} ns" if lt is not None else "missing"
        raise TrackreplayError(f"the trajectory's frame {f} (t={t} ns) is {where} in {log} ({bad.height} frame(s) "
                               "disagree): it was not replayed from this log")


def smooth_and_report(table, log: Path, max_gap: int, observations=None, configs=None):
    """Smooth ``table`` with the log's frame times and cameras (and the trackers' raw measurements
    and configs as replayed, which only ``replay --smooth`` has); print one line per track."""
    from trackreplay.replay.analysis.smooth import (
        SmoothConfig,
        log_context,
        smooth_trajectory,
    )

    times, cameras = log_context(log)
    _replayed_from(table, times, log)
    out, fits = smooth_trajectory(table, SmoothConfig(max_gap=max_gap), frame_times=times, cameras=cameras,
                                  observations=observations, configs=configs)
    for f in fits:
        print(_fit_line(f))
    return out


# Rows of short tracks smoothed together when the trajectory is read a few tracks at a time (a longer track
# alone): smaller pieces peak lower, larger ones fill the smoother's lanes better (docs/memory.md)
SMOOTH_ROWS = 8192


def run(args: argparse.Namespace) -> int:
    from trackreplay.replay.core.export import read_trajectory, write_trajectory

    if args.out.suffix.lower() not in SUFFIXES:  # before the smoothing, not after it
        from trackreplay.schemas.errors import TrackreplayError

        raise TrackreplayError(f"{args.out}: a smoothed trajectory is written as {' or '.join(SUFFIXES)} "
                               "(it has std and fill columns, which MOTChallenge .txt cannot hold)")
    if args.trajectory.suffix.lower() == ".parquet" and args.trajectory.is_file():
        # issue 33: a Parquet table in canonical order (as a replay writes it) is read, checked, smoothed and
        # written a few whole tracks at a time (memory bounded by the longest track, not the log); another
        # file, or one a check refuses, is read whole, which names the defect
        rows = smooth_in_pieces(args.trajectory, args.log, args.max_gap, args.out)
        if rows is not None:
            print(f"wrote {args.out}: {rows} rows")
            return 0
    table = read_trajectory(args.trajectory)
    out = smooth_and_report(table, args.log, args.max_gap)
    write_trajectory(out, args.out)
    print(f"wrote {args.out}: {out.height} rows")
    return 0


def piece_mismatches(part, times):
    """:func:`~trackreplay.replay.core.trajectory.frame_time_mismatches` of the rows ``part`` against the log's
    frame times (``missing``: a frame the log lacks is one), by a search in the log's sorted frames instead of
    a join with the whole log's table, once a piece: rows ``frame, t_ns, other_t_ns``,
    a frame's first disagreeing row, by frame."""
    import numpy as np
    import polars as pl

    from trackreplay.replay.analysis.smooth import logged_times
    from trackreplay.replay.core.trajectory import TIMED_STATUSES

    frames = part["frame"].to_numpy().astype(np.int64)
    logged, found = logged_times(times, frames)
    t = part["t_ns"].cast(pl.Int64)
    timed = part["status"].is_in(TIMED_STATUSES).fill_null(False).to_numpy()
    known = t.is_not_null().to_numpy()
    bad = ~found | (timed & known & (t.fill_null(0).to_numpy() != logged))
    rows = pl.DataFrame({"frame": part["frame"].filter(bad), "t_ns": t.filter(bad), "_logged": logged[bad],
                         "_found": found[bad]}).select("frame", "t_ns", pl.when("_found").then("_logged").alias("other_t_ns"))
    return rows.sort("frame", maintain_order=True).unique("frame", keep="first", maintain_order=True)


class _ReadWhole(Exception):
    """The trajectory does not read a piece at a time (out of canonical order, or a check fails)."""


def _pieces(trajectory: Path, rows: int, long_rows: int):
    """:func:`_tracks_and_long_pieces`, a failure to read so as :class:`_ReadWhole`."""
    import polars as pl
    from pyarrow.lib import ArrowException
    from trackreplay.replay.core import export
    from trackreplay.schemas.errors import TrackreplayError

    items = _tracks_and_long_pieces(trajectory, rows, long_rows)
    while True:
        try:
            item = next(items)
        except StopIteration:
            return
        except (export.NotCanonical, TrackreplayError, pl.exceptions.PolarsError, OSError, ArrowException):
            raise _ReadWhole from None
        yield item


def _tracks_and_long_pieces(path: Path, rows: int, long_rows: int, batch: int = 4096):
    """:func:`~trackreplay.replay.core.export.ordered_tracks` (each batch cast and checked, the order checked),
    except that a track of more than ``long_rows`` rows is given a batch at a time:
    ``("tracks", table)`` of whole tracks, ``("long", rows)`` of a long track's next rows, ``("end", None)`` after
    its last (:mod:`~trackreplay.replay.analysis.smooth_long` smooths it in two passes)."""
    import polars as pl
    import pyarrow as pa
    from trackreplay.replay.analysis import segments
    from trackreplay.replay.core import export
    from trackreplay.replay.core.trajectory import COLUMNS

    done: list = []  # whole tracks, not yet given
    size = 0
    current: list = []  # the rows so far of the track being read
    key, current_rows, streaming, last_key = None, 0, False, None
    for df in export.parquet_batches(path, batch):
        df = export.conform(df, str(path)).select(COLUMNS)
        if not df.height:
            continue
        keys = df.select(export.KEYS)
        if not _strictly_ordered(keys if last_key is None else pl.concat([last_key, keys])):
            raise export.NotCanonical(str(path))
        last_key = keys.tail(1)
        runs = segments.offsets(df.select(pl.struct("tracker", "track_id").rle_id()).to_series().to_numpy())
        for a, b in zip(runs[:-1].tolist(), runs[1:].tolist()):
            part = df.slice(a, b - a)
            run = (part["tracker"][0], part["track_id"][0])
            if run != key:
                if streaming:
                    yield "end", None
                else:
                    done += current
                    size += current_rows
                key, current, current_rows, streaming = run, [], 0, False
                if size >= rows:
                    pa.default_memory_pool().release_unused()
                    yield "tracks", pl.concat(done, rechunk=False)
                    done, size = [], 0
            if streaming:
                yield "long", part
                continue
            current.append(part)
            current_rows += part.height
            if current_rows > long_rows:
                if done:
                    yield "tracks", pl.concat(done, rechunk=False)
                    done, size = [], 0
                streaming = True
                for c in current:
                    yield "long", c
                current, current_rows = [], 0
    if streaming:
        yield "end", None
    done += current
    pa.default_memory_pool().release_unused()
    if done:
        yield "tracks", pl.concat(done, rechunk=False)


def _strictly_ordered(keys) -> bool:
    """Whether every row of ``keys`` (tracker, track, frame; no nulls) comes after the one before it."""
    import polars as pl

    later, same = None, None
    for c in ("tracker", "track_id", "frame"):
        gt, eq = pl.col(c) > pl.col(c).shift(1), pl.col(c) == pl.col(c).shift(1)
        later, same = (gt, eq) if later is None else (later | (same & gt), same & eq)
    return bool(keys.select(later.fill_null(True).all()).item())


def _fit_line(f) -> str:
    return (f"smooth {f.tracker}/{f.track_id}: {f.observations} observations ({f.outliers} rejected), "
            f"{f.filled} frames filled; {f.noise}")


def smooth_in_pieces(trajectory: Path, log: Path, max_gap: int, out: Path, rows: int | None = None,
                     long_rows: int | None = None) -> int | None:
    """:func:`smooth_and_report` of a Parquet trajectory in canonical order, read once, a few whole tracks at a
    time (:func:`~trackreplay.replay.core.export.ordered_tracks`), each piece's output written as it is done
    (a Parquet row group, or CSV lines): every track is smoothed alone (its fit, gaps and times are its own),
    so the rows are those of the whole table, in the same order. Each piece's frames are compared with the
    log's before it is smoothed; after a disagreement the rest is only compared, and the whole table's
    sentence (its first frame, how many) is raised. The fits are printed once every piece is done. Returns
    the rows written; None, with nothing printed or written, when the file does not read so (out of order,
    a check fails): the whole read then names any defect. The log is read first (its frame times): a log
    that fails is reported after the trajectory's own defect, as the whole table's path reports them.

    A track longer than ``long_rows`` (:data:`~trackreplay.replay.analysis.smooth_long.LONG_ROWS`)
    is not gathered: its rows go a batch at a time to a :class:`~trackreplay.replay.analysis.smooth_long.LongTrack`,
    which smooths it once they are all read and gives its rows back a piece at a time (the same rows)."""
    import os

    import polars as pl
    from trackreplay.recorder.atomic import claim_partial
    from trackreplay.replay.analysis.eval import mismatches_in_pieces
    from trackreplay.replay.analysis.smooth import (
        EXTRA_SCHEMA,
        SmoothConfig,
        log_context,
        smooth_trajectory,
    )
    from trackreplay.replay.analysis import smooth_long
    from trackreplay.replay.core.export import (
        WRITE_ROWS,
        PieceWriter,
        read_trajectory,
        trajectory_format,
    )
    from trackreplay.replay.core.trajectory import SCHEMA
    from trackreplay.schemas.errors import OutputError

    try:
        times, cameras = log_context(log)
    except Exception:
        read_trajectory(trajectory)  # the trajectory's defect first, as the whole table's path names it
        raise
    config = SmoothConfig(max_gap=max_gap)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = claim_partial(out)  # this process's own; the final name appears only for a complete file
    written, writer, lines, bad = 0, None, [], []

    def failed(err: Exception) -> OutputError:  # as write_trajectory words a failed write
        return OutputError(f"cannot write {out} ({err})")

    long = None

    def write(smoothed) -> None:  # row groups of WRITE_ROWS, converted a row group at a time
        try:
            for at in range(0, smoothed.height, WRITE_ROWS):
                writer.write(smoothed.slice(at, WRITE_ROWS))
        except (OSError, pl.exceptions.PolarsError) as err:
            raise failed(err) from None

    try:
        try:
            writer = PieceWriter(tmp, trajectory_format(out), {**SCHEMA, **EXTRA_SCHEMA}).__enter__()
        except (OSError, pl.exceptions.PolarsError) as err:
            raise failed(err) from None
        for kind, part in _pieces(trajectory, rows or SMOOTH_ROWS, long_rows or smooth_long.LONG_ROWS):
            if kind == "end":  # a long track's rows are all read: smoothed, and written a piece at a time
                if long is not None and not bad:
                    for smoothed in long.pieces(config, times, cameras):
                        write(smoothed)
                        written += smoothed.height
                    lines += [_fit_line(long.fit)] if long.fit is not None else []
                if long is not None:
                    long.close()
                long = None
                continue
            wrong = piece_mismatches(part, times)
            if wrong.height:
                bad.append(wrong)
            if bad:  # (not smoothed: the trajectory is refused)
                continue
            if kind == "long":
                long = long or smooth_long.LongTrack(part["tracker"][0])
                long.add(part)
                continue
            smoothed, fits = smooth_trajectory(part, config, frame_times=times, cameras=cameras)
            del part
            lines += [_fit_line(f) for f in fits]
            write(smoothed)
            written += smoothed.height
        if not written and not bad:
            raise _ReadWhole  # no rows: the whole read names it
        if bad:  # the whole table's comparison: a frame's first disagreeing row, frames in order
            _refuse_mismatches(pl.concat(bad).sort("frame", maintain_order=True).unique("frame", keep="first",
                                                                                    maintain_order=True), log)
        try:
            done, writer = writer, None
            done.__exit__(None, None, None)
            os.replace(tmp, out)
        except (OSError, pl.exceptions.PolarsError) as err:
            raise failed(err) from None
    except BaseException as err:
        if long is not None:
            long.close()
        if writer is not None:
            try:
                writer.__exit__(type(err), err, None)  # closed (not finished) before its file is removed
            except (OSError, pl.exceptions.PolarsError):
                pass
        tmp.unlink(missing_ok=True)
        if isinstance(err, _ReadWhole):
            return None
        raise
    for line in lines:
        print(line)
    return written
