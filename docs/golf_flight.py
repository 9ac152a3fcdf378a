"""The golf ball's 3-D flight fitted offline (trackreplay flight) vs the causal 3-D EKF, on synthetic tee shots.

    python docs/golf_flight.py [--quick] [--workdir DIR] [--golf KEY ...] [--from-json]

Uses the tee shots of docs/golf_synthetic.py (``--workdir`` reuses ``golf-KEY.mcap``; ``--quick``:
seed0 and launch2 only). Each shot is replayed once with the engine's own loop (seed 0): the
trajectory gives the lines of sight for the fit, and the golf tracker's EKF intermediates give the
causal estimates (its last predicted ground contact before the true landing, the highest Z of its
state before the landing). Writes docs/golf_flight.md (every number from this run) and
docs/golf_flight.json.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

# One BLAS thread: least_squares' SVD of a ~900 x 15 Jacobian gains nothing from threads, and on a
# shared machine OpenBLAS's spinning threads cost 2-3x the fit's CPU time (seed0 without the
# jackknife: 4.5 s CPU with the default threads, 1.8 s with one). Must precede numpy's import.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))

import numpy as np  # noqa: E402
import polars as pl  # noqa: E402

from trackreplay.replay.core.engine import ReplayRequest, iter_steps  # noqa: E402
from trackreplay.replay.analysis.flight import FlightConfig, fit_flight, observations  # noqa: E402
from trackreplay.replay.log.groundtruth import read_groundtruth  # noqa: E402
from trackreplay.replay.log.reader import LogReader  # noqa: E402
from trackreplay.replay.analysis.smooth import log_context  # noqa: E402
from trackreplay.replay.core.trajectory import state_row, trajectory_table  # noqa: E402

GOLF_DEFAULT = ("seed0", "launch2", "occl", "nobounce", "beside")
GOLF_QUICK = ("seed0", "launch2")
# The fit before the impact/launch changes (replay/analysis/flight.py of 84a9a4e, docs of b31d04b: one horizontal retention for
# every impact, launch time free), same logs and replay, measured in the session that made them:
# landing error m, fit CPU s (one BLAS thread) — the committed golf_flight.md of b31d04b has the
# same landing errors.
PREVIOUS = {"seed0": (6.93, 9.7), "launch2": (1.62, 4.7), "occl": (8.32, 19.2), "nobounce": (1.48, None), "beside": (13.46, None)}


def causal(log: Path, land_frame: int) -> tuple[pl.DataFrame, np.ndarray | None, float | None]:
    rows, contact, apex = [], None, None
    for step in iter_steps(ReplayRequest(log=log, tracker="golf")):
        k = step.frame.index
        rows.extend(state_row("golf", k, step.frame.t_ns, s) for s in step.states)
        ekf = step.intermediates.ekf if step.intermediates is not None else None
        if ekf is None or k >= land_frame:
            continue
        if np.isfinite(ekf.landing_world).all():
            contact = ekf.landing_world.copy()
        if np.isfinite(ekf.x[2]):
            apex = float(ekf.x[2]) if apex is None else max(apex, float(ekf.x[2]))
    return trajectory_table(rows), contact, apex


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--workdir", type=Path)
    ap.add_argument("--golf", nargs="*", default=None)
    ap.add_argument("--quick", action="store_true", help="seed0 and launch2 only")
    ap.add_argument("--from-json", action="store_true", help="rewrite golf_flight.md from golf_flight.json (no run)")
    args = ap.parse_args()
    if args.from_json:
        d = json.loads((HERE / "golf_flight.json").read_text())
        write(d["shots"], d["commit"], d["golf_dirty"])
        return 0
    args.golf = args.golf or list(GOLF_QUICK if args.quick else GOLF_DEFAULT)
    tmp = None
    if args.workdir is None:
        tmp = tempfile.TemporaryDirectory()
        args.workdir = Path(tmp.name)
    import golf_synthetic as G

    golf = {k: (label, cfg) for k, label, cfg in G.RUNS}
    results = []
    head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=HERE, capture_output=True, text=True).stdout.strip()
    dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no", "trackers/golf"], cwd=HERE.parent,
                           capture_output=True, text=True).stdout.strip()
    for key in args.golf:
        label, cfg = golf[key]
        log, info = G.synthesise(key, cfg, args.workdir)
        gt = read_groundtruth(LogReader(log))
        tee = gt.filter(pl.col("frame") == 0).select("X", "Y").to_numpy()[0]
        land_true = np.array(info["landing_point"])
        t_rep = time.perf_counter()
        traj, contact, apex_c = causal(log, info["landing_frame"])
        t_rep = time.perf_counter() - t_rep
        times, cams = log_context(log)
        started, cpu = time.perf_counter(), time.process_time()
        fit = fit_flight(observations(traj, cams), FlightConfig(), cfg.fps)
        seconds, cpu = time.perf_counter() - started, time.process_time() - cpu
        rep = fit.report
        land_fit = np.array([v.value for v in rep.landing_point])
        r = {
            "key": key, "label": label, "carry": info["carry"], "apex": info["apex_height"],
            "fit_land_err": float(np.linalg.norm(land_fit[:2] - land_true[:2])),
            "fit_land_std": float(np.hypot(rep.landing_point[0].std, rep.landing_point[1].std)),
            "fit_carry_err": rep.carry.value - info["carry"], "fit_carry_std": rep.carry.std,
            "fit_apex_err": rep.apex_height.value - info["apex_height"], "fit_apex_std": rep.apex_height.std,
            "fit_tof_err": rep.time_of_flight.value - (info["landing_time"] - info["launch_time"]),
            "speed": rep.launch_speed, "elev": rep.launch_elevation, "az": rep.launch_azimuth,
            "true_launch": (cfg.launch.speed, cfg.launch.elevation, cfg.launch.azimuth),
            "rms_px": rep.rms_px, "frames": rep.frames_used, "seconds": seconds, "cpu_seconds": cpu, "replay_seconds": t_rep, "notes": rep.notes,
            "ekf_land_err": None if contact is None else float(np.linalg.norm(contact[:2] - land_true[:2])),
            "ekf_carry_err": None if contact is None else float(np.linalg.norm(contact[:2] - tee)) - info["carry"],
            "ekf_apex_err": None if apex_c is None else apex_c - info["apex_height"],
            "rest_err": float(np.linalg.norm(np.array([v.value for v in rep.rest_point])[:2] - np.array(info["rest_point"][:2])))
            if math.isfinite(rep.rest_point[0].value) else None,
        }
        r["speed"], r["elev"], r["az"] = ((v.value, v.std) for v in (r["speed"], r["elev"], r["az"]))
        r["notes"] = list(r["notes"])
        results.append(r)
        print(key, r, flush=True)
        print(rep.describe(), flush=True)
        (HERE / "golf_flight.json").write_text(json.dumps({"commit": head, "golf_dirty": bool(dirty), "shots": results}, indent=1) + "\n")
        write(results, head, bool(dirty))
    if tmp is not None:
        tmp.cleanup()
    return 0


def f(v, spec=".2f") -> str:
    return "–" if v is None or (isinstance(v, float) and not math.isfinite(v)) else format(v, spec)


def write(results: list[dict], commit: str, dirty: bool) -> None:
    L = ["# Golf: the 3-D flight from one PTZ camera, fitted offline vs the causal EKF", "",
         "> Stays a script, not a `trackreplay evaluate` manifest (docs/README.md): `golf_flight.py`: the offline 3-D "
         "flight fit against the causal EKF (landing, carry and apex errors in metres), not a tracking score of image "
         "rows.", "",
         "Generated end to end by `python docs/golf_flight.py [--quick]` (synthetic tee shots of docs/golf_synthetic.py,",
         f"replay seed 0, deterministic), on commit {commit}" + (" with trackers/golf modified in the working tree" if dirty else "")
         + ". `trackreplay flight TRAJ LOG` (replay/analysis/flight.py) fits launch time and point, launch",
         "velocity, drag, lift (with a 1/speed slope) and spin-axis tilt, then the impacts (restitution, Coulomb",
         "friction capped at rolling without slipping, the backspin at the first impact), the hops (drag and the",
         "spin's Magnus lift) and the roll (deceleration), jointly, by SciPy least squares (soft-L1) to every measured",
         "line of sight (encoders + lens table) and the blob's apparent size. The *causal EKF* is the golf tracker's own 3-D",
         "filter (seed 000 §2.3): its last predicted ground contact before the true landing frame, and the",
         "highest Z of its state before the landing. Errors against the scene's 3-D ground truth. ± is the",
         "reported 1-σ: for apex, carry, landing (and the other derived quantities) a delete-a-block jackknife",
         "over time (10 refits without a tenth of the frames each, warm-started), so that model error counts;",
         "for the launch parameters the larger of it and the fit's covariance. Goal: landing point within 1 % of carry.",
         "*fit s*: wall and CPU seconds of the fit with its jackknife (one BLAS thread) on a shared 2-core machine",
         "(other jobs ran at the same time: the CPU seconds are the comparable figure); *before*: the fit of 84a9a4e (the table of b31d04b).", "",
         "| shot | carry m | landing error m (fit ± 1σ) | error / σ | % of carry | before: landing error m | causal EKF landing error m | carry error m fit / EKF | apex error m fit / EKF | time-of-flight error s | fit RMS px | frames | replay s | fit s wall / CPU | before: fit CPU s |",
         "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in results:
        ratio = r["fit_land_err"] / r["fit_land_std"] if r["fit_land_std"] > 0 else math.inf
        prev = PREVIOUS.get(r["key"], (None, None))
        L.append(f"| {r['label']} | {r['carry']:.1f} | {r['fit_land_err']:.2f} ± {r['fit_land_std']:.2f} | {ratio:.2f} | {100 * r['fit_land_err'] / r['carry']:.2f} % | "
                 f"{f(prev[0])} | {f(r['ekf_land_err'])} | {r['fit_carry_err']:+.2f} / {f(r['ekf_carry_err'], '+.2f')} | "
                 f"{r['fit_apex_err']:+.2f} ± {r['fit_apex_std']:.2f} / {f(r['ekf_apex_err'], '+.2f')} | {r['fit_tof_err']:+.3f} | {r['rms_px']:.2f} | {r['frames']} | "
                 f"{r['replay_seconds']:.0f} | {r['seconds']:.1f} / {f(r.get('cpu_seconds'), '.1f')} | {f(prev[1], '.1f')} |")
    L += ["", "Launch (fit ± 1σ, true in brackets):", "", "| shot | speed m/s | elevation ° | azimuth ° | rest point error m | notes |", "|---|---|---|---|---|---|"]
    for r in results:
        s, e, a = r["true_launch"]
        L.append(f"| {r['label']} | {r['speed'][0]:.1f} ± {r['speed'][1]:.1f} ({s:g}) | {r['elev'][0]:.2f} ± {r['elev'][1]:.2f} ({e:g}) | "
                 f"{r['az'][0]:.2f} ± {r['az'][1]:.2f} ({a:g}) | {f(r['rest_err'])} | {'; '.join(r['notes'])} |")
    within = [r for r in results if r["fit_land_err"] <= 3 * r["fit_land_std"]]
    goal = [r for r in results if r["fit_land_err"] <= 0.01 * r["carry"]]
    better = [r for r in results if r["ekf_land_err"] is not None and r["fit_land_err"] < r["ekf_land_err"]]
    L += ["", "## What this shows", "",
          f"- Landing within 1 % of carry on {len(goal)} of {len(results)} shots; closer than the causal EKF's last",
          f"  prediction on {len(better)} of {len(results)}.",
          f"- The true landing point lies within 3σ on {len(within)} of {len(results)} shots; the largest error/σ is "
          f"{max(r['fit_land_err'] / r['fit_land_std'] for r in results):.2f}.",
          "- What moved the landing (each measured on seed0 / launch2 / occl, without the jackknife; landing error m):",
          "  the fit of 84a9a4e 6.93 / 1.62 / 8.32. (1) *The impacts*: one horizontal retention for every impact",
          "  cannot fit both hops and the roll (the first impact stops the slip and costs ~half the horizontal",
          "  speed, the later ones almost nothing), and its misfit after the landing pulled the landing; Coulomb",
          "  friction capped at rolling without slipping, with the backspin at the first impact fitted: 2.87 / 0.14 / –.",
          "  (2) *The launch within one frame of the last tee frame*: the tracker loses the ball at the launch",
          "  and finds it again 1.4 s later; left free, launch time, speed and lift traded off along that gap",
          "  (seed0 launched 0.6 s late at 52 m/s); with (1): 0.79 / 0.14 / 0.23; alone (old impacts): 6.86 / 2.99 / 7.59.",
          "  (3) *Magnus lift in the hops* from the spin the impact leaves (topspin pushes the hop down):",
          "  without it 1.77 / 0.17 / 1.17. (4) The spin's decay in the hops (e-folding 25 s; 5 % over a long",
          "  hop, so the next impact finds the ball slipping again): 0.60 / 0.13 / 0.16, and the rest point of a",
          "  test shot 2 m closer. Each step helped on every shot it was tried on.",
          "- The ground: once the ball rolls, its line of sight meets the known ground plane; at the zoom the",
          "  operator uses (the ball ~6 px at 180 m) that places it within ~0.3 m per frame, and the landing is",
          "  continuous with the hops and the roll. The joint fit uses this through the angles themselves (a",
          "  rolling ball's modelled Z is its radius), no separate ground-intersection residual.",
          "- Tried and not kept: weighting each frame by the tracker's confidence (0.91 / 0.13 / 0.05 m: better",
          "  on two shots, worse on seed0; `FlightConfig.confidence_weight`, off); `predicted` and `lost` rows were",
          "  already not observations. A jackknife of a few Gauss-Newton steps with the full fit's Jacobian instead",
          "  of refits (σ 0.06 m for a 0.79 m error: the refits move along the valleys a linearisation does not",
          "  see); refits capped at 40 evaluations (seed0's σ 1.05 -> 0.44 m). A 1/30 s step (landing within",
          "  0.12 m of the 1/60 s fit, half the cost): not needed.",
          "- Speed: the RK4's acceleration written out in the loop (no call per evaluation) and the flight cached",
          "  by its own parameters (launch time and point only shift it; the bounce and roll parameters do not",
          "  touch it, so 7 of the 15 simulations of a Jacobian integrate no flight): one finite-difference",
          "  Jacobian 33.8 -> 17.4 ms CPU. The full fit in rounds of 100 evaluations (a restart resets",
          "  least_squares' trust region, which a kink — the friction's cap, a hop too low to count — had",
          "  shrunk until it crawled: seed0 took 400 evaluations, 11.4 s CPU, now 152, 3.7 s). One BLAS thread",
          "  (this script sets OPENBLAS_NUM_THREADS=1): on a shared machine the default threads cost 2-3x the",
          "  CPU of least_squares' small SVDs. Fit with jackknife, CPU s, before -> after: "
          + ", ".join(f"{r['key']} {f(PREVIOUS.get(r['key'], (None, None))[1], '.1f')} -> {f(r.get('cpu_seconds'), '.1f')}" for r in results) + ".",
          "  The jackknife's 10 refits are most of it: where a block holds the tee frames or the landing, a refit",
          "  walks a long valley to its 100-evaluation limit (seed0: 4 of 10 in a profiled run), and that keeps the σ",
          "  honest (see above); with the new impacts seed0's refits walk further than before, so its total",
          "  is not lower although each evaluation is ~2x cheaper.",
          "- carry's σ (JSON `fit_carry_std`, 5-14 m) is much larger than the landing point's: the block",
          "  holding the tee frames leaves the launch point free along the line of sight in its refit.",
          "- The shot beside the tee is not solved: its track starts in the air (frame 89, near the apex, the",
          "  marks were over the sky), so no frame shows the launch; the fit settles in a wrong basin (RMS ~5 px,",
          "  launch point and time far off) and the landing is "
          + next((f"{100 * r['fit_land_err'] / r['carry']:.0f} %" for r in results if r['key'] == 'beside' and r.get('fit_land_err') is not None), "far")
          + " of carry off (the fit of 84a9a4e: 9 %).",
          "  Until a guard was added the new launch bound took its first frame for a tee frame (20 %). A launch",
          "  extrapolated back from the first frames' apparent-size ranges was tried as the start and was worse",
          "  (31 %): the sizes of a 6 px ball are too noisy. It needs a start from the ground phase backwards.",
          "- Model error left (the synthetic truth's lift is S/(1+2S) of a decaying spin, the fit's a 1/speed",
          "  law): a noiseless test shot seen like seed0 lands 0.5 % of carry off (tests/replay/analysis/test_flight_ground.py).",
          "- The golf tracker was being changed at the same time: the commit above names the one replayed."]
    (HERE / "golf_flight.md").write_text("\n".join(L) + "\n")


if __name__ == "__main__":
    sys.exit(main())
