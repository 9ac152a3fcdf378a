"""The colour PF's Tables 1-3 as ablations on the synthetic scenes, and otb_crossing against CSRT.

    python docs/colorpf_eval.py            # writes docs/colorpf_results.json (numbers quoted in docs/colorpf.md)

Metric: the paper's mean absolute error of x, y, w, h (px) over the visible frames where the track has
a position, with coverage (share of those frames) beside it. Seeds 0-2, 96 walking frames, 720x480.
otb_crossing: OTB success AUC and precision at 20 px; CSRT in its own venv (benchmarks/bench_colorpf.py).
"""

from __future__ import annotations

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
from trackreplay.recorder.synth.colorpf import ColorPfSceneConfig, write_colorpf_scene  # noqa: E402
from trackreplay.replay.cli import main as cli  # noqa: E402
from trackreplay.replay.engine import ReplayRequest, replay  # noqa: E402
from trackreplay.replay.eval import evaluate  # noqa: E402
from trackreplay.replay.groundtruth import read_groundtruth  # noqa: E402
from trackreplay.replay.reader import LogReader  # noqa: E402

REAL = HERE.parents[1] / "shared" / "data" / "real" / "otb_crossing"
NOISE = {"size": {"mode": "noise"}}
TABLES = {
    "Table 1 (colorpf-illumination)": ("colorpf-illumination", {
        "H-S (proposed), size noise": NOISE, "H-S+V (Pérez), size noise": {**NOISE, "likelihood": {"histogram": "hsv"}},
        "H-S, full (geometry)": {}, "H-S+V, full (geometry)": {"likelihood": {"histogram": "hsv"}}}),
    "Table 2 (colorpf-background)": ("colorpf-background", {
        "mixed reference, size noise": NOISE, "target colours only, size noise": {**NOISE, "reference": {"mode": "target"}},
        "mixed, full (geometry)": {}, "target only, full (geometry)": {"reference": {"mode": "target"}}}),
    "Table 3 (colorpf-approach)": ("colorpf-approach", {
        "with size estimation (geometry, fixed R)": {},
        "with size estimation (geometry, paper's R_t)": {"aspect": {"mode": "likelihood"}},
        "without size estimation (noise)": NOISE, "fixed box": {"size": {"mode": "fixed"}}}),
}


def errors(log: Path, config: dict) -> dict:
    r = replay(ReplayRequest(log=log, tracker="colorpf", seed=0, config=config))
    gt = read_groundtruth(LogReader(log)).filter((pl.col("id") == 1) & pl.col("visible"))
    j = gt.join(r.trajectory, on="frame", how="left", suffix="_pf")
    placed = j.filter(pl.col("x_pf").is_not_null())
    out = {k: float((placed[f"{k}_pf"] - placed[k]).abs().mean()) if len(placed) else None for k in "xywh"}
    out["coverage"] = len(placed) / len(j)
    return out


def main() -> None:
    results: dict = {"tables": {}, "otb": {}}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for title, (scene, variants) in TABLES.items():
            rows = {}
            for seed in (0, 1, 2):
                log = tmp / f"{scene}-{seed}.mcap"
                write_colorpf_scene(log, ColorPfSceneConfig(scene=scene, seed=seed))
                for name, cfg in variants.items():
                    rows.setdefault(name, []).append(errors(log, cfg))
            results["tables"][title] = {
                name: {k: float(np.mean([r[k] for r in rs if r[k] is not None])) if any(r[k] is not None for r in rs) else None
                       for k in ("x", "y", "w", "h", "coverage")} for name, rs in rows.items()}
            print(title, json.dumps(results["tables"][title], indent=1))
        if REAL.is_dir():
            log, marked = tmp / "otb.mcap", tmp / "otbm.mcap"
            cli(["record", str(log), "--images", str(REAL / "img"), "--fps", "30", "--groundtruth",
                 str(REAL / "groundtruth_rect.txt"), "--quiet"])
            x, y, w, h = (float(v) for v in (REAL / "groundtruth_rect.txt").read_text().split()[0].split(","))
            cli(["annotate", str(log), "--frame", "0", "--box", f"{x - 1},{y - 1},{w},{h}", "--out", str(marked)])
            gt = read_groundtruth(LogReader(marked))
            for name, cfg in {"colorpf (defaults)": {}, "H-S+V": {"likelihood": {"histogram": "hsv"}},
                              "target-only reference": {"reference": {"mode": "target"}}, "size noise": NOISE}.items():
                s, _ = evaluate(replay(ReplayRequest(log=marked, tracker="colorpf", seed=0, config=cfg)).trajectory, gt)
                results["otb"][name] = {"auc": s.success_auc, "precision20": s.precision_at_20px, "coverage": s.coverage}
            py = ensure_venv(DEFAULT_VENV)
            out = tmp / "csrt.json"
            subprocess.run([str(py), str(HERE.parent / "benchmarks" / "csrt_side.py"), str(REAL / "img"),
                            f"{x - 1},{y - 1},{w},{h}", str(out)], check=True)
            boxes = json.loads(out.read_text())["boxes"]
            rows = [{"tracker": "csrt", "track_id": 1, "frame": i, "x": b[0] + b[2] / 2 - 0.5 if b else None,
                     "y": b[1] + b[3] / 2 - 0.5 if b else None, "w": b[2] if b else None, "h": b[3] if b else None,
                     "vx": None, "vy": None, "status": "measured" if b else "lost"} for i, b in enumerate(boxes)]
            table = pl.DataFrame(rows, schema_overrides={c: pl.Float64 for c in ("x", "y", "w", "h", "vx", "vy")})
            s, _ = evaluate(table, gt)
            results["otb"]["CSRT (opencv-contrib 5.0)"] = {"auc": s.success_auc, "precision20": s.precision_at_20px,
                                                          "coverage": s.coverage}
            print(json.dumps(results["otb"], indent=1))
    (HERE / "colorpf_results.json").write_text(json.dumps(results, indent=2) + "\n")


if __name__ == "__main__":
    cv2.setNumThreads(1)
    main()
