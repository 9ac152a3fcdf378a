"""`trackreplay merge LOG [--encoders CSV] [--lens-table CSV] [--groundtruth FILE] [--calibration FILE] -o OUT`:
a new log with side inputs added."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from trackreplay.recorder.merge import MergeInputs, merge
from trackreplay.recorder.sources.groundtruth import FORMATS


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = sub.add_parser("merge", help="add encoders, a lens table, ground truth or a calibration to an existing log (a new log)",
                       description="Copy LOG into a new log OUT with side inputs added as new topics, read as `record` "
                                   "reads them. LOG is never written; a topic LOG already has is refused.")
    p.add_argument("log", type=Path, metavar="LOG")
    p.add_argument("-o", "--out", type=Path, required=True, metavar="OUT.mcap", help="the new log (its folder must exist)")
    p.add_argument("--encoders", type=Path, metavar="CSV", help="PTZ encoder CSV with header t_ns,pan,tilt,zoom,focus (at their own times)")
    p.add_argument("--lens-table", type=Path, metavar="CSV", help="zoom,focus,fx,fy,cx,cy rows (as record --lens-table)")
    p.add_argument("--groundtruth", type=Path, metavar="FILE", help="ground truth as record --groundtruth takes it; "
                   "file frame 1 (or line 1) is the log's first image")
    p.add_argument("--gt-format", choices=FORMATS, default="auto", metavar="FORMAT", help=f"{', '.join(FORMATS)} (default: auto)")
    p.add_argument("--gt-first-frame", type=int, default=0, metavar="N", help="the log's frame the truth's first frame describes (default 0)")
    p.add_argument("--calibration", type=Path, metavar="FILE", help="camera (or stereo) calibration, JSON or OpenCV YAML, as record takes it")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    inputs = MergeInputs(args.encoders, args.lens_table, args.groundtruth, args.gt_format, args.gt_first_frame,
                         args.calibration)
    report = merge(args.log, args.out, inputs)
    for warning in report.warnings:
        print(f"trackreplay: warning: {warning}", file=sys.stderr)
    added = ", ".join(f"{t} {n}" for t, n in sorted(report.added.items())) or "nothing"
    print(f"wrote {args.out}: {args.log} and {added}")
    return 0
