"""`trackreplay overlay LOG TRAJ --frame N --out overlay.png`: the trajectory drawn into any frame."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import cv2
import numpy as np

from trackreplay.schemas.errors import TrackreplayError
from trackreplay.replay.core.export import read_trajectory
from trackreplay.replay.log.frames import FrameTopics, iter_frames
from trackreplay.replay.views.overlay import overlay_frames, project_trajectory, draw, trajectory_directions
from trackreplay.replay.log.reader import LogReader


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = sub.add_parser("overlay", help="draw a trajectory's lines of sight into a frame (or every frame)")
    p.add_argument("log", type=Path)
    p.add_argument("trajectory", type=Path, help=".parquet or .csv with dx, dy, dz (from a PTZ log)")
    p.add_argument("--frame", type=int, help="frame to draw into (PNG/JPEG output)")
    p.add_argument("--out", type=Path, help="output image for --frame")
    p.add_argument("--video", type=Path, help="write every frame with the trajectory so far (.avi MJPG or .mp4 mp4v)")
    p.add_argument("--track-id", type=int)
    p.add_argument("--rrd", type=Path, help="also log the overlay to a Rerun .rrd")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    if (args.frame is None) == (args.video is None):
        raise TrackreplayError("give either --frame N with --out IMAGE, or --video OUT")
    if args.out is not None and not cv2.haveImageWriter(str(args.out)):  # before any work (OpenCV raises at the write)
        raise TrackreplayError(f"--out {args.out}: OpenCV writes no image format by that name (use .png or .jpg)")
    rows = trajectory_directions(read_trajectory(args.trajectory), args.track_id)
    reader = LogReader(args.log)
    topics = FrameTopics.detect(reader)
    rec = None
    if args.rrd is not None:
        import rerun as rr

        from trackreplay.replay.views.rerun_sink import RerunSink
        import rerun.blueprint as rrb

        sink = RerunSink(args.rrd, f"{args.log.stem}-overlay", rrb.Blueprint(rrb.Spatial2DView(origin="/")))
        rec = sink.rec
    try:
        if args.frame is not None:
            if args.out is None:
                raise TrackreplayError("--frame needs --out IMAGE")
            frame = next((f for f in iter_frames(reader, topics) if f.index == args.frame), None)
            if frame is None:
                raise TrackreplayError(f"{args.log} has no frame {args.frame} on {topics.image}")
            pts = project_trajectory(rows, frame)
            image = draw(frame.image, pts)
            args.out.parent.mkdir(parents=True, exist_ok=True)
            if not cv2.imwrite(str(args.out), image):
                raise TrackreplayError(f"{args.out}: OpenCV cannot write this image format")
            visible = int(np.isfinite(pts.points).all(axis=1).sum())
            print(f"wrote {args.out}: {visible} of {len(rows)} trajectory points in front of frame {args.frame}'s camera")
            if rec is not None:
                _log(rec, frame, image, pts)
            return 0
        fourcc = "mp4v" if args.video.suffix.lower() == ".mp4" else "MJPG"
        writer = None
        n = 0
        for frame, image, pts in overlay_frames(iter_frames(reader, topics), rows, progressive=True):
            if writer is None:
                h, w = image.shape[:2]
                fps = _fps(reader, topics.image)
                writer = cv2.VideoWriter(str(args.video), cv2.VideoWriter_fourcc(*fourcc), fps, (w, h))
                if not writer.isOpened():
                    raise TrackreplayError(f"{args.video}: OpenCV cannot open a {fourcc} video writer here")
            writer.write(image if image.ndim == 3 else cv2.cvtColor(image, cv2.COLOR_GRAY2BGR))
            if rec is not None and pts is not None:
                _log(rec, frame, image, pts)
            n += 1
        if writer is not None:
            writer.release()
        print(f"wrote {args.video}: {n} frames", file=sys.stderr)
        return 0
    finally:
        if rec is not None:
            sink.close()


def _fps(reader: LogReader, topic: str) -> float:
    t0, t1 = reader.time_range()
    n = reader.topics()[topic].count
    return (n - 1) / ((t1 - t0) / 1e9) if n > 1 and t1 > t0 else 30.0


def _log(rec, frame, image, pts) -> None:
    import rerun as rr

    rec.set_time("frame", sequence=frame.index)
    rec.set_time("log_time", timestamp=np.datetime64(frame.t_ns, "ns"))
    rec.log("overlay/image", rr.Image(image, color_model="BGR"))
    keep = np.isfinite(pts.points).all(axis=1)
    rec.log("overlay/trajectory", rr.LineStrips2D([pts.points[keep]], colors=[(255, 215, 0)]))
