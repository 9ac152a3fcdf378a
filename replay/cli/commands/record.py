"""`trackreplay record OUT.mcap --video F | --images DIR | --stereo L R [...]`: sources -> MCAP."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from trackreplay.recorder.image_codec import ENCODINGS
from trackreplay.recorder.record import RecordTopics, record
from trackreplay.recorder.sources.groundtruth import FORMATS
from trackreplay.schemas.errors import OutputError, TrackreplayError


def check_output_folder(out: Path) -> None:
    """A log is written only into a folder that exists (exit 5, as every output that cannot be written)."""
    if not out.parent.is_dir():
        raise OutputError(f"cannot write {out}: output folder {out.parent} does not exist")


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = sub.add_parser(
        "record", help="record a video, image folder or stereo pair (+ encoders, calibration, ground truth) to MCAP",
        description="Record one image source and optional side inputs into one MCAP log. "
                    "JPEG/PNG files keep their bytes; video frames and BMP files are encoded as --encoding.",
    )
    p.add_argument("out", type=Path, metavar="OUT.mcap", help="output log")
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--video", type=Path, help="a video file (any container/codec OpenCV reads)")
    src.add_argument("--images", type=Path, metavar="DIR", help="a folder of jpg/jpeg/png/bmp images, natural order")
    src.add_argument("--stereo", type=Path, nargs=2, metavar=("LEFT", "RIGHT"), help="two videos or two image folders")
    p.add_argument("--fps", type=float, help="frame rate (default: the video's own; required for images without --timestamps)")
    p.add_argument("--t0", type=int, default=0, metavar="NS", help="capture time of the first frame in ns (default 0; ignored with --timestamps)")
    p.add_argument("--timestamps", type=Path, metavar="FILE", help="one integer t_ns per line, one line per frame")
    p.add_argument("--calibration", type=Path, metavar="FILE", help="calibration: JSON or OpenCV YAML with width, height, K, D (stereo: baseline_m or right_P)")
    p.add_argument("--encoders", type=Path, metavar="CSV", help="PTZ encoder CSV with header t_ns,pan,tilt,zoom,focus")
    p.add_argument("--lens-table", type=Path, metavar="CSV", help="zoom,focus,fx,fy,cx,cy rows; '# width: W', '# height: H', '# camera_position: X, Y, Z' comments")
    p.add_argument("--groundtruth", type=Path, metavar="FILE", help="ground truth: MOTChallenge gt.txt, OTB groundtruth_rect.txt, VOT polygons, point labels "
                        "frame,visible,x,y, TrackNet Label.csv/*_ball.csv, reference frame,x,y")
    p.add_argument("--ground-plane", type=Path, metavar="FILE",
                   help="fixed camera over flat ground: JSON with width, height, image_to_ground (3x3) or points [[u,v,X,Y],...], "
                        "camera_ground [X,Y], camera_height (see recorder/sources/ground_plane.py)")
    p.add_argument("--ground-plane-from-truth", action="store_true",
                   help="fit the ground plane to the --groundtruth file's boxes and ground positions (MOTChallenge X,Y in "
                        "metres: each box's bottom-centre is a foot on the ground); the fit's error is reported")
    p.add_argument("--gt-format", "--groundtruth-format", dest="gt_format", choices=FORMATS, default="auto", metavar="FORMAT",
                   help=f"annotation format: {', '.join(FORMATS)} (default: auto, detected)")
    p.add_argument("--gt-first-frame", type=int, default=0, metavar="N",
                   help="the recorded frame (0-based) the annotation's first frame describes (default 0; OTB's David, "
                        "whose truth starts at image 300: 299)")
    p.add_argument("--encoding", choices=ENCODINGS, default="jpeg", help="encoding of decoded frames (default jpeg)")
    p.add_argument("--flush-every", type=int, default=30, metavar="N", help="flush a chunk every N messages (default 30): a crash loses at most N")
    p.add_argument("--topic", action="append", default=[], metavar="KEY=/NAME",
                   help=f"rename a topic; KEY is one of {', '.join(RecordTopics.keys())} (repeatable)")
    p.add_argument("--quiet", action="store_true", help="no progress bar or summary")
    p.set_defaults(func=run)
    return p


def parse_topics(items: list[str]) -> RecordTopics:
    names = {}
    for item in items:
        key, sep, name = item.partition("=")
        if not sep or key not in RecordTopics.keys() or not name.startswith("/"):
            raise TrackreplayError(f"--topic {item!r} must be KEY=/name with KEY one of {', '.join(RecordTopics.keys())}")
        names[key] = name
    return RecordTopics(**names)


def run(args: argparse.Namespace) -> int:
    if args.flush_every < 1:
        raise TrackreplayError("--flush-every must be at least 1")
    check_output_folder(args.out)
    report = record(
        args.out, video=args.video, images=args.images, stereo=tuple(args.stereo) if args.stereo else None,
        fps=args.fps, t0_ns=args.t0, timestamps=args.timestamps, calibration=args.calibration,
        encoders=args.encoders, lens_table=args.lens_table, groundtruth=args.groundtruth, gt_format=args.gt_format,
        gt_first_frame=args.gt_first_frame,
        ground_plane=args.ground_plane, ground_plane_from_truth=args.ground_plane_from_truth,
        encoding=args.encoding, flush_every=args.flush_every, topics=parse_topics(args.topic), quiet=args.quiet,
    )
    for warning in report.warnings:
        print(f"trackreplay: warning: {warning}", file=sys.stderr)
    if not args.quiet:
        for note in report.notes:
            print(f"trackreplay: {note}", file=sys.stderr)
        per_topic = ", ".join(f"{t} {n}" for t, n in sorted(report.topics.items()))
        print(f"wrote {report.path}: {report.frames} frames, {report.messages} messages ({per_topic})", file=sys.stderr)
    return 7 if report.frames_lost else 0  # a valid log of what could be read, but not the whole source
