"""`trackreplay annotate LOG --frame N --box x,y,w,h`: mark what to track in any log."""

from __future__ import annotations

import argparse
from pathlib import Path

from trackreplay.recorder.annotate import annotate, parse_box, read_marks_csv
from trackreplay.schemas.errors import TrackreplayError

from trackreplay.replay import registry
from trackreplay.replay.commands.frame import frame_image, image_topic
from trackreplay.replay.marks import check_inside, check_labels, check_one_start_per_frame
from trackreplay.replay.reader import LogReader


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = sub.add_parser("annotate", help="add /annotations/init (marked boxes) to a log")
    p.add_argument("log", type=Path)
    p.add_argument("--frame", type=int, help="frame the --box marks are on")
    p.add_argument("--box", action="append", default=[], help="x,y,w,h top-left corner and size in pixels (repeatable)")
    p.add_argument("--from-csv", type=Path, help="marks as rows frame,x,y,w,h[,label]")
    p.add_argument("--label", default="target", help="label of the marks (e.g. ball; default target)")
    p.add_argument("--image-topic", help="image topic the frames count on (default: as replay chooses it)")
    p.add_argument("--tracker", choices=registry.NAMES,
                   help="refuse labels this tracker would ignore (flow reads only 'target'; golf any)")
    dest = p.add_mutually_exclusive_group(required=True)
    dest.add_argument("--out", type=Path, help="write the annotated log here")
    dest.add_argument("--in-place", action="store_true", help="replace LOG atomically once the new log is complete")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    marks = []
    if args.box:
        if args.frame is None:
            raise TrackreplayError("--box needs --frame N")
        marks.extend(parse_box(b, args.frame, args.label) for b in args.box)
    if args.from_csv:
        marks.extend(read_marks_csv(args.from_csv, args.label))
    if not marks:
        raise TrackreplayError("nothing to add: give --frame N --box x,y,w,h or --from-csv FILE")
    out = args.log if args.in_place else args.out
    reader = LogReader(args.log)
    topic = image_topic(reader, args.image_topic)
    first = min(mk.frame for mk in marks)
    height, width = frame_image(reader, topic, first).shape[:2]  # also: the frame exists
    for mk in marks:  # (one at a time: a mark from a CSV is named by its file:line)
        check_inside([(mk.frame, mk.x, mk.y, mk.w, mk.h)], width, height, mk.source or f"{args.log}: {topic}")
    if args.tracker:
        check_labels({mk.label for mk in marks}, args.tracker, registry.get(args.tracker).tracker_cls, "annotate")
        check_one_start_per_frame(marks, args.tracker, registry.get(args.tracker).tracker_cls, "annotate")
    regions = annotate(args.log, out, marks, topic)
    print(f"wrote {out}: {len(regions)} marked region(s) on frames {sorted({r.frame for r in regions})}")
    return 0
