"""`trackreplay cat LOG [--topic T ...] [--exclude T ...] [--limit N]`: messages as JSON lines."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from trackreplay.replay.log.cat import records
from trackreplay.replay.log.reader import LogMessage, LogReader
from trackreplay.replay.log.topic_select import select_topics
from trackreplay.schemas.errors import TruncatedLogError

from trackreplay.replay.cli.commands.values import non_negative_int


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = sub.add_parser("cat", help="print a log's messages as JSON lines (log time, topic, decoded fields)",
                       description="One JSON object a line, in log-time order: log_time_ns, topic, schema, index (on "
                                   "its topic), message (the decoded fields; an image's bytes as their size and, for "
                                   "PNG/JPEG, shape [height, width]). A log with damaged chunks prints what is readable, "
                                   "then exits 3.")
    p.add_argument("log", type=Path, metavar="LOG")
    p.add_argument("--topic", action="append", default=[], metavar="T",
                   help="topic to print: a name, a glob ('camera/*') or re:REGEX (repeatable; default every topic)")
    p.add_argument("--exclude", action="append", default=[], metavar="T", help="topic to leave out (name, glob or re:REGEX; repeatable)")
    p.add_argument("--limit", type=non_negative_int, metavar="N", help="stop after N messages")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    reader = LogReader(args.log)
    topics = select_topics(reader.topics(), args.topic, args.exclude, str(args.log))
    lost: list[LogMessage] = []
    out = sys.stdout
    for record in records(reader, topics, args.limit, lost):
        out.write(json.dumps(record, separators=(",", ":"), allow_nan=False) + "\n")
    if lost:
        first = lost[0]
        raise TruncatedLogError(f"{args.log}: {len(lost)} message(s) could not be read ({first.topic} message "
                                f"{first.index}: {first.lost}); run `trackreplay recover {args.log} OUT.mcap` to "
                                f"salvage every intact chunk")
    return 0
