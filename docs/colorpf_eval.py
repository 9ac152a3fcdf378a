"""The colour PF's Tables 1-3 as ablations on the synthetic scenes, and both against CSRT.

    python docs/colorpf_eval.py   # docs/colorpf_results.json + docs/colorpf_otb.png, docs/colorpf_synthetic.png
    python docs/colorpf_eval.py --only otb   # re-run one part (synthetic | otb | switches), the others kept from the JSON

Metric: the paper's mean absolute error of x, y, w, h (px) over the visible frames where the track has
a position, with coverage (share of those frames) beside it. Seeds 0-2, 96 walking frames, 720x480.
Beside it, OTB success AUC, precision at 20 px (a frame without a position counts as IoU 0 and as a
miss) and mean centre error over the frames with a position. OpenCV's CSRT runs on the same frames
from the same marked box, in its own venv (replay/runs/csrt_side.py; built on first use by
benchmarks/bench_colorpf.py's ensure_venv). otb_crossing: the colour PF with tracker seeds 0-4.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import cv2
import numpy as np
import polars as pl

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from benchmarks.bench_colorpf import DEFAULT_VENV, ensure_venv  # noqa: E402
from trackreplay.replay.analysis.eval import IOU_THRESHOLDS  # noqa: E402
from trackreplay.replay.log.frames import FrameTopics, iter_frames  # noqa: E402
from trackreplay.recorder.synth.colorpf import ColorPfSceneConfig, write_colorpf_scene  # noqa: E402
from trackreplay.replay.cli.main import main as cli  # noqa: E402
from trackreplay.replay.core.engine import ReplayRequest, replay  # noqa: E402
from trackreplay.replay.analysis.eval import evaluate  # noqa: E402
from trackreplay.replay.log.groundtruth import read_groundtruth  # noqa: E402
from trackreplay.replay.log.reader import LogReader  # noqa: E402
from trackreplay.trackers.geometry.box import iou  # noqa: E402
from trackreplay.trackers.colorpf.config import PAPER  # noqa: E402

REAL = HERE.parents[1] / "shared" / "data" / "real" / "otb_crossing"
NOISE = {"size": {"mode": "noise"}}


def merged(*cfgs: dict) -> dict:
    """Config overrides merged table by table (later ones win)."""
    out: dict = {}
    for c in cfgs:
        for k, v in c.items():
            out[k] = {**out.get(k, {}), **v} if isinstance(v, dict) else v
    return out


# The Tables 1-3 ablations run on the paper's pipeline (PAPER: uniform pixel weights, fixed
# reference), as the paper compares them; the last row of each is our defaults.
P = PAPER
OURS = ("ours, defaults (Epanechnikov kernel + adaptive reference + foreground cue + region refinement + early "
        "background without the tracked box + hold, geometry)")
TABLES = {
    "Table 1 (colorpf-illumination)": ("colorpf-illumination", {
        "H-S (proposed), size noise": merged(P, NOISE),
        "H-S+V (Pérez), size noise": merged(P, NOISE, {"likelihood": {"histogram": "hsv"}}),
        "H-S, full (geometry)": P, "H-S+V, full (geometry)": merged(P, {"likelihood": {"histogram": "hsv"}}),
        OURS: {}}),
    "Table 2 (colorpf-background)": ("colorpf-background", {
        "mixed reference, size noise": merged(P, NOISE),
        "target colours only, size noise": merged(P, NOISE, {"reference": {"mode": "target"}}),
        "mixed, full (geometry)": P, "target only, full (geometry)": merged(P, {"reference": {"mode": "target"}}),
        OURS: {}}),
    "Table 3 (colorpf-approach)": ("colorpf-approach", {
        "with size estimation (geometry, fixed R)": P,
        "with size estimation (geometry, paper's R_t)": merged(P, {"aspect": {"mode": "likelihood"}}),
        "without size estimation (noise)": merged(P, NOISE), "fixed box": merged(P, {"size": {"mode": "fixed"}}),
        OURS: {}}),
}
# Each departure alone on the paper's pipeline, then on the defaults: synthetic scenes (scene seeds
# 0-2 x tracker seeds 0-2) and otb_crossing (tracker seeds 0-4).
KERNEL, PARTS = {"likelihood": {"kernel": "epanechnikov"}}, {"likelihood": {"parts": 2}}
CV, MS = {"motion": {"model": "constant_velocity"}}, {"refine": {"mode": "meanshift"}}
UPDATE, RW = {"reference": {"update_rate": 0.05}}, {"size": {"no_plane": "random_walk"}}
FG, NO_FG = {"likelihood": {"foreground": 10.0}}, {"likelihood": {"foreground": 0.0}}
REGION, NO_REGION = {"refine": {"mode": "foreground"}}, {"refine": {"mode": "none"}}
NO_HOLD, NO_EXCLUDE = {"hold": {"enabled": False}}, {"reference": {"exclude": 0.0}}
SWITCHES = {
    "paper (before: uniform, fixed reference)": P,
    "paper + Epanechnikov kernel": merged(P, KERNEL),
    "paper + two parts": merged(P, PARTS),
    "paper + constant velocity": merged(P, CV),
    "paper + mean-shift refinement": merged(P, MS),
    "paper + adaptive reference (0.05)": merged(P, UPDATE),
    "paper + scale random walk without a plane": merged(P, RW),
    "paper + foreground cue (10)": merged(P, FG),
    "paper + foreground-region refinement": merged(P, REGION),
    "defaults without the foreground cue": NO_FG,
    "defaults without the region refinement": NO_REGION,
    "defaults without the hold (early background without the tracked box kept)": NO_HOLD,
    "defaults without the early background without the tracked box (hold kept)": NO_EXCLUDE,
    "defaults without either (the previous defaults: kernel + adaptive reference + foreground cue + region refinement)":
        merged(NO_HOLD, NO_EXCLUDE),
    "defaults (kernel + adaptive reference + foreground cue + region refinement + early background without the "
    "tracked box + hold)": {},
    "defaults + two parts": PARTS,
    "defaults + constant velocity": CV,
    "defaults + mean-shift refinement": MS,
    "defaults + scale random walk without a plane": RW,
}


OTB_SEEDS = (0, 1, 2, 3, 4)


def scores(traj: pl.DataFrame, gt: pl.DataFrame) -> tuple[dict, dict]:
    """OTB summary and the per-frame IoU (0 where no position) and centre error (None there)."""
    s, frames = evaluate(traj, gt, gt_id=1)
    frames = frames.filter(pl.col("x").is_not_null() & pl.col("visible").fill_null(True))
    est = frames.select("est_x", "est_y", "est_w", "est_h").to_numpy().astype(np.float64)
    ok = ~np.isnan(est).any(axis=1)
    ious = np.zeros(len(est))
    if ok.any():
        ious[ok] = iou(est[ok], frames.select("x", "y", "w", "h").to_numpy()[ok], centred=True)
    ce = frames["centre_error"].to_list()
    return ({"auc": s.success_auc, "precision20": s.precision_at_20px, "centre_error_mean": s.centre_error_mean,
             "coverage": s.coverage},
            {"frame": frames["frame"].to_list(), "iou": ious.tolist(), "centre_error": ce})


def errors(traj: pl.DataFrame, gt: pl.DataFrame) -> dict:
    """The paper's per-column MAE over the visible frames with a position, and coverage."""
    gt = gt.filter((pl.col("id") == 1) & pl.col("visible"))
    j = gt.join(traj, on="frame", how="left", suffix="_pf")
    placed = j.filter(pl.col("x_pf").is_not_null())
    out = {k: float((placed[f"{k}_pf"] - placed[k]).abs().mean()) if len(placed) else None for k in "xywh"}
    out["coverage"] = len(placed) / len(j)
    return out


