"""`trackreplay evaluate SUITE.toml --out DIR`: every tracker on a labelled corpus, started from the truth, scored."""

from __future__ import annotations

import argparse
import dataclasses
import math
import shlex
import sys
from pathlib import Path

import polars as pl

from trackreplay.replay.cli.commands.values import non_negative_float, positive_int
from trackreplay.replay.core import registry
from trackreplay.replay.core.outputs import write_bytes, write_parquet
from trackreplay.replay.runs.batch_config import parse_seeds
from trackreplay.schemas.errors import TrackreplayError

FAILED = 1  # some replay failed (its row says why); every other row is written


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = sub.add_parser(
        "evaluate", help="score trackers on a labelled corpus (a TOML manifest): one table, summary and plots",
        description="Reads the corpus manifest (docs/evaluate.md), records each case once into OUT/logs (cached by "
                    "content hash), marks the start from the truth, replays every tracker the case's target suits × "
                    "--seeds (and OpenCV CSRT on box cases), scores them, and writes OUT/cases.parquet (one row per "
                    "case × tracker × seed; the same bytes for the same manifest, seeds and code), OUT/timings.parquet "
                    "(ms per frame), OUT/summary.md and OUT/plots/*.png. Runs on Ray when it is installed (or --address "
                    "is given), else one replay after another. A case whose files are absent is skipped (one line); a "
                    "replay that fails is a row with its error. Exit 0 when every replay was scored, 1 when some failed.")
    p.add_argument("manifest", type=Path, metavar="SUITE.toml", help="the corpus manifest")
    p.add_argument("--out", type=Path, required=True, help="output folder (its logs/ are reused by the next run)")
    p.add_argument("--seeds", default="0", help="seeds: N, N-M or a comma list (default 0)")
    p.add_argument("--trackers", help=f"only these trackers, comma-separated ({', '.join(registry.NAMES)}); "
                                      "default: every tracker each case names or its target suits")
    p.add_argument("--jitter", type=non_negative_float, default=0.0, metavar="PX",
                   help="move each start mark by up to PX pixels, differently per seed (robustness to the marking)")
    p.add_argument("--jitter-scale", type=scale_range, metavar="LO:HI",
                   help="also scale each start mark's sides round its centre by a factor drawn in [LO, HI] per seed "
                        "(e.g. 0.7:1.5: robustness to how large a box the user draws)")
    p.add_argument("--no-baseline", action="store_true", help="no OpenCV CSRT rows on box cases")
    p.add_argument("--address", help="join this Ray cluster (auto, ray://head:10001, …); its nodes must see --out")
    p.add_argument("--workers", type=positive_int, help="CPUs of the local Ray (default: all cores)")
    p.add_argument("--serial", action="store_true", help="no Ray: one replay after another in this process")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)
    return p


def scale_range(text: str) -> tuple[float, float]:
    """``LO:HI`` with 0 < LO <= HI, both finite: the range of --jitter-scale's factor."""
    lo, sep, hi = text.partition(":")
    try:
        low, high = float(lo), float(hi)
    except ValueError:
        low = high = math.nan
    if not sep or not (math.isfinite(low) and math.isfinite(high) and 0 < low <= high):
        raise argparse.ArgumentTypeError(f"give two factors LO:HI with 0 < LO <= HI (e.g. 0.7:1.5), not {text!r}")
    return low, high


def parse_trackers(text: str | None) -> tuple[str, ...] | None:
    if text is None:
        return None
    names = tuple(dict.fromkeys(registry.canonical(t.strip()) for t in text.split(",") if t.strip()))
    unknown = [n for n in names if n not in registry.NAMES]
    if not names or unknown:
        raise TrackreplayError(f"--trackers {text!r}: give tracker names from {', '.join(registry.NAMES)}, comma-separated")
    return names


def _use_ray(args: argparse.Namespace) -> bool:
    if args.serial:
        if args.address:
            raise TrackreplayError("--serial and --address contradict each other: give one")
        return False
    if args.address:
        return True
    try:
        import ray  # noqa: F401
    except ImportError:
        return False
    return True


