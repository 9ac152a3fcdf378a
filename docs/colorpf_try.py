"""Replay some cases of the colour PF's box corpus with ``[colorpf]`` overrides and score them as ``evaluate`` does.

    python docs/colorpf_try.py --out colorpf-box-out --cases otb_car4 --seeds 0,1,2 \\
        --config '{"reference": {"refuse_unseparated": false}}'

For trying a change on the cases it is meant for before the whole corpus is run through ``trackreplay evaluate``
(docs/colorpf.md, "Issue 31, fourth pass": the "tried and not kept" figures). ``--out``: an ``evaluate`` run's
folder whose ``logs/`` it reuses (the cases are recorded there when absent). Prints one line per case and seed
(success AUC, precision at 20 px, wrong_rate, predicted_wrong_rate, ECE, coverage, the replay's digest) and each
case's mean and max - min over the seeds.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

from trackreplay.replay.core.engine import ReplayRequest, replay  # noqa: E402
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
    args = ap.parse_args()
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
            result = replay(ReplayRequest(log=log, tracker="colorpf", seed=seed, config=config))
            s = score(prep, log, result.trajectory)
            aucs.append(s["success_auc"])
            print(f"{case.name} seed {seed}: AUC {s['success_auc']:.3f} prec@20px {s['precision_20px']:.3f} "
                  f"wrong_rate {_rate(s['wrong_rate'])} predicted_wrong_rate {_rate(s['predicted_wrong_rate'])} "
                  f"ECE {_rate(s['ece'])} coverage {_rate(s['coverage'])} digest {result.digest[:12]}", flush=True)
        means.append(float(np.mean(aucs)))
        print(f"{case.name}: mean AUC {np.mean(aucs):.3f}, seed spread {np.ptp(aucs):.3f}", flush=True)
    if means:
        print(f"mean over {len(means)} case(s): {np.mean(means):.3f}")


if __name__ == "__main__":
    main()
