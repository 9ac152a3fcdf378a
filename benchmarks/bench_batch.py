"""Batch replay on a local Ray (2 workers) vs the same replays one after another, in one run.

The tasks: flow-sim1 logs x --set epsilon values (the same cross product `trackreplay batch`
builds), each a full task as a Ray worker runs it (replay, trajectory, per-frame digests,
summary, eval). Serial runs them in this process (`trackreplay batch --serial`), after a warm-up,
so its imports are paid; Ray's figure includes starting the local cluster and its workers
(what a user waits for), and is also given without `ray.init`/`shutdown`.

Ray's per-task overhead is stated two ways: a no-op task's round trip (scheduling + transfer),
and, in the batch itself, the worker time not spent inside tasks divided by the task count
(worker start-up and imports, scheduling, result transfer, the idle tail).

Usage: python benchmarks/bench_batch.py [--frames 300] [--logs 2] [--values 4] [--workers 2]
Writes benchmarks/results/batch.json and prints a table.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks.machine import describe  # noqa: E402
from trackreplay.recorder.synth.flow_sims import FlowSimConfig, write_flow_sim  # noqa: E402
from trackreplay.replay.runs.batch import BatchOptions, plan, run_ray, run_serial  # noqa: E402
from trackreplay.replay.runs.batch_config import grid  # noqa: E402


def noop(x: int) -> int:
    return x


TASK_MEMORY = """
import resource, sys, tracemalloc
from pathlib import Path
sys.path.insert(0, {root!r})
from trackreplay.replay.runs.batch import BatchOptions, plan, run_task
task = plan([Path({log!r})], "flow", [0], [])[0]
tracemalloc.start()
row = run_task(task, BatchOptions(out=Path({out!r})))
assert row["status"] == "ok", row["error"]
print(row["frames"], resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, tracemalloc.get_traced_memory()[1] // 1024)
"""


def task_memory(log: Path, out: Path) -> tuple[int, int, int]:
    """(frames, peak RSS KiB, peak traced Python/numpy KiB) of one batch task in a fresh process."""
    import subprocess

    code = TASK_MEMORY.format(root=str(ROOT), log=str(log), out=str(out))
    frames, rss, traced = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True,
                                         text=True).stdout.split()
    return int(frames), int(rss), int(traced)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--logs", type=int, default=2)
    ap.add_argument("--values", type=int, default=4, help="epsilon values per log (tasks = logs x values)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results" / "batch.json")
    args = ap.parse_args()
    import ray

    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        logs = []
        for k in range(args.logs):
            logs.append(tmp / f"sim{k}.mcap")
            write_flow_sim(logs[-1], FlowSimConfig(scene=("flow-sim1", "flow-sim2", "flow-sim3")[k % 3], frames=args.frames))
        values = ",".join(f"{0.5 + 0.05 * i:.2f}" for i in range(args.values))
        tasks = plan(logs, "flow", [0], grid([f"epsilon={values}"]))
        run_serial(tasks[:1], BatchOptions(out=tmp / "warm"))  # imports and first-call costs, as a warm process has
        t = time.perf_counter()
        serial = run_serial(tasks, BatchOptions(out=tmp / "serial"))
        serial_s = time.perf_counter() - t

        t = time.perf_counter()
        ray.init(num_cpus=args.workers, include_dashboard=False, log_to_driver=False)
        init_s = time.perf_counter() - t
        t = time.perf_counter()
        batch = run_ray(tasks, BatchOptions(out=tmp / "ray"))
        batch_s = time.perf_counter() - t
        remote_noop = ray.remote(num_cpus=1)(noop)
        ray.get([remote_noop.remote(i) for i in range(20)])  # warm
        t = time.perf_counter()
        ray.get([remote_noop.remote(i) for i in range(200)])
        noop_ms = (time.perf_counter() - t) / 200 * 1e3
        t = time.perf_counter()
        for i in range(50):
            ray.get(remote_noop.remote(i))
        noop_sequential_ms = (time.perf_counter() - t) / 50 * 1e3
        t = time.perf_counter()
        ray.shutdown()
        shutdown_s = time.perf_counter() - t

        # memory of one task (replay + per-frame digests + outputs + eval) for a log 10x longer
        long = tmp / "long.mcap"
        write_flow_sim(long, FlowSimConfig(scene="flow-sim1", frames=10 * args.frames))
        mem_base = task_memory(logs[0], tmp / "mem-base")
        mem_long = task_memory(long, tmp / "mem-long")

    same = all(a["digest"] == b["digest"] and a["digest"] is not None for a, b in zip(serial, batch))
    inside = sum(r["task_seconds"] for r in batch)
    per_task_overhead = (args.workers * batch_s - inside) / len(tasks)
    with_cluster = init_s + batch_s + shutdown_s
    results = {
        "machine": describe(),
        "tasks": {"count": len(tasks), "tracker": "flow", "log": f"flow-sim1/2 256x256 PNG, {args.frames} frames",
                  "grid": f"{args.logs} logs x epsilon={values}"},
        "workers": args.workers,
        "serial_s": serial_s,
        "serial_task_s_mean": sum(r["task_seconds"] for r in serial) / len(serial),
        "ray_batch_s": batch_s,
        "ray_init_s": init_s,
        "ray_shutdown_s": shutdown_s,
        "ratio_serial_over_batch": serial_s / batch_s,
        "ratio_including_cluster_start_stop": serial_s / with_cluster,
        "ray_task_s_mean": inside / len(batch),
        "per_task_overhead_in_batch_s": per_task_overhead,
        "noop_task_ms_pipelined": noop_ms,
        "noop_task_ms_round_trip": noop_sequential_ms,
        "digests_equal_serial": same,
        "task_memory": {"frames": [mem_base[0], mem_long[0]], "peak_rss_kib": [mem_base[1], mem_long[1]],
                        "traced_peak_kib": [mem_base[2], mem_long[2]], "traced_ratio": mem_long[2] / max(1, mem_base[2]),
                        "rss_ratio": mem_long[1] / max(1, mem_base[1]), "target": "<= 1.2 (flat in log length)"},
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(results, indent=2) + "\n")
    print(f"machine: {results['machine']['cpu']}, {results['machine']['cores']} cores; {len(tasks)} flow replays of {args.frames} frames")
    print(f"serial (one process, warm): {serial_s:.2f} s ({results['serial_task_s_mean']:.2f} s per task)")
    print(f"Ray, {args.workers} workers: {batch_s:.2f} s (+ init {init_s:.2f} s, shutdown {shutdown_s:.2f} s); "
          f"{results['ray_task_s_mean']:.2f} s per task inside the workers")
    print(f"throughput ratio serial/batch: {results['ratio_serial_over_batch']:.2f} "
          f"({results['ratio_including_cluster_start_stop']:.2f} counting cluster start and stop)")
    print(f"Ray overhead: no-op task {noop_sequential_ms:.2f} ms round trip ({noop_ms:.2f} ms pipelined); "
          f"in the batch {per_task_overhead:.2f} s of worker time per task outside the task (worker start and imports, "
          f"scheduling, idle tail)")
    print(f"every batch digest equals its serial replay: {same}")
    m = results["task_memory"]
    print(f"one task's memory, {m['frames'][1]} vs {m['frames'][0]} frames: peak RSS ratio {m['rss_ratio']:.3f}, "
          f"traced allocations {m['traced_peak_kib'][1]} vs {m['traced_peak_kib'][0]} KiB: ratio {m['traced_ratio']:.3f}")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