def csrt(py: Path, folder: Path, box: tuple[float, float, float, float], first_frame: int, tmp: Path) -> pl.DataFrame:
    """CSRT over the images in ``folder`` (sorted by name, the first one the marked frame) from the
    top-left box ``box``; a trajectory table like the replay's. Centres as ``annotate`` makes them
    (left + w / 2), so CSRT's first box is exactly the colour PF's mark."""
    out = tmp / "csrt.json"
    subprocess.run([str(py), str(HERE.parent / "replay" / "runs" / "csrt_side.py"), str(folder),
                    ",".join(str(v) for v in box), str(out)], check=True)
    boxes = json.loads(out.read_text())["boxes"]
    rows = [{"tracker": "csrt", "track_id": 1, "frame": first_frame + i, "x": b[0] + b[2] / 2 if b else None,
             "y": b[1] + b[3] / 2 if b else None, "w": b[2] if b else None, "h": b[3] if b else None,
             "vx": None, "vy": None, "status": "measured" if b else "lost"} for i, b in enumerate(boxes)]
    return pl.DataFrame(rows, schema_overrides={c: pl.Float64 for c in ("x", "y", "w", "h", "vx", "vy")})


def csrt_on_log(py: Path, log: Path, tmp: Path) -> pl.DataFrame:
    """CSRT on a log's frames from its (first) mark on, started from the marked box."""
    folder = tmp / f"{log.stem}-frames"
    folder.mkdir()
    frames = list(iter_frames(LogReader(log), FrameTopics()))
    mark = min(frames[0].all_hints, key=lambda r: r.frame)
    for f in frames:
        if f.index >= mark.frame:
            cv2.imwrite(str(folder / f"{f.index:06d}.png"), f.image)
    box = (mark.x - mark.w / 2, mark.y - mark.h / 2, mark.w, mark.h)
    return csrt(py, folder, box, mark.frame, tmp)


