"""`trackreplay eval TRAJ LOG`: metrics against the log's ground truth."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import polars as pl

from trackreplay.replay.cli.commands.values import finite_json, positive_float
from trackreplay.replay.analysis.eval import check_frames, evaluate, format_summary
from trackreplay.replay.core.export import read_trajectory
from trackreplay.replay.log.frames import image_times
from trackreplay.replay.log.groundtruth import groundtruth_with_frames
from trackreplay.replay.analysis.mot import MAX_DISTANCE_M
from trackreplay.replay.log.reader import LogReader


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = sub.add_parser("eval", help="centre error, IoU and velocity error against /groundtruth/objects")
    p.add_argument("trajectory", type=Path, help=".parquet or .csv trajectory")
    p.add_argument("log", type=Path, help="the log holding the ground truth")
    p.add_argument("--track-id", type=int, help="track to evaluate (default: the longest)")
    p.add_argument("--gt-id", type=int, help="ground-truth object (default: the one seen most)")
    p.add_argument("--json", type=Path, help="also write the metrics as JSON")
    p.add_argument("--per-frame", type=Path, help="also write the per-frame errors (.csv or .parquet)")
    p.add_argument("--mot", action="store_true",
                   help="multi-object metrics over every track: MOTA, MOTP, IDF1, ID switches on image boxes (IoU >= 0.5) "
                        "and on 3-D positions (--max-distance-m; not applicable when the trajectory or the truth has no "
                        "X, Y, Z); HOTA, DetA, AssA, LocA over alpha 0.05..0.95 with IoU and with max(0, 1 - d/max-distance-m) "
                        "as the similarity; a box on a frame whose truth shows no object is a false positive")
    p.add_argument("--gt-topic", default=None, help="ground-truth topic (default /groundtruth/objects; "
                   "the groups scenes also write /groundtruth/groups)")
    p.add_argument("--image-topic", help="the image topic the trajectory was replayed on, whose frames it numbers "
                   "(default as replay's: /camera/image, else the stereo left, else the log's only image topic)")
    p.add_argument("--max-distance-m", type=positive_float, default=MAX_DISTANCE_M, help="3-D match distance for --mot, and the distance at which the 3-D HOTA similarity reaches 0 (default %(default)s m)")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    traj = read_trajectory(args.trajectory)
    reader = LogReader(args.log)
    gt, annotated = groundtruth_with_frames(reader, *([args.gt_topic] if args.gt_topic else []))
    check_frames(traj, str(args.trajectory), image_times(reader, args.image_topic), annotated, str(args.log))
    if args.mot:
        return _run_mot(args, traj, gt, annotated["frame"])
    summary, frames = evaluate(traj, gt, track_id=args.track_id, gt_id=args.gt_id)
    print(format_summary(summary))
    if args.json:
        _write_json(args.json, summary.as_dict())
    if args.per_frame:
        (frames.write_parquet if args.per_frame.suffix == ".parquet" else frames.write_csv)(args.per_frame)
    return 0


def _run_mot(args: argparse.Namespace, traj: pl.DataFrame, gt: pl.DataFrame, frames: pl.Series) -> int:
    """CLEAR MOT and HOTA over every annotated frame, on image boxes and, where both the trajectory and
    the truth have them, on 3-D positions."""
    from trackreplay.replay.analysis.mot import format_hota, format_mot, hota_metrics, mot_metrics, three_d_missing

    image = mot_metrics(traj, gt, space="image", frames=frames)
    image_hota = hota_metrics(traj, gt, space="image", frames=frames)
    why_not = three_d_missing(traj, gt)
    space = space_hota = None
    if why_not is None:
        space = mot_metrics(traj, gt, space="3d", max_distance_m=args.max_distance_m, frames=frames)
        space_hota = hota_metrics(traj, gt, space="3d", max_distance_m=args.max_distance_m, frames=frames)
    label = f"3-D positions (<= {args.max_distance_m:g} m)"
    print(format_mot(image, "image boxes (IoU >= 0.5)"))
    print(format_mot(space, label) if space else f"{label}: not applicable ({why_not})")
    print(format_hota(image_hota, "image boxes (IoU similarity)"))
    if space_hota:
        print(format_hota(space_hota, f"3-D positions (1 - d/{args.max_distance_m:g} m)"))
    if args.json:
        _write_json(args.json, {"image": image.as_dict(), "3d": space and space.as_dict(),
                                "hota": {"image": image_hota.as_dict(), "3d": space_hota and space_hota.as_dict()},
                                "3d_not_applicable": why_not})
    return 0


def _write_json(path: Path, data: dict) -> None:
    """Strict JSON: a metric that is undefined (no truth, no match) is null, not NaN."""
    from trackreplay.replay.core.outputs import write_bytes  # NAME.partial, renamed when complete

    write_bytes(path, (json.dumps(finite_json(data), indent=2, allow_nan=False) + "\n").encode())
