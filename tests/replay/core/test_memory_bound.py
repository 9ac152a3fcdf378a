"""docs/memory.md's bound on a replay's memory as a formula of the frame size, for the flow tracker:
peak ≈ R0 + (T + (P + 2)·C)·W·H bytes, T = 20 bytes a pixel (the flow tracker's float planes), P the
frames decoded ahead (4), C the bytes of a decoded pixel (1: grey). Checked on the Python and numpy
allocations a replay makes (what grows with the frame), from the marginal cost of a larger frame."""

from __future__ import annotations

import tracemalloc
from pathlib import Path

from trackreplay.recorder.synth.flow_sims import FlowSimConfig, write_flow_sim
from trackreplay.replay.core.engine import ReplayRequest, replay

FLOW_BYTES_PER_PIXEL = 20
PREFETCH = 4


def _traced_peak(log: Path) -> int:
    replay(ReplayRequest(log=log, tracker="flow", prefetch=PREFETCH))  # (caches filled once)
    tracemalloc.start()
    replay(ReplayRequest(log=log, tracker="flow", prefetch=PREFETCH))
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return peak


def test_replay_memory_per_pixel_is_within_the_stated_bound(tmp_path: Path) -> None:
    peaks = {}
    for size in (256, 512):
        log = tmp_path / f"flow-{size}.mcap"
        write_flow_sim(log, FlowSimConfig(scene="flow-sim1", frames=6, size=size, radius=size / 8))
        peaks[size] = _traced_peak(log)
    per_pixel = (peaks[512] - peaks[256]) / (512**2 - 256**2)
    assert per_pixel <= FLOW_BYTES_PER_PIXEL + (PREFETCH + 2) * 1, per_pixel
    assert peaks[512] <= 1_000_000 + (FLOW_BYTES_PER_PIXEL + (PREFETCH + 2)) * 512**2, peaks
