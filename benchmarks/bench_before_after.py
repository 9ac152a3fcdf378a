"""Replay speed and digest of every tracker, this checkout against another commit, in one run.

A refactor that must not change behaviour (issue 28) is checked here twice: each tracker's replay
digest on the same synthetic logs must be equal on both sides, and its replay CPU time must stay
within 5 %. The two sides are two Python interpreters, each with its own ``pip install -e`` of one
checkout. They run in turn (before, after, before, after, ...) so a drift in the machine's speed
hits both alike, and the ratio is taken round by round; the median of the rounds is reported.

    python -m venv /tmp/base/.venv && /tmp/base/.venv/bin/pip install -e /tmp/base   # a checkout of the old commit
    python benchmarks/bench_before_after.py --before /tmp/base/.venv/bin/python --after .venv/bin/python

Writes ``benchmarks/results/before_after.json`` (each side's commit, the machine, per tracker: the
digests, CPU seconds per round, the median after/before ratio).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
# One synthetic log per tracker, written once by the "after" side's synthesiser and read by both.
SCENES = {
    "flow": ("flow-sim1", ["--frames", "120"]),
    "golf": ("golf-teeshot", ["--seed", "4"]),
    "colorpf": ("colorpf-approach", []),
    "groups": ("groups-crossing", []),
}
# Run inside each side's interpreter: one warm-up replay, then the timed one (CPU of this process,
# the engine's read-ahead thread included).
TIMED = """
import json, sys, time
import trackreplay
log, tracker = sys.argv[1], sys.argv[2]
trackreplay.replay_log(log, tracker)
t0 = time.process_time()
result = trackreplay.replay_log(log, tracker)
print(json.dumps({"cpu_s": time.process_time() - t0, "digest": result.digest, "frames": result.frames}))
"""


def commit_of(python: str) -> str:
    """The git commit of the checkout ``python``'s trackreplay was installed from (editable)."""
    code = "import trackreplay, pathlib; print(pathlib.Path(trackreplay.__file__).resolve().parents[1])"
    root = subprocess.run([python, "-c", code], capture_output=True, text=True, check=True, cwd=tempfile.gettempdir()).stdout.strip()
    return subprocess.run(["git", "-C", root, "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                          check=True).stdout.strip()


def timed_replay(python: str, log: Path, tracker: str) -> dict:
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    # Started outside both checkouts: ``python -c`` puts the working directory first on sys.path.
    out = subprocess.run([python, "-c", TIMED, str(log), tracker], capture_output=True, text=True, env=env, timeout=900,
                         cwd=log.parent)
    if out.returncode:
        raise SystemExit(f"{python} failed on {tracker}: {out.stderr.strip().splitlines()[-1:]}")
    return json.loads(out.stdout)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--before", required=True, help="python of the old checkout's venv")
    ap.add_argument("--after", default=sys.executable, help="python of this checkout's venv (default: this one)")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--trackers", default=",".join(SCENES))
    ap.add_argument("--out", type=Path, default=HERE / "results" / "before_after.json")
    args = ap.parse_args(argv)
    trackers = [t for t in args.trackers.split(",") if t]
    report: dict = {"machine": {"cpu": platform.processor() or platform.machine(), "cores": os.cpu_count(),
                                "python": platform.python_version(), "load_before": os.getloadavg()},
                    "before": commit_of(args.before), "after": commit_of(args.after), "rounds": args.rounds,
                    "trackers": {}}
    cli = str(Path(args.after).with_name("trackreplay"))
    with tempfile.TemporaryDirectory() as tmp:
        for tracker in trackers:
            scene, extra = SCENES[tracker]
            log = Path(tmp) / f"{scene}.mcap"
            subprocess.run([cli, "synth", scene, str(log), *extra], check=True, capture_output=True)
            before, after = [], []
            for _ in range(args.rounds):
                before.append(timed_replay(args.before, log, tracker))
                after.append(timed_replay(args.after, log, tracker))
            ratios = [a["cpu_s"] / b["cpu_s"] for a, b in zip(after, before)]
            row = {"scene": f"{scene} {' '.join(extra)}".strip(), "frames": after[0]["frames"],
                   "digest_before": before[0]["digest"], "digest_after": after[0]["digest"],
                   "digests_equal": {r["digest"] for r in before} == {r["digest"] for r in after},
                   "cpu_s_before": [round(r["cpu_s"], 4) for r in before],
                   "cpu_s_after": [round(r["cpu_s"], 4) for r in after],
                   "median_ratio_after_over_before": round(statistics.median(ratios), 4)}
            report["trackers"][tracker] = row
            print(f"{tracker:8s} digests equal: {row['digests_equal']}  CPU after/before (median of {args.rounds}): "
                  f"{row['median_ratio_after_over_before']:.3f}", flush=True)
    report["machine"]["load_after"] = os.getloadavg()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(report, indent=2) + "\n")
    return 0 if all(r["digests_equal"] for r in report["trackers"].values()) else 1


if __name__ == "__main__":
    sys.exit(main())
