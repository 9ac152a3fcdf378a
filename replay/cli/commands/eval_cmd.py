"""`trackreplay eval TRAJ TRUTH`: metrics against ground truth.

TRAJ is a trajectory table (.parquet, .csv) or a MOTChallenge result (.txt); TRUTH is a log with
ground truth, or a MOTChallenge sequence (a folder with gt/gt.txt and seqinfo.ini, or a gt.txt).
One track is scored against one truth object when the trajectory has one track or ``--track``
names it; a trajectory of several tracks is scored whole with the multi-object metrics. The choice
is printed first."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import polars as pl

from trackreplay.replay.cli.commands.values import finite_json, positive_float
from trackreplay.replay.analysis.eval import (check_frames, checked_scan, evaluate, evaluate_chunked, evaluate_parts,
                                              format_summary, object_followed, object_followed_parts, truth_index,
                                              truth_parts)
from trackreplay.replay.core.export import read_trajectory
from trackreplay.replay.log.frames import image_times, read_rig_pose
from trackreplay.replay.log.groundtruth import groundtruth_with_frames
from trackreplay.replay.analysis.mot import MAX_DISTANCE_M
from trackreplay.replay.analysis.mot_files import drop_distractor_matches, read_mot_result, read_mot_sequence
from trackreplay.replay.log.reader import LogReader
from trackreplay.schemas.errors import TrackreplayError
from trackreplay.schemas.topics import GROUNDTRUTH


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = sub.add_parser("eval", help="measured share, centre error, IoU and velocity error against ground truth; "
                                    "CLEAR MOT, IDF1, HOTA over several tracks",
                       description=__doc__.split("\n\n", 1)[1])
    p.add_argument("trajectory", type=Path, help=".parquet or .csv trajectory, or a MOTChallenge result .txt "
                   "(frame,id,bb_left,bb_top,bb_width,bb_height,conf,...; 1-based frames and pixels)")
    p.add_argument("log", type=Path, metavar="TRUTH", help="the log holding the ground truth, or a MOTChallenge "
                   "sequence folder (gt/gt.txt, seqinfo.ini) or its gt.txt")
    p.add_argument("--track", "--track-id", dest="track_id", type=int, metavar="ID",
                   help="score this track alone (needed to score one of several tracks; without it they are all scored "
                        "with the multi-object metrics)")
    p.add_argument("--gt-id", type=int, help="ground-truth object to score one track against (default: the one the track "
                   "lies on most often; it is printed)")
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
    mot_result = args.trajectory.suffix.lower() == ".txt"
    # a long Parquet trajectory is scored from a lazy scan, a chunk of frames at a time (one track, or all: --mot)
    # (docs/memory.md); the keys stand in for the table in the checks
    lazy = (checked_scan(args.trajectory) if args.trajectory.suffix.lower() == ".parquet" and args.trajectory.is_file()
            and not (args.per_frame or _is_sequence(args.log)) else None)
    traj = lazy[1] if lazy else read_mot_result(args.trajectory) if mot_result else read_trajectory(args.trajectory)
    index = None
    if _is_sequence(args.log):
        traj, gt, frames = _sequence_truth(args, traj)
    else:
        reader = LogReader(args.log)
        topic = args.gt_topic or GROUNDTRUTH
        # one track scored alone against one truth object: the truth is read a chunk at a time too (and,
        # among several objects, the one the track lies on most often is counted a chunk at a time)
        index, times = truth_index(reader, topic, args.image_topic) if lazy else (None, None)
        if index is not None and index.in_order:
            gt, annotated = None, index.annotated
        else:
            index = None
            gt, annotated = groundtruth_with_frames(reader, topic)
            times = image_times(reader, args.image_topic)
        if mot_result:  # a result file carries no times: its frames are the log's images, at their times
            beyond = traj.filter(~pl.col("frame").is_in(list(times)))
            if beyond.height:
                raise TrackreplayError(f"{args.trajectory}: frame {beyond['frame'].min() + 1} (1-based) is not one of the "
                                       f"{len(times)} frames of {args.log} ({beyond.height} row(s)): a result of another log")
            traj = traj.with_columns(pl.col("frame").replace_strict(times, return_dtype=pl.Int64).alias("t_ns"))
        check_frames(traj, str(args.trajectory), times, annotated, str(args.log))
        frames = annotated["frame"]
    objects = sorted(index.seen) if index is not None else None
    every_object = (lambda: truth_parts(reader, topic, None)) if index is not None else None
    if args.mot or _score_all(args, traj, gt, objects, every_object):
        if gt is None and read_rig_pose(reader) is None:  # a chunk of frames at a time (docs/memory.md)
            from trackreplay.replay.analysis.mot import ChunkedTables, truth_chunks

            return _run_mot(args, _Chunked(ChunkedTables(lazy[0], truth_chunks(reader, topic))))
        if gt is None:
            gt = groundtruth_with_frames(reader, topic)[0]
        return _run_mot(args, _Whole(read_trajectory(args.trajectory) if lazy else traj, gt, frames))
    if index is not None:
        parts = truth_parts(reader, topic, index.gt_id(args.gt_id))
        summary, per_frame = evaluate_parts(lazy[0], parts, track_id=args.track_id), None
    elif lazy:
        summary, per_frame = evaluate_chunked(lazy[0], gt, track_id=args.track_id, gt_id=args.gt_id), None
    else:
        summary, per_frame = evaluate(traj, gt, track_id=args.track_id, gt_id=args.gt_id)
    print(format_summary(summary))
    if args.json:
        _write_json(args.json, summary.as_dict())
    if args.per_frame and per_frame is not None:
        _write_table(args.per_frame, per_frame)
    return 0


def _score_all(args: argparse.Namespace, traj: pl.DataFrame, gt: pl.DataFrame | None, objects: list[int] | None = None,
               every_object=None) -> bool:
    """Whether to score every track (several tracks and no ``--track``); says what is scored either way.
    ``objects``: the truth objects placed and visible, when ``gt`` is not read; ``every_object()`` then
    gives their rows a chunk at a time (:func:`truth_parts` of no one object)."""
    tracks = sorted(traj.filter(pl.col("x").is_not_null())["track_id"].unique().to_list())
    if objects is None:
        objects = sorted(gt.filter(pl.col("x").is_not_null() & pl.col("visible").fill_null(True))["id"].unique().to_list())
    if args.track_id is None and len(tracks) > 1:
        if args.gt_id is not None:
            raise TrackreplayError(f"{args.trajectory} holds {len(tracks)} tracks: --gt-id scores one of them, so name it "
                                   f"with --track ID (or leave both out to score all)")
        print(f"scoring all {len(tracks)} tracks against all {len(objects)} truth object(s) with the multi-object "
              f"metrics (--track ID scores one track alone)")
        return True
    if args.track_id is not None:
        if args.track_id not in traj["track_id"].unique().to_list():
            raise TrackreplayError(f"{args.trajectory} has no track {args.track_id} (its tracks: "
                                   f"{', '.join(map(str, tracks[:20]))}{' ...' if len(tracks) > 20 else ''})")
        which = f"track {args.track_id} (--track)"
    else:
        which = f"track {tracks[0]} (the trajectory's only one)" if tracks else "the trajectory"
    if args.gt_id is not None:
        against = f"truth object {args.gt_id} (--gt-id)"
    elif len(objects) == 1:
        against = f"truth object {objects[0]} (the truth's only one)"
    else:
        tid = args.track_id if args.track_id is not None else tracks[0] if tracks else None
        followed = (None if tid is None else object_followed(traj, gt, tid) if gt is not None
                    else object_followed_parts(traj, every_object(), tid))
        if followed is not None:
            args.gt_id = followed
            against = f"truth object {followed}, the one of {len(objects)} it lies on most often (--gt-id ID chooses)"
        else:
            against = f"the truth object seen on most frames, of {len(objects)}, as it lies on none (--gt-id ID chooses)"
    print(f"scoring {which} against {against}")
    return False


def _is_sequence(path: Path) -> bool:
    """A MOTChallenge sequence (a folder with gt/gt.txt, or a .txt) rather than a log or a bag folder."""
    return (path.is_dir() and (path / "gt" / "gt.txt").is_file()) or path.suffix.lower() == ".txt"


def _sequence_truth(args: argparse.Namespace, traj: pl.DataFrame) -> tuple[pl.DataFrame, pl.DataFrame, pl.Series]:
    """The trajectory (checked against the sequence's length, cleared of boxes on distractors, which
    it says), the sequence's scored truth and its annotated frames."""
    if args.gt_topic or args.image_topic:
        raise TrackreplayError(f"--gt-topic and --image-topic choose topics of a log; {args.log} is a MOTChallenge sequence")
    seq = read_mot_sequence(args.log)
    if seq.length is not None:
        beyond = traj.filter(pl.col("frame") >= seq.length)
        if beyond.height:
            raise TrackreplayError(f"{args.trajectory}: frame {beyond['frame'].min() + 1} (1-based) is beyond the "
                                   f"{seq.length} frames of {seq.name} ({beyond.height} row(s)): a result of another sequence")
    traj, removed = drop_distractor_matches(traj, seq)
    if removed:
        print(f"{removed} tracked box(es) on distractors (static people, reflections, ...) left out, as TrackEval does")
    return traj, seq.gt, seq.frames


