"""The deterministic replay loop: log -> frames -> tracker -> trajectory, digest, Rerun.

:func:`iter_steps` is the loop itself, one :class:`ReplayStep` (frame, track states,
intermediates) per frame; :func:`replay` consumes it into the trajectory, the digest and the
optional .rrd, so tests, notebooks, docs scripts and benchmarks step the path the CLI takes.

Notices belong in the digest. A tracker's notice (its spec's ``notice``, read from its
intermediates: e.g. the golf tracker's "… tracking in image coordinates only") is a field of its
intermediates like any other, so it is hashed with them in every frame: it is derived from the
log, config and seed alone, and it records a change of mode that the numbers alone may not show. Rewording a notice therefore
changes the digest (as any change of a tracker's outputs does). Separately, :func:`replay`
prints each distinct notice once to stderr and returns them, in order, in ``ReplayResult.notices``.
"""

from __future__ import annotations

import math
import sys
import time
import zlib
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import polars as pl
from tqdm import tqdm

from trackreplay import __version__
from trackreplay.replay.core import registry
from trackreplay.replay.core.config import ConfigSource, config_to_dict, load_config
from trackreplay.replay.core.config_toml import config_toml
from trackreplay.replay.core.digest import SPILL_FRAMES, FrameDigests, ReplayDigest
from trackreplay.replay.core.observations import observation_rows, observations_table
from trackreplay.replay.log.frames import (BundleReport, FrameTopics, iter_frames, marked_images, marks_in_window, read_hints,
                                       read_ground_plane, read_stereo_rig)
from trackreplay.replay.log.marks import check_can_track, check_labels, check_one_start_per_frame
from trackreplay.replay.log.groundtruth import read_groundtruth
from trackreplay.replay.log.prefetch import prefetch
from trackreplay.replay.log.reader import LogReader
from trackreplay.replay.core.trajectory import SPILL_ROWS, SpilledTrajectory, TrajectoryRows, state_row
from trackreplay.trackers.base import Tracker, TrackState
from trackreplay.trackers.frame import Frame
from trackreplay.schemas import topics as T
from trackreplay.schemas.errors import TrackreplayError


# OpenCV's cv2.setRNGSeed takes a C int: every seed a replay accepts must fit one.
SEED_LIMIT = 2**31


def check_seed(seed: object, name: str = "seed") -> int:
    """``seed`` as an int if it is one in 0 .. 2**31 - 1; else one sentence naming ``name``."""
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or not 0 <= seed < SEED_LIMIT:
        raise TrackreplayError(f"{name} {seed!r} is not a valid seed: give an integer from 0 to {SEED_LIMIT - 1} "
                               "(OpenCV's random generator takes a 32-bit int)")
    return int(seed)


def tracker_rng(seed: int, tracker: str) -> np.random.Generator:
    """Generator from ``--seed`` and the tracker's name (stable across processes and machines)."""
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(zlib.crc32(tracker.encode()),)))


