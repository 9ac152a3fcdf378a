"""`trackreplay replay LOG --tracker NAME`: deterministic replay to trajectory, digest and .rrd."""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

from trackreplay.replay.cli.commands.values import non_negative_float, non_negative_int, positive_int, seed_int
from trackreplay.schemas.errors import TrackreplayError

from trackreplay.replay.core import registry
from trackreplay.replay.core.engine import ReplayRequest, replay
from trackreplay.replay.core.export import METHODS, export_trajectory, trajectory_format, write_trajectory
from trackreplay.replay.core.outputs import write_json
from trackreplay.replay.log.frames import read_hints
from trackreplay.replay.log.reader import LogReader
from trackreplay.replay.runs.batch_config import apply_sets, parse_assignment, refuse_repeats
from trackreplay.schemas import topics as T


def _rerun_url(text: str) -> str:
    """A --connect URL, checked before the replay (a scheme Rerun does not take: one sentence)."""
    from trackreplay.replay.views.rerun_sink import check_connect_url

    try:
        return check_connect_url(text)
    except TrackreplayError as err:
        raise argparse.ArgumentTypeError(str(err).removeprefix("--connect ")) from None


# The replay finished but skipped damaged or undecodable frames (docs/exit_codes.md).
DAMAGED_INPUT = 7


class DigestMismatch(TrackreplayError):
    exit_code = 4