def mean_of(rows: list[dict]) -> dict:
    keys = rows[0].keys()
    return {k: float(np.mean([r[k] for r in rows if r[k] is not None])) if any(r[k] is not None for r in rows) else None
            for k in keys}


def success_curve(ious: list[float]) -> list[float]:
    a = np.asarray(ious)
    return [float((a > t).mean()) for t in IOU_THRESHOLDS]


def switches(tmp: Path, otb_log: Path, otb_gt: pl.DataFrame) -> dict:
    """AUC / precision@20 / centre error per variant of SWITCHES: each synthetic scene (scene seeds 0-2
    x tracker seeds 0-2, 96 walking frames) and otb_crossing (tracker seeds 0-4)."""
    logs = {}
    for scene in ("colorpf-illumination", "colorpf-background", "colorpf-approach"):
        for seed in (0, 1, 2):
            log = tmp / f"sw-{scene}-{seed}.mcap"
            write_colorpf_scene(log, ColorPfSceneConfig(scene=scene, seed=seed))
            logs[(scene, seed)] = (log, read_groundtruth(LogReader(log)))
    out = {}
    for name, cfg in SWITCHES.items():
        row = {}
        for scene in ("colorpf-illumination", "colorpf-background", "colorpf-approach"):
            rs = [scores(replay(ReplayRequest(log=log, tracker="colorpf", seed=ts, config=cfg)).trajectory, gt)[0]
                  for (sc, _), (log, gt) in sorted(logs.items()) if sc == scene for ts in (0, 1, 2)]
            row[scene] = mean_of(rs)
        rs = [scores(replay(ReplayRequest(log=otb_log, tracker="colorpf", seed=ts, config=cfg)).trajectory, otb_gt)[0]
              for ts in OTB_SEEDS]
        row["otb_crossing"] = {**mean_of(rs), "auc_per_seed": [r["auc"] for r in rs]}
        out[name] = row
        print(name, json.dumps(row), flush=True)
    return out