@dataclass(frozen=True)
class ReplayRequest:
    log: Path
    tracker: str
    config: ConfigSource = None  # the tracker's config: None (defaults), an instance, a dict or a TOML path
    seed: int = 0
    rrd: Path | None = None
    connect: str | None = None  # stream to a running Rerun viewer at this gRPC URL (as well as, or instead of, rrd)
    spawn: bool = False  # start a Rerun viewer and stream to it
    truth: bool = True  # the log's ground truth (when it has one) goes to the .rrd/viewer under truth/ (views.truth)
    rrd_full: bool = False  # views send every raster raw (groups: masks, disparity) instead of compressed
    start_s: float | None = None  # seconds from the first message of the log
    end_s: float | None = None
    image_topic: str | None = None
    stereo_topics: tuple[str, str] | None = None  # (left, right) image topics of a stereo pair
    progress: bool = False
    opencv_threads: int = 1
    prefetch: int = 4  # frames decoded ahead in a reader thread; 0 = read in the loop
    # Record per-frame, per-field hashes for `trackreplay diff` (ReplayResult.frame_digests; the
    # digest itself is the same either way). Costs ~0.1-0.2 ms a frame, so only when asked:
    # `replay --summary` and every batch task ask.
    frame_digests: bool = False
    strict: bool = False  # a damaged or undecodable frame stops the replay (else it is skipped and reported)
    # Keep the trackers' raw measurements (replay/core/observations.py observation_rows) for the offline
    # smoother: ReplayResult.observations. Not part of the digest.
    observations: bool = False
    # Trajectory rows kept in memory; beyond this many the table goes to a temporary Parquet file in row
    # groups of this size and ReplayResult.trajectory reads it back (docs/memory.md).
    spill_rows: int = SPILL_ROWS
    spill_frames: int = SPILL_FRAMES  # the same for per-frame digests (frame_digests), in frames

    def __post_init__(self) -> None:
        """The checks the CLI's argument parser makes, for callers of the Python API too; an alias of a
        tracker (``ball``) becomes its name."""
        object.__setattr__(self, "tracker", registry.canonical(self.tracker))
        check_seed(self.seed)
        for name in ("spill_rows", "spill_frames"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise TrackreplayError(f"{name} must be a whole number >= 1, not {value!r}")
        for name in ("start_s", "end_s"):
            value = getattr(self, name)
            if value is not None and (isinstance(value, bool) or not isinstance(value, int | float)
                                      or not math.isfinite(value) or value < 0):
                raise TrackreplayError(f"{name} must be a finite number of seconds >= 0, not {value!r}")
        if self.start_s is not None and self.end_s is not None and self.end_s <= self.start_s:
            raise TrackreplayError(f"end_s {self.end_s:g} must be after start_s {self.start_s:g}")


@dataclass(frozen=True)
class ReplayResult:
    tracker: str
    seed: int
    # The trajectory table: in memory, or (past ReplayRequest.spill_rows rows) a temporary Parquet file
    # that ``trajectory`` reads back on each access and ``scan_trajectory`` scans lazily.
    table: pl.DataFrame | SpilledTrajectory
    digest: str
    frames: int
    seconds: float
    report: BundleReport = field(default_factory=BundleReport)
    rrd: Path | None = None
    notices: tuple[str, ...] = ()  # each distinct tracker notice, in the order first seen
    config: Any = None  # the tracker's config as replayed (its dataclass)
    frame_digests: FrameDigests | None = None  # per-frame, per-field hashes when requested (``trackreplay diff``)
    # A tracker whose spec declares ``extra_rows`` (groups: members, 3-D velocity, extent) gives a
    # second table; its rows here, each with tracker, frame and t_ns (None for other trackers).
    extra_rows: tuple[dict, ...] | None = None
    observations: pl.DataFrame | None = None  # raw measurements when ReplayRequest.observations (smooth.OBS_SCHEMA)
    # The frame X Y Z are in when the tracker says ("world": Z up, from the log's rig pose; "camera")
    position_frame: str | None = None
    step_seconds: float = 0.0  # of ``seconds``, the time inside the tracker's step (no reading, decoding, digest or sink)

    @property
    def trajectory(self) -> pl.DataFrame:
        """The trajectory table in canonical order (read from its spill file when the replay spilled it)."""
        return self.table.frame() if isinstance(self.table, SpilledTrajectory) else self.table

    def scan_trajectory(self) -> pl.LazyFrame:
        """The trajectory as a LazyFrame: bounded memory for a query that needs only part of it."""
        return self.table.scan() if isinstance(self.table, SpilledTrajectory) else self.table.lazy()

    @property
    def rows(self) -> int:
        return self.table.height

    def summary(self, log: Path) -> dict[str, Any]:
        return {
            "log": str(log),
            "tracker": self.tracker,
            "seed": self.seed,
            "version": __version__,
            "config": None if self.config is None else config_to_dict(self.config),
            "config_toml": None if self.config is None else config_toml(self.config, self.tracker),
            "digest": self.digest,
            "frames": self.frames,
            "rows": self.rows,
            "timings": {
                "seconds": round(self.seconds, 4),
                "frames_per_second": round(self.frames / self.seconds, 2) if self.seconds > 0 else None,
            },
            "unpaired_images": len(self.report.unpaired),
            "frames_outside_encoder_coverage": len(self.report.outside_encoder_coverage),
            "frames_zoom_outside_lens": len(self.report.zoom_outside_lens),
            "frames_out_of_order": len(self.report.out_of_order),
            "frames_lost": [{"topic": x.topic, "index": x.index, "t_ns": x.t_ns, "reason": x.reason}
                            for x in self.report.lost],
            "rrd": str(self.rrd) if self.rrd else None,
            "notices": list(self.notices),
            "position_frame": self.position_frame,
        }


@dataclass(frozen=True)
class ReplayStep:
    """One frame of a replay: the frame as the tracker saw it, its track states, its intermediates."""

    frame: Frame
    states: tuple[TrackState, ...]
    intermediates: Any


class ReplaySteps(Iterator[ReplayStep]):
    """The replay loop as an iterator; opening the log, building and preparing the tracker happen
    on construction, so a bad log, topic or config fails before the first step.
    """

    def __init__(self, req: ReplayRequest) -> None:
        self.request = req
        self.spec = registry.get(req.tracker)
        self.config = load_config(self.spec.config_cls, req.config, table=req.tracker)
        cv2.setNumThreads(req.opencv_threads)
        cv2.setRNGSeed(req.seed)
        reader = LogReader(req.log)
        topics = FrameTopics.detect(reader, req.image_topic, req.stereo_topics)
        reader.require(topics.image)
        t0, t1 = reader.time_range()
        start_ns = None if req.start_s is None else t0 + int(round(req.start_s * 1e9))
        if start_ns is not None and start_ns > t1:  # nothing to replay is a mistake, not an empty success
            raise TrackreplayError(f"{req.log}: --start {req.start_s:g} s is after the log's end "
                                   f"({(t1 - t0) / 1e9:.3f} s from its first message)")
        end_ns = None if req.end_s is None else t0 + int(round(req.end_s * 1e9))
        self.tracker: Tracker = self.spec.tracker_cls(self.config, tracker_rng(req.seed, req.tracker))
        marks = read_hints(reader, topics.hints, topics.image)
        check_labels({r.label for r in marks}, self.spec, f"{req.log}: topic {topics.hints}")
        inside = marks_in_window(marks, start_ns, end_ns)
        check_one_start_per_frame(inside, self.spec, f"{req.log}: topic {topics.hints}")
        check_can_track(self.spec, inside, len(inside) < len(marks),
                        self.spec.needs not in ("stereo", "depth") or read_stereo_rig(reader, topics) is not None, req.log,
                        has_ground=self.spec.needs == "depth" and read_ground_plane(reader, topics.ground_plane) is not None)
        outside = len(marks) - len(inside)
        self.notice = (f"{outside} of the log's {len(marks)} mark(s) are on frames outside --start/--end and are not "
                       "used (a track starts only from a mark on a frame it replays)") if outside else ""
        # a no-op for trackers that need no look ahead
        self.tracker.prepare(marked_images(reader, topics, start_ns=start_ns, end_ns=end_ns))
        self.report = BundleReport()
        self.step_seconds = 0.0  # wall time inside the tracker's step, summed over frames
        self.total = reader.topics()[topics.image].count  # images in the log (the progress bar's end)
        self._frames = prefetch(iter_frames(reader, topics, start_ns=start_ns, end_ns=end_ns, report=self.report,
                                            strict=req.strict), req.prefetch)

    def __next__(self) -> ReplayStep:
        frame = next(self._frames)
        try:
            # the clock only measures the tracker's own work for reporting (`evaluate`'s speed beside CSRT's update
            # calls); nothing the replay writes depends on it
            started = time.perf_counter()
            states = tuple(self.tracker.step(frame))
            self.step_seconds += time.perf_counter() - started
        except TrackreplayError as err:  # a tracker refusing its input (a mark round no ball) names the log too
            raise type(err)(f"{self.request.log}: {err}") from None
        return ReplayStep(frame, states, self.tracker.intermediates)

    def close(self) -> None:
        """Stop reading ahead (for a consumer that leaves the loop early)."""
        self._frames.close()


def iter_steps(req: ReplayRequest) -> ReplaySteps:
    """The replay loop, one :class:`ReplayStep` per frame in log-time order (what :func:`replay` runs)."""
    return ReplaySteps(req)


def _open_sink(req: ReplayRequest, view: Any):
    """The Rerun sink when the request writes an .rrd or streams to a viewer, else None."""
    if req.rrd is None and req.connect is None and not req.spawn:
        return None
    from trackreplay.replay.views.rerun_sink import RerunSink

    sink = RerunSink(req.rrd, f"{Path(req.log).stem}-{req.tracker}-{req.seed}", view.blueprint(req.tracker),
                     connect=req.connect, spawn=req.spawn, truth=_truth(req))
    sink.logger.rrd_full = req.rrd_full  # read by the views that compress by default (views/groups.py FULL)
    return sink


def _truth(req: ReplayRequest) -> pl.DataFrame | None:
    """The log's ground truth for the Rerun stream, when asked for and the log has one (a truth that
    cannot be read is left out, said once: the replay does not need it)."""
    reader = LogReader(req.log)
    if not req.truth or T.GROUNDTRUTH not in reader.topics():
        return None
    try:
        return read_groundtruth(reader)
    except TrackreplayError as err:
        print(f"warning: the log's ground truth is left out of the Rerun stream: {err}", file=sys.stderr)
        return None


def _note(notices: list[str], notice: str, who: str) -> None:
    """Keep and print a notice the first time it is given."""
    if notice and notice not in notices:
        notices.append(notice)
        print(f"trackreplay: {who}{notice}", file=sys.stderr)


def replay(req: ReplayRequest) -> ReplayResult:
    """Step the tracker over every frame of the log: trajectory, digest, notices and the optional .rrd."""
    steps = iter_steps(req)
    spec = steps.spec
    sink = _open_sink(req, spec.view)
    digest = ReplayDigest(per_frame=req.frame_digests, spill_frames=req.spill_frames)
    rows = TrajectoryRows(req.spill_rows)
    extra: list[dict] | None = [] if spec.extra_rows is not None else None
    observed: list[dict] | None = [] if req.observations else None
    notices: list[str] = []
    _note(notices, steps.notice, "")  # the replay's own, before any tracker's
    # The clock is read before and after the loop only; tqdm reads it for display, never for results.
    started = time.perf_counter()
    try:
        for step in tqdm(steps, total=steps.total, disable=not req.progress, unit="frame", desc=req.tracker, leave=False):
            frame, inter = step.frame, step.intermediates
            if spec.notice is not None and inter is not None:
                _note(notices, spec.notice(inter), f"{req.tracker}: ")
            digest.add_frame(frame.index, (inter, step.states))
            rows.extend(state_row(req.tracker, frame.index, frame.t_ns, s) for s in step.states)
            if extra is not None:
                extra.extend({"tracker": req.tracker, "frame": frame.index, "t_ns": frame.t_ns, **r}
                             for r in spec.extra_rows(inter))
            if observed is not None:
                observed.extend(observation_rows(spec, frame.index, inter, step.states, frame.stereo, steps.config))
            if sink is not None:
                sink.begin_frame(frame)
                spec.view.log(sink.logger, req.tracker, frame, inter, list(step.states))
    finally:
        steps.close()
        if sink is not None:
            sink.close()
    seconds = time.perf_counter() - started
    digest.add_lost([(x.topic, x.index, x.t_ns) for x in steps.report.lost])
    table = rows.finish()
    return ReplayResult(req.tracker, req.seed, table, digest.finish(table), steps.report.frames, seconds, steps.report,
                        req.rrd, tuple(notices), steps.config, digest.frames, None if extra is None else tuple(extra),
                        observations=None if observed is None else observations_table(observed),
                        position_frame=None if spec.position_frame is None else spec.position_frame(steps.tracker),
                        step_seconds=steps.step_seconds)
