"""`trackreplay export TRAJ OUT`: gap-fill a trajectory and write Parquet, CSV or MOTChallenge."""

from __future__ import annotations

import argparse
from pathlib import Path

from trackreplay.replay.cli.commands.values import non_negative_int
from trackreplay.replay.core.export import (FORMATS, METHODS, CheckedParquet, export_trajectory, fill_gaps,
                                            read_trajectory, write_trajectory)


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = sub.add_parser("export", help="interpolate gaps and convert a trajectory table")
    p.add_argument("trajectory", type=Path, help="input .parquet or .csv")
    p.add_argument("out", type=Path, help="output .parquet, .csv or .txt (MOTChallenge)")
    p.add_argument("--interpolate", choices=("none", *METHODS), default="linear")
    p.add_argument("--max-gap", type=non_negative_int, default=15, help="longest gap (frames) filled; longer stays lost")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    suffix = args.trajectory.suffix.lower()
    if suffix in (".parquet", ".csv") and args.trajectory.is_file() and FORMATS.get(args.out.suffix.lower()) in ("parquet", "csv"):
        # a Parquet table is checked and exported a piece at a time (issue 33: memory flat in its length), a CSV
        # one first cast and checked a piece at a time into a temporary Parquet file; a file a check refuses is
        # read whole, which names the defect
        if suffix == ".parquet":
            if _exported_in_pieces(args, args.trajectory):
                return 0
        else:
            import tempfile

            from trackreplay.replay.core.export import csv_as_parquet

            with tempfile.TemporaryDirectory(prefix="trackreplay-export-") as tmp:
                typed = Path(tmp) / "trajectory.parquet"
                if csv_as_parquet(args.trajectory, typed) and _exported_in_pieces(args, typed):
                    return 0
    table = read_trajectory(args.trajectory)
    if args.interpolate != "none":
        table = fill_gaps(table, args.interpolate, args.max_gap)
    write_trajectory(table, args.out)
    filled = table.filter(table["status"] == "interpolated").height
    print(f"wrote {args.out}: {table.height} rows, {filled} interpolated")
    return 0


def _exported_in_pieces(args: argparse.Namespace, parquet: Path) -> bool:
    """Export ``parquet`` a piece at a time when every piece passes read_trajectory's checks."""
    from trackreplay.replay.analysis.eval import checked_scan

    if checked_scan(parquet) is None:
        return False
    rows, filled = export_trajectory(CheckedParquet(parquet), args.out, args.interpolate, args.max_gap)
    print(f"wrote {args.out}: {rows} rows, {filled} interpolated")
    return True
