"""`trackreplay batch LOG… --tracker NAME`: logs × seeds × --set values, one replay per Ray task."""

from __future__ import annotations

import argparse
import shutil
import sys
from pathlib import Path

from trackreplay.recorder.interrupts import deferred_interrupts
from trackreplay.replay.core import registry
from trackreplay.replay.runs.batch import (BatchInterrupted, BatchOptions, BatchTask, format_table, not_run_row, plan, run_ray,
                                      run_serial, summary_table)
from trackreplay.replay.runs.batch_config import grid, parse_seeds
from trackreplay.replay.cli.commands.values import non_negative_int, positive_int
from trackreplay.replay.core.export import METHODS
from trackreplay.replay.core.outputs import remove_empty, write_parquet
from trackreplay.schemas.errors import TrackreplayError

FAILED = 1  # some task failed (its row says why); the others' outputs are written


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = sub.add_parser(
        "batch", help="replay many logs × seeds × parameter values on Ray (local cores or a cluster)",
        description="Runs the cross product of LOGs, --seeds and every --set value, one replay per Ray task. "
                    "Writes OUT/tasks/<task>/{trajectory.parquet,summary.json,summary.frames.parquet[,replay.rrd]} "
                    "and OUT/summary.parquet (one row per task: log, tracker, seed, parameters, digest, frames, "
                    "seconds, eval metrics where the log has ground truth, status, error), and prints the table. "
                    "Exit 0 when every task succeeded, 1 when some failed or lost frames to damage, 130 on Ctrl-C (the finished "
                    "tasks and a summary marking the rest not_run are kept). See docs/batch.md for clusters.")
    p.add_argument("logs", nargs="+", type=Path, metavar="LOG")
    p.add_argument("--tracker", default="flow", type=registry.canonical, choices=registry.NAMES, help="tracker to run (default flow)")
    p.add_argument("--seeds", default="0", help="seeds: N, N-M or a comma list (default 0)")
    p.add_argument("--set", dest="sets", action="append", default=[], metavar="KEY=V1[,V2…]",
                   help="config values to sweep, e.g. golf.particles.n=500,1000 (repeat for a cross product)")
    p.add_argument("--config", type=Path, help="base tracker config TOML that --set values override")
    p.add_argument("--out", type=Path, default=Path("batch-out"), help="output folder (default batch-out)")
    p.add_argument("--rrd", action="store_true", help="also write each replay's .rrd")
    p.add_argument("--interpolate", choices=("none", *METHODS), default="linear", help="gap filling of the trajectories")
    p.add_argument("--max-gap", type=non_negative_int, default=15,
                   help="longest gap (frames) that is interpolated; longer stays lost (default 15)")
    p.add_argument("--address", help="join this Ray cluster (auto, ray://head:10001, …); default: a local Ray on this machine")
    p.add_argument("--workers", type=positive_int, help="CPUs of the local Ray, 1 or more (default: all cores)")
    p.add_argument("--ship-logs", action="store_true",
                   help="send logs to the tasks through Ray's object store and outputs back to this machine "
                        "(nodes without shared storage); default: by path")
    p.add_argument("--serial", action="store_true", help="no Ray: run the replays one by one in this process")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    tasks = plan(args.logs, args.tracker, parse_seeds(args.seeds), grid(args.sets, args.tracker), args.config)
    out = args.out.resolve()
    if out.exists() and not out.is_dir():
        raise TrackreplayError(f"--out {args.out} is a file, not a folder")
    previous = [p for p in (out / "summary.parquet", out / "tasks") if p.exists()]
    if previous:  # a review: old task folders beside the new ones contradicted the new summary
        raise TrackreplayError(f"--out {args.out} holds an earlier batch's results ({previous[0].name}); "
                               "give an empty or new folder")
    created = [p for p in (out, *out.parents) if not p.exists()]  # removed again if the batch leaves them empty
    out.mkdir(parents=True, exist_ok=True)
    opts = BatchOptions(out=out, rrd=args.rrd, interpolate=args.interpolate, max_gap=args.max_gap)
    progress = not args.quiet and sys.stderr.isatty()
    try:
        if args.serial:
            rows = run_serial(tasks, opts, progress)
        else:
            rows = run_ray(tasks, opts, address=args.address, workers=args.workers, ship_logs=args.ship_logs,
                           progress=progress)
    except BatchInterrupted as err:
        raise keep_finished(err, tasks, out, created) from None
    except BaseException:  # e.g. a Ray that cannot start or join: no empty --out left behind
        remove_empty(created)
        raise
    table = summary_table(rows, tasks)
    with deferred_interrupts():  # a Ctrl-C now waits for the summary of the finished batch
        write_parquet(table, out / "summary.parquet")
    print(format_table(table))
    failed = table.filter(table["status"] != "ok").height  # an error, or frames lost to damage (replay's exit 7)
    print(f"{table.height - failed} of {table.height} replays done; summary {out / 'summary.parquet'}")
    return FAILED if failed else 0


def keep_finished(err: BatchInterrupted, tasks: list[BatchTask], out: Path, created: list[Path]) -> KeyboardInterrupt:
    """After an interrupt: the finished tasks' outputs and a summary of every task (the rest ``not_run``),
    the unfinished tasks' folders removed; returns the interrupt to raise, saying what was kept."""
    for task in tasks:
        if task.index not in err.rows:
            shutil.rmtree(out / "tasks" / task.name, ignore_errors=True)
    if not err.rows:
        remove_empty([out / "tasks", *created])
        return type(err.cause)("no replay had finished; nothing was kept")
    table = summary_table([err.rows.get(t.index) or not_run_row(t) for t in tasks], tasks)
    with deferred_interrupts():
        write_parquet(table, out / "summary.parquet")
    print(format_table(table))
    return type(err.cause)(f"kept the outputs of the {len(err.rows)} of {len(tasks)} replays that had finished and "
                           f"a summary of all {len(tasks)} in {out / 'summary.parquet'} (the others' status is not_run)")