class _Whole:
    """The multi-object metrics of the whole trajectory and truth tables."""

    def __init__(self, traj: pl.DataFrame, gt: pl.DataFrame, frames: pl.Series) -> None:
        self.traj, self.gt, self.frames = traj, gt, frames

    def mot(self, **kw):
        from trackreplay.replay.analysis.mot import mot_metrics

        return mot_metrics(self.traj, self.gt, frames=self.frames, **kw)

    def hota(self, **kw):
        from trackreplay.replay.analysis.mot import hota_metrics

        return hota_metrics(self.traj, self.gt, frames=self.frames, **kw)

    def three_d_missing(self) -> str | None:
        from trackreplay.replay.analysis.mot import three_d_missing

        return three_d_missing(self.traj, self.gt)


class _Chunked:
    """The same metrics a chunk of frames at a time (:class:`~trackreplay.replay.analysis.mot.ChunkedTables`)."""

    def __init__(self, tables) -> None:
        self.tables = tables

    def mot(self, **kw):
        from trackreplay.replay.analysis.mot import mot_metrics_chunked

        return mot_metrics_chunked(self.tables, **kw)

    def hota(self, **kw):
        from trackreplay.replay.analysis.mot import hota_metrics_chunked

        return hota_metrics_chunked(self.tables, **kw)

    def three_d_missing(self) -> str | None:
        return self.tables.three_d_missing()


