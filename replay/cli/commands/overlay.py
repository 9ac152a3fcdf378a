"""`trackreplay overlay LOG TRAJ --frame N --out overlay.png` (or `--video OUT`): the trajectory drawn
over the log's frames. A trajectory with lines of sight (golf on a PTZ log) is drawn whole into any
frame from them; any other is drawn frame by frame from its image positions, with the log's truth."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import cv2
import numpy as np
import polars as pl

from trackreplay.schemas import topics as T
from trackreplay.schemas.errors import TrackreplayError
from trackreplay.replay.core.export import read_trajectory
from trackreplay.replay.log.frames import FrameTopics, iter_frames
from trackreplay.replay.log.groundtruth import read_groundtruth
from trackreplay.replay.views.overlay import (ImageOverlay, draw, draw_image_frame, has_lines_of_sight, image_overlay,
                                              image_overlay_frames, overlay_frames, project_trajectory,
                                              trajectory_directions)
from trackreplay.replay.log.reader import LogReader


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = sub.add_parser("overlay", help="draw a trajectory over a frame (or every frame) of its log")
    p.add_argument("log", type=Path)
    p.add_argument("trajectory", type=Path, help=".parquet or .csv trajectory (any tracker's; with dx, dy, dz from a "
                   "PTZ log the lines of sight are drawn)")
    p.add_argument("--frame", type=int, help="frame to draw into (PNG/JPEG output)")
    p.add_argument("--out", type=Path, help="output image for --frame")
    p.add_argument("--video", type=Path, help="write every frame with the trajectory so far (.avi MJPG or .mp4 mp4v)")
    p.add_argument("--track-id", type=int)
    p.add_argument("--image-positions", action="store_true", help="draw the image positions (boxes, ids, status, "
                   "truth) even when the trajectory has lines of sight")
    p.add_argument("--no-truth", dest="truth", action="store_false",
                   help="leave out the log's ground truth (default: drawn in magenta beside the boxes when the log has it)")
    p.add_argument("--rrd", type=Path, help="also log the overlay to a Rerun .rrd")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    if (args.frame is None) == (args.video is None):
        raise TrackreplayError("give either --frame N with --out IMAGE, or --video OUT")
    if args.out is not None and not cv2.haveImageWriter(str(args.out)):  # before any work (OpenCV raises at the write)
        raise TrackreplayError(f"--out {args.out}: OpenCV writes no image format by that name (use .png or .jpg)")
    if args.frame is not None and args.out is None:
        raise TrackreplayError("--frame needs --out IMAGE")
    table = read_trajectory(args.trajectory)
    reader = LogReader(args.log)
    topics = FrameTopics.detect(reader)
    if has_lines_of_sight(table) and not args.image_positions:
        rows = trajectory_directions(table, args.track_id)
        drawing: pl.DataFrame | ImageOverlay = rows
    else:
        truth = read_groundtruth(reader) if args.truth and T.GROUNDTRUTH in reader.topics() else None
        drawing = image_overlay(table, truth, args.track_id)
    rec = sink = None
    if args.rrd is not None:
        import rerun.blueprint as rrb

        from trackreplay.replay.views.rerun_sink import RerunSink

        sink = RerunSink(args.rrd, f"{args.log.stem}-overlay", rrb.Blueprint(rrb.Spatial2DView(origin="/")))
        rec = sink.rec
    try:
        if args.frame is not None:
            return _one_frame(args, reader, topics, drawing, rec)
        return _video(args, reader, topics, drawing, rec)
    finally:
        if sink is not None:
            sink.close()


def _one_frame(args: argparse.Namespace, reader: LogReader, topics: FrameTopics, drawing, rec) -> int:
    frame = next((f for f in iter_frames(reader, topics) if f.index == args.frame), None)
    if frame is None:
        raise TrackreplayError(f"{args.log} has no frame {args.frame} on {topics.image}")
    if isinstance(drawing, ImageOverlay):
        image, pts = draw_image_frame(frame.image, drawing, frame.index), None
        now = drawing.tracks.span(frame.index, frame.index)
        truth = 0 if drawing.truth is None else len(drawing.truth.ids[drawing.truth.span(frame.index, frame.index)])
        said = f"{now.stop - now.start} track position(s) and {truth} truth object(s) on frame {args.frame}"
    else:
        pts = project_trajectory(drawing, frame)
        image = draw(frame.image, pts)
        visible = int(np.isfinite(pts.points).all(axis=1).sum())
        said = f"{visible} of {len(drawing)} trajectory points in front of frame {args.frame}'s camera"
    args.out.parent.mkdir(parents=True, exist_ok=True)
    if not cv2.imwrite(str(args.out), image):
        raise TrackreplayError(f"{args.out}: OpenCV cannot write this image format")
    print(f"wrote {args.out}: {said}")
    if rec is not None:
        _log(rec, frame, image, pts)
    return 0


def _video(args: argparse.Namespace, reader: LogReader, topics: FrameTopics, drawing, rec) -> int:
    fourcc = "mp4v" if args.video.suffix.lower() == ".mp4" else "MJPG"
    writer = None
    n = 0
    if isinstance(drawing, ImageOverlay):
        drawn = ((f, image, None) for f, image in image_overlay_frames(iter_frames(reader, topics), drawing))
    else:
        drawn = overlay_frames(iter_frames(reader, topics), drawing, progressive=True)
    for frame, image, pts in drawn:
        if writer is None:
            h, w = image.shape[:2]
            fps = _fps(reader, topics.image)
            writer = cv2.VideoWriter(str(args.video), cv2.VideoWriter_fourcc(*fourcc), fps, (w, h))
            if not writer.isOpened():
                raise TrackreplayError(f"{args.video}: OpenCV cannot open a {fourcc} video writer here")
        writer.write(image if image.ndim == 3 else cv2.cvtColor(image, cv2.COLOR_GRAY2BGR))
        if rec is not None and (pts is not None or isinstance(drawing, ImageOverlay)):
            _log(rec, frame, image, pts)
        n += 1
    if writer is not None:
        writer.release()
    print(f"wrote {args.video}: {n} frames", file=sys.stderr)
    return 0


def _fps(reader: LogReader, topic: str) -> float:
    t0, t1 = reader.time_range()
    n = reader.topics()[topic].count
    return (n - 1) / ((t1 - t0) / 1e9) if n > 1 and t1 > t0 else 30.0


def _log(rec, frame, image, pts) -> None:
    import rerun as rr

    rec.set_time("frame", sequence=frame.index)
    rec.set_time("log_time", timestamp=np.datetime64(frame.t_ns, "ns"))
    rec.log("overlay/image", rr.Image(image, color_model="BGR"))
    if pts is None:  # image positions: drawn into the image
        return
    keep = np.isfinite(pts.points).all(axis=1)
    rec.log("overlay/trajectory", rr.LineStrips2D([pts.points[keep]], colors=[(255, 215, 0)]))