def add_replay_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--tracker", type=registry.canonical, choices=registry.NAMES, help="tracker to run (default: the one the log's marks are "
                   "labelled for, e.g. flow for `target` marks; else it must be given; `ball` is another name for golf, "
                   "the small-ball tracker)")
    p.add_argument("--config", type=Path, help="tracker config TOML (keys of the tracker's config dataclass)")
    p.add_argument("--set", dest="sets", action="append", default=[], metavar="KEY=VALUE",
                   help="a config value, over --config's (e.g. golf.particles.n=500); repeatable")
    p.add_argument("--seed", type=seed_int, default=0, help="seed of the tracker's random generator (default 0)")
    p.add_argument("--image-topic", help="image topic (default /camera/image, else the stereo left, else the log's "
                   "only image topic)")
    p.add_argument("--stereo-topics", nargs=2, metavar=("LEFT", "RIGHT"), help="stereo pair: left and right image topics")
    p.add_argument("--start", type=non_negative_float, help="start, seconds from the log's first message")
    p.add_argument("--end", type=non_negative_float, help="end (exclusive), seconds from the log's first message")
    p.add_argument("--opencv-threads", type=positive_int, default=1, help="OpenCV threads (results do not depend on it)")
    p.add_argument("--strict", action="store_true",
                   help="stop at the first damaged or undecodable frame (default: skip it, warn, exit 7)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = sub.add_parser("replay", help="replay a tracker over a log deterministically")
    p.add_argument("log", type=Path)
    add_replay_arguments(p)
    p.add_argument("--rrd", type=Path, help="write every intermediate to this Rerun .rrd file")
    p.add_argument("--connect", metavar="URL", nargs="?", const="rerun+http://127.0.0.1:9876/proxy", type=_rerun_url,
                   help="also stream to a running Rerun viewer (default URL rerun+http://127.0.0.1:9876/proxy)")
    p.add_argument("--spawn", action="store_true", help="start a Rerun viewer and stream to it (needs a display)")
    p.add_argument("--serve-web", action="store_true", help="serve Rerun's web viewer over HTTP (no display needed), "
                   "stream the replay to it, print its URL and keep serving until Ctrl-C (or --serve-seconds)")
    p.add_argument("--web-port", type=positive_int, default=9090, help="--serve-web's HTTP port (default 9090)")
    p.add_argument("--grpc-port", type=positive_int, default=9876,
                   help="--serve-web's gRPC port, which the web viewer reads the replay from (default 9876)")
    p.add_argument("--serve-seconds", type=non_negative_float, help="with --serve-web: stop serving this many seconds "
                   "after the replay (default: at Ctrl-C)")
    p.add_argument("--no-truth", dest="truth", action="store_false",
                   help="leave the log's ground truth out of the Rerun stream (default: under truth/ when the log has it)")
    p.add_argument("--rrd-full", action="store_true", help="send every raster to Rerun as it is (groups: the foreground "
                   "masks and disparity raw, 4 bytes a pixel a stereo frame in the viewer, instead of lossless PNG)")
    p.add_argument("--export", type=Path, help="trajectory output: .parquet, .csv or .txt (MOTChallenge)")
    p.add_argument("--interpolate", choices=("none", *METHODS), help="gap filling of the export (default linear; "
                   "not with --smooth, which fills gaps itself)")
    p.add_argument("--max-gap", type=non_negative_int, default=15, help="longest gap (frames) that is interpolated; longer stays lost")
    p.add_argument("--smooth", action="store_true", help="export the offline RTS-smoothed trajectory (trackreplay smooth) "
                   "instead of interpolating; the digest is the causal replay's")
    p.add_argument("--summary", type=Path, help="write a JSON summary (digest, frames, timings; per-frame digests "
                   "beside it as SUMMARY.frames.parquet, for trackreplay diff)")
    p.add_argument("--expect-digest", help="fail unless the replay's digest equals this hex string")
    p.set_defaults(func=run)
    return p


def choose_tracker(log: Path) -> str:
    """The tracker the log's marks are labelled for (the one tracker whose ``mark_labels`` hold them all),
    said on stderr; without one, a sentence asking for ``--tracker``."""
    labels = sorted({mark.label for mark in read_hints(LogReader(log), T.ANNOTATIONS_INIT)})
    claims = [name for name in registry.NAMES
              if labels and (known := registry.get(name).mark_labels) is not None and set(labels) <= set(known)]
    if len(claims) != 1:
        marks = f"marks labelled {', '.join(repr(x) for x in labels)}" if labels else "no marks"
        raise TrackreplayError(f"{log} has {marks}, which choose no one tracker: give --tracker "
                               f"({', '.join(registry.NAMES)})")
    print(f"trackreplay: tracker {claims[0]} (the log's marks are labelled {', '.join(labels)}; "
          "--tracker chooses another)", file=sys.stderr)
    return claims[0]


def request_from_args(args: argparse.Namespace, rrd: Path | None) -> ReplayRequest:
    if args.stereo_topics and args.image_topic:  # (the stereo pair's left is the image topic)
        raise TrackreplayError("--stereo-topics and --image-topic both name the images; give one")
    if args.start is not None and args.end is not None and args.end <= args.start:
        raise TrackreplayError(f"--end {args.end:g} must be after --start {args.start:g}")
    tracker = args.tracker or choose_tracker(args.log)
    sets = [parse_assignment(text) for text in args.sets]
    refuse_repeats([key for key, _ in sets], tracker, "give it once")
    config = apply_sets(tracker, args.config, dict(sets)) if sets else args.config
    return ReplayRequest(
        log=args.log, tracker=tracker, config=config, seed=args.seed, rrd=rrd,
        start_s=args.start, end_s=args.end, image_topic=args.image_topic,
        connect=getattr(args, "connect", None), spawn=getattr(args, "spawn", False), truth=getattr(args, "truth", True),
        rrd_full=getattr(args, "rrd_full", False),
        stereo_topics=tuple(args.stereo_topics) if args.stereo_topics else None,
        progress=not args.quiet and sys.stderr.isatty(), opencv_threads=args.opencv_threads, strict=args.strict,
    )


def run(args: argparse.Namespace) -> int:
    if not getattr(args, "serve_web", False):
        return _run(args, None)
    if args.connect or args.spawn:
        raise TrackreplayError("--serve-web serves its own viewer: give it without --connect and --spawn")
    from trackreplay.replay.views.rerun_sink import WebViewer

    viewer = WebViewer(args.grpc_port, args.web_port)
    try:
        print(f"trackreplay: Rerun web viewer at {viewer.url} (the replay streams to {viewer.connect_url})",
              file=sys.stderr, flush=True)
        code = _run(args, viewer.connect_url)
        until = "Ctrl-C" if args.serve_seconds is None else f"{args.serve_seconds:g} s have passed"
        print(f"trackreplay: serving the replay at {viewer.url} until {until}", file=sys.stderr, flush=True)
        viewer.serve(args.serve_seconds)
        return code
    finally:
        viewer.close()


def _run(args: argparse.Namespace, connect: str | None) -> int:
    if args.smooth and args.interpolate is not None:
        raise TrackreplayError(f"--interpolate {args.interpolate} and --smooth exclude each other: the smoother fills the "
                               "gaps of the export itself (up to --max-gap frames)")
    if args.smooth and not args.export:  # (it would smooth nothing anyone sees)
        raise TrackreplayError("--smooth smooths the --export; give --export PATH")
    if args.export:
        trajectory_format(args.export)  # before the replay, not after it
    request = request_from_args(args, args.rrd)
    if connect is not None:  # --serve-web's own gRPC server
        request = dataclasses.replace(request, connect=connect)
    if args.summary:  # the summary's sidecar holds per-frame digests (for `trackreplay diff`)
        request = dataclasses.replace(request, frame_digests=True)
    if args.export and args.smooth:  # the smoother observes the trackers' raw measurements
        request = dataclasses.replace(request, observations=True)
    result = replay(request)
    if args.export and args.smooth:
        from trackreplay.replay.cli.commands.smooth import smooth_and_report

        write_trajectory(smooth_and_report(result.trajectory, args.log, args.max_gap, result.observations,
                                           {result.tracker: result.config}), args.export)
    elif args.export:  # a spilled trajectory is filled and written a piece at a time (docs/memory.md)
        export_trajectory(result.table, args.export, args.interpolate or "linear", args.max_gap)
    if args.export and result.extra_rows is not None:  # groups: the second table beside it, TRAJ.groups.parquet
        from trackreplay.replay.core.group_table import group_table, write_group_table

        write_group_table(group_table(result.extra_rows), args.export)
    summary = result.summary(args.log)
    if args.summary:  # the per-frame digests go beside it, for `trackreplay diff`
        from trackreplay.replay.analysis.diff import sidecar_path, write_sidecar

        summary["frame_digests"] = write_sidecar(result.frame_digests, sidecar_path(args.summary)).name
        args.summary.parent.mkdir(parents=True, exist_ok=True)
        write_json(args.summary, summary)
    print(f"{result.tracker}: {result.frames} frames, digest {result.digest}")
    if result.report.outside_encoder_coverage:
        print(f"warning: {len(result.report.outside_encoder_coverage)} frames outside encoder coverage", file=sys.stderr)
    if result.report.zoom_outside_lens:
        print(f"warning: {args.log}: {len(result.report.zoom_outside_lens)} frame(s) have a zoom reading outside the lens "
              f"table's range (first: frame {result.report.zoom_outside_lens[0]}); the nearest entry's intrinsics were used",
              file=sys.stderr)
    if result.report.out_of_order:
        print(f"warning: {args.log}: the images' write order and log_time order disagree at {len(result.report.out_of_order)} "
              f"place(s) (first: before frame {result.report.out_of_order[0]}); they are replayed in log_time order", file=sys.stderr)
    for sentence in result.report.channel_conflicts.values():
        print(f"warning: {args.log}: {sentence}", file=sys.stderr)
    if args.expect_digest and args.expect_digest.lower() != result.digest:
        raise DigestMismatch(f"digest mismatch for {args.log}: expected {args.expect_digest.lower()}, got {result.digest}")
    if result.report.lost:
        print(f"warning: {lost_frames_sentence(args.log, result.report.lost)}", file=sys.stderr)
        return DAMAGED_INPUT
    return 0


def lost_frames_sentence(log: Path, lost: list) -> str:
    """One sentence: how many frames were skipped, which, and the first reason."""
    indexes = [x.index for x in lost]
    runs: list[str] = []
    start = prev = indexes[0]
    for i in indexes[1:] + [None]:
        if i is not None and i == prev + 1:
            prev = i
            continue
        runs.append(str(start) if start == prev else f"{start}-{prev}")
        if i is not None:
            start = prev = i
    shown = ", ".join(runs[:6]) + (f" and {len(runs) - 6} more runs" if len(runs) > 6 else "")
    return (f"{log}: {len(lost)} frame(s) could not be read and were skipped (the tracker predicted across them): "
            f"frames {shown}; first cause: {lost[0].reason}")
