"""`trackreplay info LOG [--json]`: topics, rates, gaps, stereo pairing, encoder coverage."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from trackreplay.replay.log.info import format_info, log_info, problem_message
from trackreplay.schemas.errors import TruncatedLogError


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = sub.add_parser("info", help="what a log holds: topics, counts, rates, gaps, stereo pairing, encoder coverage",
                       description="Report a log's contents. A log that ends early (TRUNCATED) or has unreadable "
                                   "chunks (DAMAGED) is reported as far as it is readable, then the command fails "
                                   "with exit status 3.")
    p.add_argument("log", type=Path, metavar="LOG")
    p.add_argument("--json", action="store_true", help="print the report as JSON")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    info = log_info(args.log, partial_ok=True)
    print(json.dumps(info, indent=2) if args.json else format_info(info))
    if not info["complete"]:  # damaged chunks, or a file that ends early: exit 3 either way
        chunking = {"chunks": info["chunks"], "messages_expected": info["messages_expected"]}
        raise TruncatedLogError(problem_message(args.log, info["truncated"], info["damaged"], info["messages"], chunking))
    return 0
