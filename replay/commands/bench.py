"""`trackreplay bench LOG --tracker NAME`: replay speed vs read+decode, and the cost of Rerun logging."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from trackreplay.replay.commands.values import positive_int
from trackreplay.replay import registry
from trackreplay.replay.bench import format_timing, time_replay


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = sub.add_parser("bench", help="time a replay against read+decode of the same log, with and without --rrd")
    p.add_argument("log", type=Path)
    p.add_argument("--tracker", default="flow", choices=registry.NAMES)
    p.add_argument("--config", type=Path)
    p.add_argument("--repeats", type=positive_int, default=3, help="timed runs of each kind (default 3)")
    p.add_argument("--json", type=Path, help="also write the timings as JSON")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    timing = time_replay(args.log, args.tracker, args.repeats, args.config)
    print(format_timing(f"{args.tracker} on {args.log}", timing))
    if args.json:
        args.json.write_text(json.dumps({
            "log": str(args.log), "tracker": args.tracker, "frames": timing.frames,
            "read_decode_s": timing.read_decode_s, "replay_s": timing.replay_s, "replay_rrd_s": timing.replay_rrd_s,
            "throughput_ratio": timing.throughput_ratio, "rerun_ratio": timing.rerun_ratio, "rrd_bytes": timing.rrd_bytes,
        }, indent=2) + "\n")
    return 0