def _run_mot(args: argparse.Namespace, metrics: _Whole | _Chunked) -> int:
    """CLEAR MOT and HOTA over every annotated frame, on image boxes and, where both the trajectory and
    the truth have them, on 3-D positions."""
    from trackreplay.replay.analysis.mot import format_hota, format_mot

    image = metrics.mot(space="image")
    image_hota = metrics.hota(space="image")
    why_not = metrics.three_d_missing()
    space = space_hota = None
    if why_not is None:
        space = metrics.mot(space="3d", max_distance_m=args.max_distance_m)
        space_hota = metrics.hota(space="3d", max_distance_m=args.max_distance_m)
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


def _write_table(path: Path, table: pl.DataFrame) -> None:
    """The per-frame errors as Parquet or CSV, under NAME.partial until complete (its folder created)."""
    import io

    from trackreplay.replay.core.outputs import write_bytes

    buf = io.BytesIO()
    (table.write_parquet if path.suffix.lower() == ".parquet" else table.write_csv)(buf)
    write_bytes(_folder(path), buf.getvalue())


def _folder(path: Path) -> Path:
    """``path``, its folder created as the other result outputs' are (docs/exit_codes.md, status 5)."""
    from trackreplay.schemas.errors import OutputError

    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise OutputError(f"cannot write {path} ({err.strerror or err})") from None
    return path


def _write_json(path: Path, data: dict) -> None:
    """Strict JSON: a metric that is undefined (no truth, no match) is null, not NaN."""
    from trackreplay.replay.core.outputs import write_bytes  # NAME.partial, renamed when complete

    write_bytes(_folder(path), (json.dumps(finite_json(data), indent=2, allow_nan=False) + "\n").encode())
