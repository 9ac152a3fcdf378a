"""`trackreplay eval TRAJ LOG`: metrics against the log's ground truth."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from trackreplay.replay.eval import evaluate, format_summary
from trackreplay.replay.export import read_trajectory
from trackreplay.replay.groundtruth import read_groundtruth
from trackreplay.replay.reader import LogReader


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
                        "and on 3-D positions (--max-distance-m); HOTA, DetA, AssA, LocA over alpha 0.05..0.95 "
                        "with IoU and with max(0, 1 - d/max-distance-m) as the similarity")
    p.add_argument("--gt-topic", default=None, help="ground-truth topic (default /groundtruth/objects; "
                   "the groups scenes also write /groundtruth/groups)")
    p.add_argument("--max-distance-m", type=float, default=1.0, help="3-D match distance for --mot, and the distance at which the 3-D HOTA similarity reaches 0 (default 1 m)")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    traj = read_trajectory(args.trajectory)
    gt = read_groundtruth(LogReader(args.log), *([args.gt_topic] if args.gt_topic else []))
    if args.mot:
        from trackreplay.replay.mot import format_hota, format_mot, hota_metrics, mot_metrics

        image = mot_metrics(traj, gt, space="image")
        space = mot_metrics(traj, gt, space="3d", max_distance_m=args.max_distance_m)
        image_hota = hota_metrics(traj, gt, space="image")
        space_hota = hota_metrics(traj, gt, space="3d", max_distance_m=args.max_distance_m)
        print(format_mot(image, "image boxes (IoU >= 0.5)"))
        print(format_mot(space, f"3-D positions (<= {args.max_distance_m:g} m)"))
        print(format_hota(image_hota, "image boxes (IoU similarity)"))
        print(format_hota(space_hota, f"3-D positions (1 - d/{args.max_distance_m:g} m)"))
        if args.json:
            args.json.write_text(json.dumps({"image": image.as_dict(), "3d": space.as_dict(),
                                             "hota": {"image": image_hota.as_dict(), "3d": space_hota.as_dict()}},
                                            indent=2) + "\n")
        return 0
    summary, frames = evaluate(traj, gt, track_id=args.track_id, gt_id=args.gt_id)
    print(format_summary(summary))
    if args.json:
        args.json.write_text(json.dumps(summary.as_dict(), indent=2) + "\n")
    if args.per_frame:
        (frames.write_parquet if args.per_frame.suffix == ".parquet" else frames.write_csv)(args.per_frame)
    return 0
