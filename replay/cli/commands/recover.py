"""`trackreplay recover BROKEN OUT`: salvage every intact chunk of a truncated or damaged log.

Exit 0: the source was complete (OUT is an equivalent copy); 1: partial salvage; 2: nothing could be
saved, or BROKEN is not an MCAP file. OUT is always a valid log when the command gets to write it.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from trackreplay.recorder.recover import recover


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = sub.add_parser("recover", help="salvage a truncated or damaged log into a valid one",
                       description="Copy every intact chunk of BROKEN into the valid log OUT, skipping damaged "
                                   "stretches and resuming at the next intact chunk. Exit status 0 when BROKEN was "
                                   "complete, 1 when only part of it could be saved, 2 when nothing could.")
    p.add_argument("broken", type=Path, metavar="BROKEN")
    p.add_argument("out", type=Path, metavar="OUT")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    report = recover(args.broken, args.out)
    extra = "".join(
        f", {n} {what}" for n, what in ((report.attachments_saved, "attachment(s)"), (report.metadata_saved, "metadata record(s)")) if n
    )
    if report.complete:
        print(f"{args.broken} was complete; wrote {args.out} with {report.messages_saved} messages{extra}")
    elif report.exit_code == 1:
        print(f"saved {report.messages_saved} messages{extra} to {args.out}; {args.broken} is damaged ({report.error})")
    else:
        print(f"nothing could be saved from {args.broken} ({report.error}); {args.out} is a valid empty log")
    return report.exit_code
