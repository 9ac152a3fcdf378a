"""Replay some cases of the colour PF's box corpus with ``[colorpf]`` overrides and score them as ``evaluate`` does.

    python docs/colorpf_try.py --out colorpf-box-out --cases otb_car4 --seeds 0,1,2 \\
        --config '{"reference": {"refuse_unseparated": false}}'

For trying a change on the cases it is meant for before the whole corpus is run through ``trackreplay evaluate``
(docs/colorpf.md, "Issue 31, fourth pass": the "tried and not kept" figures). ``--out``: an ``evaluate`` run's
folder whose ``logs/`` it reuses (the cases are recorded there when absent). Prints one line per case and seed
(success AUC, precision at 20 px, wrong_rate, predicted_wrong_rate, ECE, coverage, the replay's digest) and each
case's mean and max - min over the seeds.

Where the time goes (docs/colorpf.md, "Speed, issue 31"): ``--cpu`` adds to each line the tracker's own CPU
time per frame (the process's CPU clock round each step alone, in a second replay: no decoding, digest or rows;
another process's load inflates it less than the wall clock) and the whole loop's (reading and decoding the
frames too); ``--repeat N``: the least of N such replays, ``--profile N`` prints cProfile's N largest
cumulative entries under ``trackers/`` (and OpenCV's LK and warp calls) over all the replays (frames read in the
loop, no reader thread).
"""

from __future__ import annotations

import argparse
import cProfile
import dataclasses
import json
import pstats
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

from trackreplay.replay.core.engine import ReplayRequest, iter_steps, replay  # noqa: E402
from trackreplay.replay.runs.case_logs import recorder_code  # noqa: E402
from trackreplay.replay.runs.corpus import load_corpus  # noqa: E402
from trackreplay.replay.runs.evaluate import EvalOptions, prepare_or_error, score  # noqa: E402

CORPUS = ROOT / "benchmarks" / "corpora" / "colorpf-box.toml"


def _rate(value: float | None) -> str:
    return "n/a" if value is None or not np.isfinite(value) else f"{value:.3f}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, required=True, help="an evaluate run's folder (its logs/ are reused)")
    ap.add_argument("--cases", default="", help="comma-separated case names (default: every case)")
    ap.add_argument("--seeds", default="0", help="comma-separated tracker seeds")
    ap.add_argument("--config", default="{}", help="[colorpf] overrides as JSON")
    ap.add_argument("--cpu", action="store_true", help="also the tracker's own CPU ms per frame (a second replay)")
    ap.add_argument("--repeat", type=int, default=1, help="--cpu: the least of this many replays")
    ap.add_argument("--profile", type=int, default=0, metavar="N", help="print cProfile's N largest entries")
    args = ap.parse_args()
    profile = cProfile.Profile() if args.profile else None
    seeds = tuple(int(s) for s in args.seeds.split(","))
    wanted = set(args.cases.split(",")) if args.cases else None
    opts = EvalOptions(args.out, seeds, 0.0, None, recorder_code())
    config = json.loads(args.config)
    means = []
    for case in load_corpus(CORPUS, None).cases:
        if wanted is not None and case.name not in wanted:
            continue
        prep = prepare_or_error(case, opts)
        if isinstance(prep, str):
            print(f"{case.name}: skipped ({prep})", file=sys.stderr)
            continue
        aucs = []
        for seed in seeds:
            log, _ = prep.for_seed(seed)
            request = ReplayRequest(log=log, tracker="colorpf", seed=seed, config=config, prefetch=0 if profile else 4)
            if profile is not None:
                profile.enable()
            result = replay(request)
            if profile is not None:
                profile.disable()
            s = score(prep, log, result.trajectory)
            aucs.append(s["success_auc"])
            cpu = ""
            if args.cpu:
                times = [_step_cpu_ms(request) for _ in range(max(args.repeat, 1))]
                cpu = " tracker CPU {:.2f} ms/frame (with reading and decoding {:.2f})".format(
                    min(t[0] for t in times), min(t[1] for t in times))
            print(f"{case.name} seed {seed}: AUC {s['success_auc']:.3f} prec@20px {s['precision_20px']:.3f} "
                  f"wrong_rate {_rate(s['wrong_rate'])} predicted_wrong_rate {_rate(s['predicted_wrong_rate'])} "
                  f"ECE {_rate(s['ece'])} coverage {_rate(s['coverage'])} digest {result.digest[:12]}{cpu}", flush=True)
        means.append(float(np.mean(aucs)))
        print(f"{case.name}: mean AUC {np.mean(aucs):.3f}, seed spread {np.ptp(aucs):.3f}", flush=True)
    if means:
        print(f"mean over {len(means)} case(s): {np.mean(means):.3f}")
    if profile is not None:
        # the tracker's functions, and OpenCV's two largest calls in them (LK, the warp)
        pstats.Stats(profile).sort_stats("cumulative").print_stats("trackers/|calcOpticalFlowPyrLK|warpAffine",
                                                                   args.profile)


def _step_cpu_ms(request: ReplayRequest) -> tuple[float, float]:
    """CPU ms per frame of a replay of ``request`` (frames read in the loop, no reader thread; the process's CPU
    clock): the tracker's ``step`` alone, and the whole loop (reading and decoding each frame too)."""
    steps = iter_steps(dataclasses.replace(request, prefetch=0))
    step, spent = steps.tracker.step, [0.0]

    def timed(frame):
        started = time.process_time()
        out = step(frame)
        spent[0] += time.process_time() - started
        return out

    steps.tracker.step = timed
    started = time.process_time()
    frames = max(sum(1 for _ in steps), 1)  # (every step timed)
    return 1e3 * spent[0] / frames, 1e3 * (time.process_time() - started) / frames


if __name__ == "__main__":
    main()
