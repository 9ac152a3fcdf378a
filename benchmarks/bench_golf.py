"""Golf tracker cost, measured in one run on one machine.

(1) Per-frame tracker step at 720p and 1080p as a ratio to decoding one JPEG frame of the same
    log (target: step <= 0.5 x one 720p decode; the paper needed 40 ms per HD frame on a 3.2 GHz
    dual-processor PC). Both are timed per frame on the same frames, medians reported, plus the
    tail (p90, max: frames where the ball is lost scan the largest search region). Twice: with
    each frame decoded on the stepping thread just before its step (prefetch 0), and as a replay
    runs by default (a reader thread decoding ahead, on the other core).
(2) Particle-count scaling: one CONDENSATION step (select, predict, measure against 3 candidates,
    estimate) for N = 100 ... 100 000, vectorised numpy.

Usage: python benchmarks/bench_golf.py [--seconds 4]
Writes benchmarks/results/golf.json and prints tables.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks.machine import describe  # noqa: E402
from trackreplay.recorder.synth.golf.scene import GolfSceneConfig, write_golf_teeshot  # noqa: E402
from trackreplay.replay.log import frames as frames_module  # noqa: E402
from trackreplay.replay.runs.bench import median_seconds  # noqa: E402
from trackreplay.replay.core.engine import ReplayRequest, iter_steps  # noqa: E402
from trackreplay.trackers.filters.particles import ParticleFilter  # noqa: E402
from trackreplay.trackers.golf.config import GolfConfig, ParticleConfig  # noqa: E402
from trackreplay.trackers.golf.particles import DIM, likelihood, motion, spread_sigma, state  # noqa: E402


def per_frame_costs(log: Path, prefetch: int = 0) -> dict:
    """The engine's replay loop (:func:`iter_steps`) with the tracker's ``step`` timed alone, wall
    clock and the thread's CPU time (a step that waits for the GIL or for the other process on its
    core is slower by the wall clock only), and each frame's decode. ``prefetch`` 0: each frame is
    read and decoded on this thread just before its step, and that decode (the engine's own,
    ``replay.frames.decode_image``) is the one timed: its 2.7-5.9 MB of output pass through this
    core's caches between steps, as in a replay. 4 (the replay's default): a reader thread decodes
    ahead, on the other core when there is one; the decodes are then timed in a pass over the same
    frames after the replay."""
    steps = iter_steps(ReplayRequest(log=log, tracker="golf", config=GolfConfig(), prefetch=prefetch))
    step_seconds: list[float] = []
    step_cpu: list[float] = []
    inner = steps.tracker.step

    def timed_step(frame):
        start, cpu = time.perf_counter(), time.thread_time()
        out = inner(frame)
        step_cpu.append(time.thread_time() - cpu)
        step_seconds.append(time.perf_counter() - start)
        return out

    steps.tracker.step = timed_step
    decodes, encoded = [], []
    engine_decode = frames_module.decode_image

    def timed_decode(*args):
        start = time.perf_counter()
        out = engine_decode(*args)
        decodes.append(time.perf_counter() - start)
        return out

    if not prefetch:
        frames_module.decode_image = timed_decode
    try:
        for step in steps:
            if prefetch:
                encoded.append(np.frombuffer(step.frame.encoded, np.uint8))
    finally:
        frames_module.decode_image = engine_decode
    for buf in encoded:
        start = time.perf_counter()
        cv2.imdecode(buf, cv2.IMREAD_UNCHANGED)  # as decode_image does
        decodes.append(time.perf_counter() - start)
    steps_ms, cpu_ms, decodes_ms = (np.array(v) * 1e3 for v in (step_seconds, step_cpu, decodes))
    return {
        "prefetch": prefetch,
        "frames": len(step_seconds),
        "step_ms": {"median": float(np.median(steps_ms)), "mean": float(steps_ms.mean()),
                    "p90": float(np.percentile(steps_ms, 90)), "max": float(steps_ms.max())},
        "step_cpu_ms": {"median": float(np.median(cpu_ms)), "mean": float(cpu_ms.mean())},
        "decode_ms": {"median": float(np.median(decodes_ms)), "mean": float(decodes_ms.mean())},
        "ratio_median": float(np.median(steps_ms) / np.median(decodes_ms)),
        "ratio_cpu_median": float(np.median(cpu_ms) / np.median(decodes_ms)),
        "ratio_mean": float(steps_ms.mean() / decodes_ms.mean()),
    }


def particle_scaling(counts: list[int], repeats: int) -> list[dict]:
    """One CONDENSATION step on the shared :class:`ParticleFilter` with golf's models: select
    (systematic resampling), predict (eq. (1)), measure against 3 candidates (eq. (2)), estimate (eq. (3))."""
    candidates = np.array([[640.0, 360.0], [700.0, 300.0], [100.0, 600.0]])
    cfg = ParticleConfig()
    transition = motion(cfg, 1.0, damp=False, steps=1)
    measure = likelihood(candidates, cfg.sigma_px, cfg.alpha)
    rows = []
    for n in counts:
        pf = ParticleFilter(n, DIM, np.random.default_rng(0))
        pf.initialise(state(np.array([640.0, 360.0])), spread_sigma(5.0, 3.0))

        def one_step() -> None:
            pf.resample()
            pf.predict(transition)
            pf.weigh(measure)
            pf.estimate()

        seconds = median_seconds(lambda: [one_step() for _ in range(20)], repeats) / 20
        rows.append({"particles": n, "step_ms": seconds * 1e3, "us_per_particle": seconds * 1e6 / n})
    return rows


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seconds", type=float, default=8.0, help="length of the synthetic shots")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results" / "golf.json")
    args = ap.parse_args()
    sizes = {"720p": (1280, 720), "1080p": (1920, 1080)}
    per_frame = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, (w, h) in sizes.items():
            log = Path(tmp) / f"{name}.mcap"
            write_golf_teeshot(log, GolfSceneConfig(width=w, height=h, duration=args.seconds))
            per_frame[name] = per_frame_costs(log)
            per_frame[f"{name}, replay default (prefetch 4)"] = per_frame_costs(log, prefetch=4)
    for key, r in per_frame.items():  # against the 720p decode measured the same way
        reference = per_frame["720p" if r["prefetch"] == 0 else "720p, replay default (prefetch 4)"]
        r["ratio_to_720p_decode"] = r["step_ms"]["median"] / reference["decode_ms"]["median"]
        r["cpu_ratio_to_720p_decode"] = r["step_cpu_ms"]["median"] / reference["decode_ms"]["median"]
    scaling = particle_scaling([100, 300, 1000, 3000, 10000, 30000, 100000], args.repeats)
    results = {"machine": describe(), "opencv_threads": 1, "shot_seconds": args.seconds,
               "per_frame": per_frame, "target": "step median <= 0.5 x one 720p JPEG decode",
               "particle_scaling": scaling}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(results, indent=2) + "\n")
    print(f"machine: {results['machine']['cpu']}, {results['machine']['cores']} cores")
    print("size                               frames  step median (CPU)     p90     max      decode median  step/decode  step/720p-decode (CPU)")
    for name, r in per_frame.items():
        print(f"{name:34} {r['frames']:6}  {r['step_ms']['median']:6.2f} ({r['step_cpu_ms']['median']:.2f}) ms {r['step_ms']['p90']:6.2f}  "
              f"{r['step_ms']['max']:7.2f}  {r['decode_ms']['median']:8.2f} ms   {r['ratio_median']:8.2f}     "
              f"{r['ratio_to_720p_decode']:8.2f} ({r['cpu_ratio_to_720p_decode']:.2f})")
    print("particles  step ms   us/particle")
    for row in scaling:
        print(f"{row['particles']:9}  {row['step_ms']:7.3f}   {row['us_per_particle']:.4f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