def run(args: argparse.Namespace) -> int:
    from trackreplay.replay.runs.case_logs import recorder_code
    from trackreplay.replay.runs.corpus import load_corpus
    from trackreplay.replay.runs.evaluate import EvalOptions, plan, run_ray, run_serial

    corpus = load_corpus(args.manifest)
    seeds = tuple(parse_seeds(args.seeds))
    trackers = parse_trackers(args.trackers)
    skipped = []
    for case in corpus.cases:
        missing = case.missing()
        if missing is not None:
            skipped.append(f"{case.name}: {missing} is absent")
            print(f"trackreplay: skipping case {skipped[-1]}", file=sys.stderr)
    present = dataclasses.replace(corpus, cases=tuple(c for c in corpus.cases if c.missing() is None))
    cases, tasks = plan(present, seeds, trackers, baseline=not args.no_baseline)
    if not tasks:
        raise TrackreplayError(f"{args.manifest}: no case to run" + (f" with --trackers {args.trackers}" if trackers else "")
                               + (f" ({len(skipped)} skipped: their files are absent)" if skipped else ""))
    notes = []
    csrt = _csrt_python(tasks)
    if csrt is None and any(t.tracker == "csrt" for t in tasks):
        notes.append("OpenCV CSRT rows are missing: its venv could not be built here")
        cases, tasks = plan(present, seeds, trackers, baseline=False)
    out = args.out.resolve()
    if out.exists() and not out.is_dir():
        raise TrackreplayError(f"--out {args.out} is a file, not a folder")
    out.mkdir(parents=True, exist_ok=True)
    opts = EvalOptions(out, seeds, args.jitter, csrt, recorder_code(), args.jitter_scale)
    progress = not args.quiet and sys.stderr.isatty()
    if _use_ray(args):
        rows = run_ray(cases, tasks, opts, address=args.address, workers=args.workers, progress=progress)
    else:
        rows = run_serial(cases, tasks, opts, progress)
    return _write(args, corpus.name, rows, seeds, skipped, notes, out)


def _csrt_python(tasks) -> Path | None:
    """CSRT's venv python when a task needs it; None (and one line) when it cannot be built."""
    if not any(t.tracker == "csrt" for t in tasks):
        return None
    from trackreplay.replay.runs.csrt import BaselineUnavailable, csrt_venv, ensure_csrt

    try:
        return ensure_csrt(csrt_venv())
    except BaselineUnavailable as err:
        print(f"trackreplay: no CSRT baseline: {err}", file=sys.stderr)
        return None


def _write(args: argparse.Namespace, name: str, rows, seeds, skipped: list[str], notes: list[str], out: Path) -> int:
    from trackreplay.replay.runs.evaluate import cases_table, timings_table
    from trackreplay.replay.runs.evaluate_report import summary_markdown, write_plots

    table, timings = cases_table(rows), timings_table(rows)
    write_parquet(table, out / "cases.parquet")
    write_parquet(timings, out / "timings.parquet")
    command = shlex.join(["trackreplay", "evaluate", str(args.manifest), "--out", str(args.out), "--seeds", args.seeds,
                          *(["--trackers", args.trackers] if args.trackers else []),
                          *(["--jitter", f"{args.jitter:g}"] if args.jitter else []),
                          *(["--jitter-scale", "{:g}:{:g}".format(*args.jitter_scale)] if args.jitter_scale else []),
                          *(["--no-baseline"] if args.no_baseline else [])])
    text = summary_markdown(table, title=f"Evaluation: {name}", command=command, seeds=list(seeds), jitter=args.jitter, scale=args.jitter_scale,
                            skipped=skipped, notes=notes)
    text += "\n" + speed_markdown(timings)
    write_bytes(out / "summary.md", text.encode())
    plots = write_plots(table, out / "plots")
    print(text)
    failed = table.filter(pl.col("status") != "ok").height
    print(f"{table.height - failed} of {table.height} replays scored; {out / 'cases.parquet'}, {out / 'summary.md'}, "
          f"{len(plots)} plot(s) in {out / 'plots'}", file=sys.stderr)
    return FAILED if failed else 0


def speed_markdown(timings: pl.DataFrame) -> str:
    """Median ms per frame per tracker, in the tracker's own work (our ``step``, CSRT's ``update``; this machine,
    this run: the one table that is not reproducible)."""
    if timings.is_empty():
        return ""
    per = timings.group_by("tracker", maintain_order=True).agg(pl.col("ms_per_frame").median().alias("ms"),
                                                               pl.len().alias("n"))
    lines = ["## Speed (this machine, this run)", "", "| tracker | median ms per frame (the tracker's own step) | replays |", "|---|---|---|"]
    lines += [f"| {t} | {ms:.1f} | {n} |" for t, ms, n in per.iter_rows() if ms is not None]
    return "\n".join(lines) + "\n"
