"""`trackreplay annotate LOG --frame N --box x,y,w,h`: mark what to track in any log; `--from-truth`
marks where the log's ground truth places the target (a benchmark's start)."""

from __future__ import annotations

import argparse
from pathlib import Path

from trackreplay.recorder.annotate import annotate, clip_mark, marks_from_truth, parse_box, read_marks_csv
from trackreplay.schemas.errors import TrackreplayError

from trackreplay.replay.core import registry
from trackreplay.replay.cli.commands.frame import frame_image, image_topic
from trackreplay.replay.log.marks import check_inside, check_labels, check_one_start_per_frame
from trackreplay.replay.log.reader import LogReader


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = sub.add_parser("annotate", help="add /annotations/init (marked boxes) to a log")
    p.add_argument("log", type=Path)
    p.add_argument("--frame", type=int, help="frame the --box (or --from-truth) marks are on")
    p.add_argument("--box", action="append", default=[], help="x,y,w,h top-left corner and size in pixels (repeatable)")
    p.add_argument("--from-csv", type=Path, help="marks as rows frame,x,y,w,h[,label]")
    p.add_argument("--from-truth", action="store_true",
                   help="mark the ground truth's box at --frame (default: its first frame with a visible target), "
                        "or a --mark-size square round a point truth")
    p.add_argument("--mark-size", type=float, default=12.0, metavar="S",
                   help="side in pixels of the square marked round a point truth (default 12)")
    p.add_argument("--truth-id", type=int, action="append", metavar="ID",
                   help="with --from-truth: the truth object to mark (repeatable; default every visible one)")
    p.add_argument("--label", default="target", help="label of the marks (e.g. ball; default target)")
    p.add_argument("--image-topic", help="image topic the frames count on (default: as replay chooses it)")
    p.add_argument("--tracker", type=registry.canonical, choices=registry.NAMES,
                   help="refuse labels this tracker would ignore (flow reads only 'target'; golf any)")
    dest = p.add_mutually_exclusive_group(required=True)
    dest.add_argument("--out", type=Path, help="write the annotated log here")
    dest.add_argument("--in-place", action="store_true", help="replace LOG atomically once the new log is complete")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    marks = []
    if args.truth_id and not args.from_truth:
        raise TrackreplayError("--truth-id needs --from-truth")
    truth_marks = marks_from_truth(args.log, args.frame, args.mark_size, args.label, args.truth_id) if args.from_truth else []
    if args.box:
        if args.frame is None:
            raise TrackreplayError("--box needs --frame N")
        marks.extend(parse_box(b, args.frame, args.label) for b in args.box)
    if args.from_csv:
        marks.extend(read_marks_csv(args.from_csv, args.label))
    if not marks and not truth_marks:
        raise TrackreplayError("nothing to add: give --frame N --box x,y,w,h, --from-csv FILE or --from-truth")
    out = args.log if args.in_place else args.out
    reader = LogReader(args.log)
    topic = image_topic(reader, args.image_topic)
    first = min(mk.frame for mk in [*marks, *truth_marks])
    height, width = frame_image(reader, topic, first).shape[:2]  # also: the frame exists
    marks.extend(clip_mark(mk, width, height) for mk in truth_marks)  # (a truth box may reach past the picture)
    for mk in marks:  # (one at a time: a mark from a CSV is named by its file:line)
        check_inside([(mk.frame, mk.x, mk.y, mk.w, mk.h)], width, height, mk.source or f"{args.log}: {topic}")
    if args.tracker:
        check_labels({mk.label for mk in marks}, registry.find(args.tracker), "annotate")
        check_one_start_per_frame(marks, registry.find(args.tracker), "annotate")
    regions = annotate(args.log, out, marks, topic)
    print(f"wrote {out}: {len(regions)} marked region(s) on frames {sorted({r.frame for r in regions})}")
    return 0
