"""Replay benchmarks, each a ratio measured in one run on one machine.

(a) throughput: replay with the flow tracker vs plain read + decode of the same log (target >= 0.8),
    on the paper's scene (256x256 PNG) and on a broadcast-sized one (720x720 JPEG)
(b) Rerun: replay with full --rrd logging vs none (target <= 1.5)
(d) memory: peak RSS of a replay over a log 10x longer vs the base log (target <= 1.2), each in
    a fresh process so one run's allocations cannot hide the other's

Usage: python benchmarks/bench_replay.py [--frames 300] [--repeats 3]
Writes benchmarks/results/replay.json and prints a table.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks.machine import describe  # noqa: E402
from trackreplay.recorder.synth.flow_sims import FlowSimConfig, write_flow_sim  # noqa: E402
from trackreplay.replay.bench import time_replay  # noqa: E402

PEAK_RSS = """
import resource, sys, tracemalloc
sys.path.insert(0, {root!r})
from trackreplay.replay.engine import ReplayRequest, replay
tracemalloc.start()
r = replay(ReplayRequest(log={log!r}, tracker="flow"))
print(r.frames, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, tracemalloc.get_traced_memory()[1] // 1024)
"""
IMPORTS_RSS = """
import resource, sys
sys.path.insert(0, {root!r})
import trackreplay.replay.engine, trackreplay.replay.registry, trackreplay.trackers.flow.tracker, polars, cv2
print(0, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)
"""


def peak_memory_kib(code: str) -> tuple[int, int]:
    """(peak RSS, peak of Python/numpy allocations traced during the replay) of a fresh process."""
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True).stdout.split()
    return int(out[1]), int(out[2]) if len(out) > 2 else 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results" / "replay.json")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(tmp) / "base.mcap"
        long = Path(tmp) / "long.mcap"
        big = Path(tmp) / "big.mcap"
        write_flow_sim(base, FlowSimConfig(scene="flow-sim1", frames=args.frames))
        write_flow_sim(long, FlowSimConfig(scene="flow-sim1", frames=10 * args.frames))
        write_flow_sim(big, FlowSimConfig(scene="flow-sim1", frames=args.frames, size=720, encoding="jpeg"))
        throughput, rerun_cost = {}, {}
        for name, log in (("256x256 png", base), ("720x720 jpeg", big)):
            t = time_replay(log, "flow", args.repeats)
            throughput[name] = {"frames": t.frames, "read_decode_fps": t.frames / t.read_decode_s,
                                "replay_flow_fps": t.frames / t.replay_s, "ratio": t.throughput_ratio}
            rerun_cost[name] = {"replay_s": t.replay_s, "replay_with_rrd_s": t.replay_rrd_s, "rrd_bytes": t.rrd_bytes,
                                "ratio": t.rerun_ratio}
        rss_imports, _ = peak_memory_kib(IMPORTS_RSS.format(root=str(ROOT)))
        rss_base, traced_base = peak_memory_kib(PEAK_RSS.format(root=str(ROOT), log=str(base)))
        rss_long, traced_long = peak_memory_kib(PEAK_RSS.format(root=str(ROOT), log=str(long)))
        log_bytes = (base.stat().st_size, long.stat().st_size)
    results = {
        "machine": describe(),
        "log": {"scene": "flow-sim1", "frames": args.frames, "image": "256x256 grey PNG", "bytes": log_bytes[0], "long_bytes": log_bytes[1]},
        "repeats": args.repeats,
        "a_throughput": {**throughput, "target": ">= 0.8"},
        "b_rerun": {**rerun_cost, "target": "<= 1.5"},
        "d_memory": {
            "imports_only_peak_rss_kib": rss_imports,
            "base_peak_rss_kib": rss_base,
            "long_10x_peak_rss_kib": rss_long,
            "ratio": rss_long / rss_base,
            "traced_peak_base_kib": traced_base,
            "traced_peak_long_10x_kib": traced_long,
            "traced_ratio": traced_long / max(1, traced_base),
            "target": "<= 1.2",
        },
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(results, indent=2) + "\n")
    d = results["d_memory"]
    print(f"machine: {results['machine']['cpu']}, {results['machine']['cores']} cores")
    for name, r in throughput.items():
        print(f"(a) {name}: replay {r['replay_flow_fps']:.0f} fps vs read+decode {r['read_decode_fps']:.0f} fps: ratio {r['ratio']:.2f} (target >= 0.8)")
    for name, r in rerun_cost.items():
        print(f"(b) {name}: with --rrd {r['replay_with_rrd_s']:.3f} s vs none {r['replay_s']:.3f} s: ratio {r['ratio']:.2f} (target <= 1.5)")
    print(f"(d) peak RSS 10x log {d['long_10x_peak_rss_kib']} KiB vs {d['base_peak_rss_kib']} KiB: ratio {d['ratio']:.3f} "
          f"(imports alone {d['imports_only_peak_rss_kib']} KiB); traced allocations {d['traced_peak_long_10x_kib']} vs "
          f"{d['traced_peak_base_kib']} KiB: ratio {d['traced_ratio']:.3f} (target <= 1.2)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
