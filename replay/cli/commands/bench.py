"""`trackreplay bench LOG --tracker NAME`: replay speed vs read+decode, and the cost of Rerun logging."""

from __future__ import annotations

import argparse
from pathlib import Path

from trackreplay.replay.cli.commands.values import positive_int
from trackreplay.replay.core import registry
from trackreplay.replay.runs.bench import format_timing, time_replay
from trackreplay.replay.core.outputs import write_json
from trackreplay.schemas.errors import OutputError


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = sub.add_parser("bench", help="time a replay against read+decode of the same log, with and without --rrd")
    p.add_argument("log", type=Path)
    p.add_argument("--tracker", default="flow", type=registry.canonical, choices=registry.NAMES)
    p.add_argument("--config", type=Path)
    p.add_argument("--repeats", type=positive_int, default=3, help="timed runs of each kind (default 3)")
    p.add_argument("--json", type=Path, help="also write the timings as JSON")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    if args.json and not args.json.parent.is_dir():  # before minutes of timing, not after
        raise OutputError(f"cannot write --json {args.json}: the folder {args.json.parent} does not exist")
    timing = time_replay(args.log, args.tracker, args.repeats, args.config)
    print(format_timing(f"{args.tracker} on {args.log}", timing))
    if args.json:
        write_json(args.json, {
            "log": str(args.log), "tracker": args.tracker, "frames": timing.frames,
            "read_decode_s": timing.read_decode_s, "replay_s": timing.replay_s, "replay_rrd_s": timing.replay_rrd_s,
            "throughput_ratio": timing.throughput_ratio, "rerun_ratio": timing.rerun_ratio, "rrd_bytes": timing.rrd_bytes,
        })
    return 0
