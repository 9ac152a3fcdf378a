"""The deterministic replay loop: log -> frames -> tracker -> trajectory, digest, Rerun."""

from __future__ import annotations

import sys
import time
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import polars as pl
from tqdm import tqdm

from trackreplay.replay import registry
from trackreplay.replay.digest import ReplayDigest
from trackreplay.replay.frames import BundleReport, FrameTopics, iter_frames, marked_images
from trackreplay.replay.prefetch import prefetch
from trackreplay.replay.reader import LogReader
from trackreplay.replay.trajectory import state_row, trajectory_table


def tracker_rng(seed: int, tracker: str) -> np.random.Generator:
    """Generator from ``--seed`` and the tracker's name (stable across processes and machines)."""
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(zlib.crc32(tracker.encode()),)))


@dataclass(frozen=True)
class ReplayRequest:
    log: Path
    tracker: str
    config: Any = None  # the tracker's frozen config; None = defaults
    seed: int = 0
    rrd: Path | None = None
    start_s: float | None = None  # seconds from the first message of the log
    end_s: float | None = None
    image_topic: str | None = None
    progress: bool = False
    opencv_threads: int = 1
    prefetch: int = 4  # frames decoded ahead in a reader thread; 0 = read in the loop


@dataclass(frozen=True)
class ReplayResult:
    tracker: str
    seed: int
    trajectory: pl.DataFrame
    digest: str
    frames: int
    seconds: float
    report: BundleReport = field(default_factory=BundleReport)
    rrd: Path | None = None

    def summary(self, log: Path) -> dict[str, Any]:
        return {
            "log": str(log),
            "tracker": self.tracker,
            "seed": self.seed,
            "digest": self.digest,
            "frames": self.frames,
            "rows": self.trajectory.height,
            "timings": {
                "seconds": round(self.seconds, 4),
                "frames_per_second": round(self.frames / self.seconds, 2) if self.seconds > 0 else None,
            },
            "unpaired_images": len(self.report.unpaired),
            "frames_outside_encoder_coverage": len(self.report.outside_encoder_coverage),
            "rrd": str(self.rrd) if self.rrd else None,
        }


def replay(req: ReplayRequest) -> ReplayResult:
    """Step the tracker over every frame of the log in log-time order."""
    entry = registry.get(req.tracker)
    config = req.config if req.config is not None else entry.config_cls()
    cv2.setNumThreads(req.opencv_threads)
    cv2.setRNGSeed(req.seed)
    reader = LogReader(req.log)
    topics = FrameTopics.detect(reader, req.image_topic)
    reader.require(topics.image)
    t0, _ = reader.time_range()
    start_ns = None if req.start_s is None else t0 + int(round(req.start_s * 1e9))
    end_ns = None if req.end_s is None else t0 + int(round(req.end_s * 1e9))
    tracker = entry.tracker_cls(config, tracker_rng(req.seed, req.tracker))
    if hasattr(tracker, "prepare"):  # trackers that learn from every marked frame up front
        tracker.prepare(marked_images(reader, topics))
    sink = None
    if req.rrd is not None:
        from trackreplay.replay.rerun_sink import RerunSink

        sink = RerunSink(req.rrd, f"{Path(req.log).stem}-{req.tracker}-{req.seed}", entry.view.blueprint(req.tracker))
    report = BundleReport()
    digest = ReplayDigest()
    rows: list[tuple] = []
    notices: list[str] = []
    total = reader.topics()[topics.image].count
    frames = prefetch(iter_frames(reader, topics, start_ns=start_ns, end_ns=end_ns, report=report), req.prefetch)
    # The clock is read before and after the loop only; tqdm reads it for display, never for results.
    started = time.perf_counter()
    try:
        for frame in tqdm(frames, total=total, disable=not req.progress, unit="frame", desc=req.tracker, leave=False):
            states = tracker.step(frame)
            notice = getattr(tracker.intermediates, "notice", "")
            if notice and notice not in notices:
                notices.append(notice)
                print(f"trackreplay: {req.tracker}: {notice}", file=sys.stderr)
            digest.add_frame(frame.index, (tracker.intermediates, tuple(states)))
            rows.extend(state_row(req.tracker, frame.index, frame.t_ns, s) for s in states)
            if sink is not None:
                sink.begin_frame(frame)
                entry.view.log(sink.logger, req.tracker, frame, tracker.intermediates, states)
    finally:
        if sink is not None:
            sink.close()
    seconds = time.perf_counter() - started
    table = trajectory_table(rows)
    return ReplayResult(req.tracker, req.seed, table, digest.finish(table), report.frames, seconds, report, req.rrd)
