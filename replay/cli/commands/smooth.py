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


def _replayed_from(table, times: dict[int, int], log: Path) -> None:
    """Every row's frame is that frame of ``log`` (the same time): a trajectory of another log would
    be smoothed with this one's frame times and camera poses and look right."""
    import polars as pl

    from trackreplay.replay.core.trajectory import frame_time_mismatches
    from trackreplay.schemas.errors import TrackreplayError

    if "t_ns" not in table.columns or table.is_empty():
        return
    logged = pl.DataFrame({"frame": list(times), "t_ns": list(times.values())}, schema={"frame": pl.Int64, "t_ns": pl.Int64})
    bad = frame_time_mismatches(table, logged, missing=True)
    if bad.height:
        f, t, lt = bad.row(0)
        where = f"at t={lt} ns" if lt is not None else "missing"
        raise TrackreplayError(f"the trajectory's frame {f} (t={t} ns) is {where} in {log} ({bad.height} frame(s) "
                               "disagree): it was not replayed from this log")


def smooth_and_report(table, log: Path, max_gap: int, observations=None, configs=None):
    """Smooth ``table`` with the log's frame times and cameras (and the trackers' raw measurements
    and configs as replayed, which only ``replay --smooth`` has); print one line per track."""
    from trackreplay.replay.analysis.smooth import SmoothConfig, log_context, smooth_trajectory

    times, cameras = log_context(log)
    _replayed_from(table, times, log)
    out, fits = smooth_trajectory(table, SmoothConfig(max_gap=max_gap), frame_times=times, cameras=cameras,
                                  observations=observations, configs=configs)
    for f in fits:
        print(f"smooth {f.tracker}/{f.track_id}: {f.observations} observations ({f.outliers} rejected), "
              f"{f.filled} frames filled; {f.noise}")
    return out


def run(args: argparse.Namespace) -> int:
    from trackreplay.replay.core.export import read_trajectory, write_trajectory

    if args.out.suffix.lower() not in SUFFIXES:  # before the smoothing, not after it
        from trackreplay.schemas.errors import TrackreplayError

        raise TrackreplayError(f"{args.out}: a smoothed trajectory is written as {' or '.join(SUFFIXES)} "
                               "(it has std and fill columns, which MOTChallenge .txt cannot hold)")
    table = read_trajectory(args.trajectory)
    out = smooth_and_report(table, args.log, args.max_gap)
    write_trajectory(out, args.out)
    print(f"wrote {args.out}: {out.height} rows")
    return 0
