"""`trackreplay diff A B`: the first frame where two replays diverge and which intermediate differs."""

from __future__ import annotations

import argparse
from pathlib import Path

from trackreplay.replay import registry
from trackreplay.replay.batch_config import apply_sets, parse_assignment
from trackreplay.replay.diff import RunSpec, diff_recordings, diff_runs, load_side, load_summary, recording_of_run
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
    p.add_argument("--tracker", default="flow", choices=registry.NAMES, help="tracker for .mcap operands (default flow)")
    p.add_argument("--seed", type=int, default=0, help="seed for .mcap operands (default 0)")
    p.add_argument("--config", type=Path, help="tracker config TOML for .mcap operands")
    p.add_argument("--set", dest="sets", action="append", default=[], metavar="KEY=VALUE",
                   help="config value for both .mcap operands (golf.particles.n=500)")
    p.add_argument("--a", dest="a_sets", action="append", default=[], metavar="KEY=VALUE",
                   help="override for A only: seed=N, config=FILE or a config key")
    p.add_argument("--b", dest="b_sets", action="append", default=[], metavar="KEY=VALUE", help="override for B only")
    p.set_defaults(func=run)
    return p


def _spec(log: Path, args: argparse.Namespace, overrides: list[str]) -> RunSpec:
    seed, config, sets = args.seed, args.config, {}
    for text in [*args.sets, *overrides]:
        key, value = parse_assignment(text)
        if key == "seed":
            if not isinstance(value, int):
                raise TrackreplayError(f"seed must be an integer, not {value!r}")
            seed = value
        elif key == "config":
            config = Path(str(value))
        else:
            sets[key] = value
    return RunSpec(log, args.tracker, seed, apply_sets(args.tracker, config, sets) if sets else config)


def run(args: argparse.Namespace) -> int:
    kinds = [load_side(args.a), load_side(args.b)]
    if any(kind == "rrd" for kind, _ in kinds):
        from trackreplay.replay.diff_rrd import diff_rrd

        if not all(kind == "rrd" for kind, _ in kinds):
            raise TrackreplayError("an .rrd file is compared with another .rrd file only")
        result = diff_rrd(kinds[0][1], kinds[1][1])
    elif all(kind == "log" for kind, _ in kinds):
        result = diff_runs(_spec(kinds[0][1], args, args.a_sets), _spec(kinds[1][1], args, args.b_sets))
    else:
        sides = []
        for (kind, path), overrides in zip(kinds, (args.a_sets, args.b_sets)):
            sides.append(load_summary(path)[1] if kind == "summary" else recording_of_run(_spec(path, args, overrides)))
        result = diff_recordings(*sides)
    print(result.report())
    return 0 if result.identical else DIFFERENT
