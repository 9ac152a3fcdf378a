"""`trackreplay filter LOG OUT [--topic T ...] [--exclude T ...] [--start S] [--end S]`: a valid new log
with the chosen topics (names, globs or re:REGEX) and times (calibration, encoders around the range and
renumbered marks kept usable)."""

from __future__ import annotations

import argparse
from pathlib import Path

from trackreplay.recorder.filter import filter_log
from trackreplay.schemas.errors import TrackreplayError

from trackreplay.replay.cli.commands.values import non_negative_float
from trackreplay.replay.log.frames import choose_image_topic
from trackreplay.replay.log.reader import LogReader
from trackreplay.replay.log.topic_select import select_topics


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = sub.add_parser("filter", help="copy some topics and a time range of a log into a new log")
    p.add_argument("log", type=Path)
    p.add_argument("out", type=Path)
    p.add_argument("--topic", action="append", default=[], metavar="T",
                   help="topic to keep: a name, a glob ('camera/*') or re:REGEX (repeatable; default all)")
    p.add_argument("--exclude", action="append", default=[], metavar="T",
                   help="topic to leave out: a name, a glob or re:REGEX (repeatable)")
    p.add_argument("--start", type=non_negative_float, help="start, seconds from the log's first message (as replay --start)")
    p.add_argument("--end", type=non_negative_float, help="end (exclusive), seconds from the log's first message")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    if args.start is not None and args.end is not None and args.end <= args.start:
        raise TrackreplayError(f"--end {args.end:g} must be after --start {args.start:g}")
    if args.out.resolve() == args.log.resolve():
        raise TrackreplayError("OUT must be a new file, not LOG itself")
    reader = LogReader(args.log)
    topics = select_topics(reader.topics(), args.topic, args.exclude, str(args.log)) if args.topic or args.exclude else None
    t0, _ = reader.time_range()
    start = None if args.start is None else t0 + int(round(args.start * 1e9))
    end = None if args.end is None else t0 + int(round(args.end * 1e9))
    try:
        image = choose_image_topic(reader)
    except TrackreplayError:
        image = None  # no image topic: marks cannot be renumbered, and there is nothing to renumber for
    report = filter_log(args.log, args.out, topics, start, end, image)
    kept = ", ".join(f"{t} {n}" for t, n in sorted(report.kept.items())) or "nothing"
    print(f"wrote {args.out}: {kept}" + (f"; {report.marks_dropped} mark(s) outside the range dropped"
                                          if report.marks_dropped else ""))
    return 0