def plots(results: dict) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    per = results["per_frame"]
    if "otb" in per:
        fig, ax = plt.subplots(1, 2, figsize=(11, 3.8))
        for name, style in (("colorpf", "C0"), ("csrt", "C3")):
            d = per["otb"][name]
            auc = float(np.mean(success_curve(d["iou"])))
            ax[0].plot(IOU_THRESHOLDS, success_curve(d["iou"]), style, label=f"{d['label']} [AUC {auc:.2f}]")
            ce = np.array([np.nan if v is None else v for v in d["centre_error"]], dtype=float)
            ax[1].plot(d["frame"], ce, style, lw=1, label=d["label"])
            lost = np.isnan(ce)
            if lost.any():
                ax[1].plot(np.array(d["frame"])[lost], np.zeros(lost.sum()), style, marker="|", ls="", ms=8,
                           label=f"{d['label']}: no position")
        ax[0].set(xlabel="IoU threshold", ylabel="success rate", title="otb_crossing: success plot", ylim=(0, 1.02))
        ax[1].axhline(20, color="grey", lw=0.8, ls="--")
        ax[1].set(xlabel="frame", ylabel="centre error (px)", title="otb_crossing: centre error per frame")
        ax[0].legend(fontsize=8)
        ax[1].legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(HERE / "colorpf_otb.png", dpi=90)
        plt.close(fig)
    scenes = [k for k in per if k != "otb"]
    fig, ax = plt.subplots(2, len(scenes), figsize=(4.2 * len(scenes), 6.4), squeeze=False)
    for j, scene in enumerate(scenes):
        for name, style in (("colorpf", "C0"), ("csrt", "C3")):
            d = per[scene][name]
            ax[0, j].plot(IOU_THRESHOLDS, success_curve(d["iou"]), style,
                          label=f"{d['label']} [AUC {np.mean(success_curve(d['iou'])):.2f}]")
            ce = np.array([np.nan if v is None else v for v in d["centre_error"]], dtype=float)
            ax[1, j].plot(d["frame"], ce, style, lw=1, label=d["label"])
        ax[0, j].set(xlabel="IoU threshold", ylabel="success rate", title=f"{scene} (seed 0)", ylim=(0, 1.02))
        ax[1, j].set(xlabel="frame", ylabel="centre error (px)")
        ax[0, j].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(HERE / "colorpf_synthetic.png", dpi=80)
    plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--only", choices=("synthetic", "otb", "switches"), help="re-run one part, keep the others from the JSON")
    only = ap.parse_args().only
    path = HERE / "colorpf_results.json"
    results: dict = {"tables": {}, "vs_csrt": {}, "otb": {}, "per_frame": {}, "switches": {}}
    if only and path.exists():
        results = {"switches": {}, **json.loads(path.read_text())}
    py = ensure_venv(DEFAULT_VENV)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for title, (scene, variants) in TABLES.items() if only in (None, "synthetic") else ():
            rows: dict[str, list] = {}
            vs: dict[str, list] = {"colorpf (defaults)": [], "CSRT": []}
            for seed in (0, 1, 2):
                log = tmp / f"{scene}-{seed}.mcap"
                write_colorpf_scene(log, ColorPfSceneConfig(scene=scene, seed=seed))
                gt = read_groundtruth(LogReader(log))
                for name, cfg in variants.items():
                    traj = replay(ReplayRequest(log=log, tracker="colorpf", seed=0, config=cfg)).trajectory
                    rows.setdefault(name, []).append(errors(traj, gt))
                    if cfg is P:
                        vs.setdefault("colorpf (paper)", []).append({**errors(traj, gt), **scores(traj, gt)[0]})
                    if not cfg:
                        summary, frames = scores(traj, gt)
                        vs["colorpf (defaults)"].append({**errors(traj, gt), **summary})
                        if seed == 0:
                            results["per_frame"].setdefault(scene, {})["colorpf"] = {"label": "colour PF", **frames}
                traj = csrt_on_log(py, log, tmp)
                summary, frames = scores(traj, gt)
                rows.setdefault("CSRT (same frames, same marked box)", []).append(errors(traj, gt))
                vs["CSRT"].append({**errors(traj, gt), **summary})
                if seed == 0:
                    results["per_frame"][scene]["csrt"] = {"label": "CSRT", **frames}
            results["tables"][title] = {name: mean_of(rs) for name, rs in rows.items()}
            results["vs_csrt"][scene] = {name: mean_of(rs) for name, rs in vs.items()}
            print(title, json.dumps(results["tables"][title], indent=1))
            print(json.dumps(results["vs_csrt"][scene], indent=1), flush=True)
        if REAL.is_dir() and only in (None, "otb", "switches"):
            log, marked = tmp / "otb.mcap", tmp / "otbm.mcap"
            cli(["record", str(log), "--images", str(REAL / "img"), "--fps", "30", "--groundtruth",
                 str(REAL / "groundtruth_rect.txt"), "--quiet"])
            x, y, w, h = (float(v) for v in (REAL / "groundtruth_rect.txt").read_text().split()[0].split(","))
            cli(["annotate", str(log), "--frame", "0", "--box", f"{x - 1},{y - 1},{w},{h}", "--out", str(marked)])
            gt = read_groundtruth(LogReader(marked))
        if REAL.is_dir() and only in (None, "switches"):
            results["switches"] = switches(tmp, marked, gt)
        if REAL.is_dir() and only in (None, "otb"):
            by_seed = []
            for seed in OTB_SEEDS:
                summary, frames = scores(replay(ReplayRequest(log=marked, tracker="colorpf", seed=seed)).trajectory, gt)
                by_seed.append(summary)
                if seed == 0:
                    results["per_frame"]["otb"] = {"colorpf": {"label": "colour PF (seed 0)", **frames}}
            results["otb"]["colorpf (defaults), seed 0"] = by_seed[0]
            results["otb"][f"colorpf (defaults), mean of seeds {OTB_SEEDS[0]}-{OTB_SEEDS[-1]}"] = mean_of(by_seed)
            results["otb"]["colorpf (defaults), AUC per seed"] = [s["auc"] for s in by_seed]
            paper = [scores(replay(ReplayRequest(log=marked, tracker="colorpf", seed=seed, config=P)).trajectory, gt)[0]
                     for seed in OTB_SEEDS]
            results["otb"][f"colorpf (paper: uniform, fixed reference), mean of seeds {OTB_SEEDS[0]}-{OTB_SEEDS[-1]}"] = \
                mean_of(paper)
            results["otb"]["colorpf (paper), AUC per seed"] = [s["auc"] for s in paper]
            for name, cfg in {"H-S+V": {"likelihood": {"histogram": "hsv"}},
                              "target-only reference": {"reference": {"mode": "target"}}, "size noise": NOISE,
                              "fixed box": {"size": {"mode": "fixed"}},
                              "without the foreground cue": NO_FG,
                              "without the region refinement": NO_REGION,
                              "without the hold and the early background without the tracked box (the previous "
                              "defaults)": merged(NO_HOLD, NO_EXCLUDE)}.items():
                results["otb"][f"{name}, seed 0"], _ = scores(
                    replay(ReplayRequest(log=marked, tracker="colorpf", seed=0, config=cfg)).trajectory, gt)
            summary, frames = scores(csrt(py, REAL / "img", (x - 1, y - 1, w, h), 0, tmp), gt)
            results["otb"]["CSRT (opencv-contrib, own venv)"] = summary
            results["per_frame"]["otb"]["csrt"] = {"label": "CSRT", **frames}
            print(json.dumps(results["otb"], indent=1))
    path.write_text(json.dumps(results, indent=2) + "\n")
    plots(results)


if __name__ == "__main__":
    cv2.setNumThreads(1)
    main()
