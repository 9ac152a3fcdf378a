"""`trackreplay diff A B`: the first frame where two replays diverge and which intermediate differs."""

from __future__ import annotations

import argparse
from pathlib import Path

from trackreplay.replay.core import registry
from trackreplay.replay.runs.batch_config import apply_sets, parse_assignment, refuse_repeats
from trackreplay.replay.cli.commands.values import seed_int
from trackreplay.replay.core.engine import check_seed
from trackreplay.replay.analysis.diff import RunSpec, diff_recordings, diff_runs, load_side, load_summary, recording_of_run
from trackreplay.schemas.errors import TrackreplayError

DIFFERENT = 1  # like diff(1): 0 identical, 1 different, 2 trouble


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = sub.add_parser(
        "diff", help="first frame where two replays diverge, and which intermediate differs (exit 0 when identical)",
        description="A and B are two replay summaries (.json, with the per-frame digests written beside them), "
                    "or two logs (.mcap) replayed here with --tracker/--seed/--config and per-side overrides "
                    "(--a seed=1, --b golf.particles.n=500, --b config=other.toml).")
    p.add_argument("a", help="summary .json or log .mcap")
    p.add_argument("b", help="summary .json or log .mcap")
    p.add_argument("--tracker", type=registry.canonical, choices=registry.NAMES, help="tracker for .mcap operands (default flow)")
    p.add_argument("--seed", type=seed_int, help="seed for .mcap operands (default 0)")
    p.add_argument("--config", type=Path, help="tracker config TOML for .mcap operands")
    p.add_argument("--set", dest="sets", action="append", default=[], metavar="KEY=VALUE",
                   help="config value for both .mcap operands (golf.particles.n=500)")
    p.add_argument("--a", dest="a_sets", action="append", default=[], metavar="KEY=VALUE",
                   help="override for A only: seed=N, config=FILE or a config key")
    p.add_argument("--b", dest="b_sets", action="append", default=[], metavar="KEY=VALUE", help="override for B only")
    p.set_defaults(func=run)
    return p


def _spec(log: Path, args: argparse.Namespace, side: str) -> RunSpec:
    """How one .mcap operand is replayed: the shared options, then ``side``'s (``--a`` / ``--b``) overrides."""
    overrides = args.a_sets if side == "--a" else args.b_sets
    tracker = args.tracker or "flow"
    seed, config, sets = args.seed or 0, args.config, {}
    for given, option in ((args.sets, "--set"), (overrides, side)):  # (a side's may override a shared one)
        refuse_repeats([parse_assignment(t)[0] for t in given], tracker, "give it once", option)
    shared = [parse_assignment(t)[0] for t in args.sets]
    for key, option in (("seed", "--seed"), ("config", "--config")):
        if key in shared and getattr(args, key) is not None:
            raise TrackreplayError(f"{option} and --set {key}=... both give the {key} for both operands: give it once")
    for text in [*args.sets, *overrides]:
        key, value = parse_assignment(text)
        if key == "seed":
            seed = check_seed(value)
        elif key == "config":
            config = Path(str(value))
        else:
            sets[key] = value
    return RunSpec(log, tracker, seed, apply_sets(tracker, config, sets) if sets else config)


def _check_run_options(kinds: list[tuple[str, Path]], args: argparse.Namespace) -> None:
    """Refuse run options that would be ignored: they apply to a .mcap operand only."""
    logs = [kind == "log" for kind, _ in kinds]
    for side, overrides, (kind, path) in (("--a", args.a_sets, kinds[0]), ("--b", args.b_sets, kinds[1])):
        if overrides and kind != "log":
            raise TrackreplayError(f"{side} {overrides[0]} applies only to a .mcap operand (a log replayed here), "
                                   f"and {path} is a {'replay summary' if kind == 'summary' else '.rrd file'}")
    if not any(logs):
        given = [name for name, value in (("--tracker", args.tracker), ("--seed", args.seed), ("--config", args.config),
                                          ("--set", args.sets)) if value not in (None, [])]
        if given:
            raise TrackreplayError(f"{given[0]} applies only to a .mcap operand (a log replayed here), and neither "
                                   f"{args.a} nor {args.b} is one")


def _mismatch(a: tuple[str | None, str | None], b: tuple[str | None, str | None]) -> str:
    """A first line when A and B, as (tracker, log file name), replay different trackers or logs."""
    parts = [f"{what} ({x} vs {y})" for what, x, y in (("tracker", a[0], b[0]), ("log", a[1], b[1])) if x and y and x != y]
    return f"A and B replay a different {' and '.join(parts)}" if parts else ""


def run(args: argparse.Namespace) -> int:
    kinds = [load_side(args.a), load_side(args.b)]
    _check_run_options(kinds, args)
    head = ""
    if any(kind == "rrd" for kind, _ in kinds):
        from trackreplay.replay.analysis.diff_rrd import diff_rrd

        if not all(kind == "rrd" for kind, _ in kinds):
            raise TrackreplayError("an .rrd file is compared with another .rrd file only")
        result = diff_rrd(kinds[0][1], kinds[1][1])
    elif all(kind == "log" for kind, _ in kinds):
        result = diff_runs(_spec(kinds[0][1], args, "--a"), _spec(kinds[1][1], args, "--b"))
    else:
        sides, ids = [], []
        for (kind, path), side in zip(kinds, ("--a", "--b")):
            if kind == "summary":  # a summary records its tracker and log
                summary, recording = load_summary(path)
                ids.append((summary.get("tracker"), Path(str(summary["log"])).name if summary.get("log") else None))
                sides.append(recording)
            else:
                spec = _spec(path, args, side)
                ids.append((spec.tracker, path.name))
                sides.append(recording_of_run(spec))
        head = _mismatch(*ids)
        result = diff_recordings(*sides)
    print("\n".join(filter(None, [head, result.report()])))
    return 0 if result.identical else DIFFERENT
