"""Timing a replay against plain read + decode of the same log, and against itself with Rerun on.

Each figure is a median of ``repeats`` runs after one warm-up run, all in one process, so the
ratios compare like with like on the machine at hand.
"""

from __future__ import annotations

import statistics
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from trackreplay.replay.log.decode import decode_image
from trackreplay.replay.core.engine import ReplayRequest, replay
from trackreplay.replay.log.frames import FrameTopics
from trackreplay.replay.log.reader import LogReader


def median_seconds(fn: Callable[[], object], repeats: int) -> float:
    fn()  # warm-up: imports, caches, first-call costs
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def read_decode(log: Path, topic: str | None = None) -> int:
    """Read every image a replay reads and decode it (both images of a stereo pair); returns the
    number of frames (images on the frame topic)."""
    reader = LogReader(log)
    frames = FrameTopics.detect(reader, topic)
    topics = [frames.image] + ([frames.right] if frames.right else [])
    n = 0
    for item in reader.messages(topics):
        decode_image(item.decode(), item.schema, f"{log}: {item.topic} message {item.index}")
        n += item.topic == frames.image
    return n


@dataclass(frozen=True)
class ReplayTiming:
    frames: int
    read_decode_s: float
    replay_s: float
    replay_rrd_s: float
    rrd_bytes: int

    @property
    def throughput_ratio(self) -> float:
        """Replay frames/s over read+decode frames/s (1.0 = the tracker costs nothing extra)."""
        return self.read_decode_s / self.replay_s

    @property
    def rerun_ratio(self) -> float:
        """Replay time with full Rerun logging over replay time without."""
        return self.replay_rrd_s / self.replay_s


def time_replay(log: Path, tracker: str, repeats: int = 3, config=None) -> ReplayTiming:
    frames = read_decode(log)
    t_decode = median_seconds(lambda: read_decode(log), repeats)
    t_replay = median_seconds(lambda: replay(ReplayRequest(log=log, tracker=tracker, config=config)), repeats)
    with tempfile.TemporaryDirectory() as tmp:
        rrd = Path(tmp) / "bench.rrd"
        t_rrd = median_seconds(lambda: replay(ReplayRequest(log=log, tracker=tracker, config=config, rrd=rrd)), repeats)
        size = rrd.stat().st_size
    return ReplayTiming(frames, t_decode, t_replay, t_rrd, size)


def format_timing(name: str, t: ReplayTiming) -> str:
    return (
        f"{name}: {t.frames} frames; read+decode {t.frames / t.read_decode_s:.0f} fps, replay {t.frames / t.replay_s:.0f} fps "
        f"(ratio {t.throughput_ratio:.2f}), with --rrd {t.frames / t.replay_rrd_s:.0f} fps (cost ratio {t.rerun_ratio:.2f}, "
        f"{t.rrd_bytes / 1e6:.1f} MB)"
    )
