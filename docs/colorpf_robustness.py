"""How the colour PF generalises beyond otb_crossing: perturbed copies of the one real clip, each a
condition a hidden clip may have, scored like docs/colorpf_eval.py (OTB success AUC, precision at
20 px, share of frames with a position), the colour PF (defaults, tracker seeds 0-2) beside CSRT.

    python docs/colorpf_robustness.py            # docs/colorpf_robustness.md + docs/colorpf_robustness.json
    python docs/colorpf_robustness.py --only pan_0.5,shake   # some perturbations (JSON/markdown not written)
    python docs/colorpf_robustness.py --config c.json        # colour-PF overrides ([colorpf] table as JSON)

Perturbations (ground truth transformed with the frames; all deterministic, one seeded Generator):

- ``pan_0.5`` / ``pan_0.5_follow``: a 300x200 window sliding 0.5 px/frame across the 360x240 frame,
  against the walker's direction (content moves left with it) / with it (the camera follows);
- ``pan_1.5``: the window back and forth (triangle wave) at 1.5 px/frame;
- ``shake``: the centred 300x200 window jittered by an integer in [-2, 2] px per axis per frame;
- ``zoom``: the window shrinking linearly to 0.7 of the frame (centred), resized back to 360x240;
- ``bright_ramp``: brightness x0.6 -> x1.3 over the sequence; ``bright_step``: x1 then x0.6 from frame 50;
- ``shift+3`` / ``shift-3``: the marked box moved by (+3, +3) / (-3, -3) px; ``scale0.8`` / ``scale1.25``:
  the marked box scaled about its centre (the frames and the truth unchanged);
- ``reversed``: the frames backwards (the walker comes towards the camera, starting off the road);
- ``half_fps``: every other frame (15 fps);
- ``grey``: the frames without colour (many OTB sequences are grey).

Sub-pixel windows are resampled bilinearly (cv2.warpAffine); frames are written as PNG (lossless).
"Confident wrong" counts the colour PF's ``measured`` rows whose centre is more than twice the true
box's diagonal away (summed over the seeds).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import cv2
import numpy as np
import polars as pl

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))

from colorpf_eval import REAL, csrt, scores  # noqa: E402
from benchmarks.bench_colorpf import DEFAULT_VENV, ensure_venv  # noqa: E402
from trackreplay.replay.cli.main import main as cli  # noqa: E402
from trackreplay.replay.core.engine import ReplayRequest, replay  # noqa: E402
from trackreplay.replay.log.groundtruth import read_groundtruth  # noqa: E402
from trackreplay.replay.log.reader import LogReader  # noqa: E402

SEEDS = (0, 1, 2)
W, H = 360, 240  # otb_crossing's frame
CW, CH = 300, 200  # the panning window


def load() -> tuple[list[np.ndarray], np.ndarray]:
    files = sorted((REAL / "img").glob("*.jpg"))
    images = [cv2.imread(str(f)) for f in files]
    gt = np.loadtxt(REAL / "groundtruth_rect.txt", delimiter=",", dtype=np.float64)
    return images, gt


def window(image: np.ndarray, ox: float, oy: float, s: float, size: tuple[int, int]) -> np.ndarray:
    """Output pixel (u, v) = input (ox + u / s, oy + v / s), bilinear."""
    m = np.array([[1.0 / s, 0.0, ox], [0.0, 1.0 / s, oy]])
    return cv2.warpAffine(image, m, size, flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                          borderMode=cv2.BORDER_REFLECT)


def warp(images, gt, offsets: np.ndarray, scales: np.ndarray, size: tuple[int, int]):
    """Each frame through its window; the truth's left/top (and centre) map as (x - o) * s."""
    out = [window(im, ox, oy, s, size) for im, (ox, oy), s in zip(images, offsets, scales)]
    g = gt.copy()
    g[:, 0] = (gt[:, 0] - offsets[:, 0]) * scales
    g[:, 1] = (gt[:, 1] - offsets[:, 1]) * scales
    g[:, 2:] = gt[:, 2:] * scales[:, None]
    return out, g


def perturbations(images, gt) -> dict:
    """name -> (frames, truth (n, 4) OTB x,y,w,h, marked box x,y,w,h (0-based top-left), fps)."""
    rng = np.random.default_rng(20260101)
    n = len(images)
    t = np.arange(n, dtype=np.float64)
    ones = np.ones(n)
    mark = lambda g: (g[0, 0] - 1, g[0, 1] - 1, g[0, 2], g[0, 3])  # as colorpf_eval marks otb_crossing
    out = {"none": (images, gt, mark(gt), 30)}

    def pan(offsets):
        f, g = warp(images, gt, offsets, ones, (CW, CH))
        return f, g, mark(g), 30

    out["pan_0.5"] = pan(np.column_stack([np.minimum(0.5 * t, W - CW), np.full(n, (H - CH) / 2)]))
    out["pan_0.5_follow"] = pan(np.column_stack([np.maximum(W - CW - 0.5 * t, 0), np.full(n, (H - CH) / 2)]))
    tri = (W - CW) - np.abs((1.5 * t) % (2 * (W - CW)) - (W - CW))  # 0 -> 60 -> 0 ... at 1.5 px/frame
    out["pan_1.5"] = pan(np.column_stack([tri, np.full(n, (H - CH) / 2)]))
    jitter = rng.integers(-2, 3, size=(n, 2)).astype(np.float64)
    out["shake"] = pan(np.array([(W - CW) / 2, (H - CH) / 2]) + jitter)
    scale = 1.0 + (1.0 / 0.7 - 1.0) * t / (n - 1)  # the window 1 -> 0.7 of the frame (output px per input px)
    f, g = warp(images, gt, np.column_stack([(W - W / scale) / 2, (H - H / scale) / 2]), scale, (W, H))
    out["zoom"] = (f, g, mark(g), 30)
    for name, gain in (("bright_ramp", 0.6 + 0.7 * t / (n - 1)), ("bright_step", np.where(t < 50, 1.0, 0.6))):
        out[name] = ([cv2.convertScaleAbs(im, alpha=float(a)) for im, a in zip(images, gain)], gt, mark(gt), 30)
    out["bright1.3"] = ([cv2.convertScaleAbs(im, alpha=1.3) for im in images], gt, mark(gt), 30)
    noise = np.random.default_rng(11)
    out["noise"] = ([np.clip(im + noise.normal(0.0, 4.0, im.shape), 0, 255).astype(np.uint8) for im in images], gt, mark(gt), 30)
    out["blur"] = ([cv2.GaussianBlur(im, (0, 0), 1.2) for im in images], gt, mark(gt), 30)
    out["grey"] = ([cv2.cvtColor(cv2.cvtColor(im, cv2.COLOR_BGR2GRAY), cv2.COLOR_GRAY2BGR) for im in images], gt, mark(gt), 30)
    logo = []
    for im in out["grey"][0]:
        im = im.copy()
        im[5:25, 5:50] = (0, 0, 255)  # a red channel logo, 1 % of the frame, far from the walker
        logo.append(im)
    out["grey_logo"] = (logo, gt, mark(gt), 30)
    x, y, w, h = mark(gt)
    for name, box in (("shift+3", (x + 3, y + 3, w, h)), ("shift-3", (x - 3, y - 3, w, h)),
                      ("scale0.8", (x + 0.1 * w, y + 0.1 * h, 0.8 * w, 0.8 * h)),
                      ("scale1.25", (x - 0.125 * w, y - 0.125 * h, 1.25 * w, 1.25 * h))):
        out[name] = (images, gt, box, 30)
    out["reversed"] = (images[::-1], gt[::-1], mark(gt[::-1]), 30)
    out["half_fps"] = (images[::2], gt[::2], mark(gt[::2]), 15)
    # a still 240-px-wide view the walker leaves by its left edge at frame 92 (truth there: a box cut by
    # the edge, then none): the track must go lost, not find him again on the empty road
    left, right = 110, 350
    cut = gt.copy()
    cut[:, 0] -= left
    x0, x1 = np.maximum(cut[:, 0], 0), np.minimum(cut[:, 0] + cut[:, 2], right - left)
    cut[:, 2] = np.where(x1 > x0, x1 - x0, 0.0)
    cut[:, 0] = x0
    cut[cut[:, 2] <= 0] = np.nan  # out of the picture: no truth
    out["leaves_view"] = ([np.ascontiguousarray(im[:, left:right]) for im in images], cut, mark(cut), 30)
    return out


def confident_wrong(traj: pl.DataFrame, gt: pl.DataFrame) -> int:
    """``measured`` rows more than twice the true box's diagonal off, or where the target is not in the picture."""
    j = traj.filter(pl.col("status") == "measured").join(gt.filter(pl.col("id") == 1), on="frame", suffix="_gt", how="left")
    if not len(j):
        return 0
    d = np.hypot(j["x"] - j["x_gt"], j["y"] - j["y_gt"]).to_numpy().astype(float)
    diag = np.hypot(j["w_gt"], j["h_gt"]).to_numpy().astype(float)
    absent = j["x_gt"].is_null().to_numpy() | ~np.isfinite(d)
    return int(((d > 2 * diag) & ~absent).sum() + absent.sum())


def run(name: str, seq, tmp: Path, py: Path, config: dict) -> dict:
    frames, truth, box, fps = seq
    folder = tmp / name / "img"
    folder.mkdir(parents=True)
    for i, im in enumerate(frames):
        cv2.imwrite(str(folder / f"{i:04d}.png"), im)
    gt_file = tmp / name / "groundtruth_rect.txt"
    gt_file.write_text("".join(",".join(f"{v:.2f}" for v in r) + "\n" for r in truth))
    log, marked = tmp / name / "log.mcap", tmp / name / "marked.mcap"
    cli(["record", str(log), "--images", str(folder), "--fps", str(fps), "--groundtruth", str(gt_file), "--quiet"])
    cli(["annotate", str(log), "--frame", "0", "--box", ",".join(f"{v:.2f}" for v in box), "--out", str(marked)])
    gt = read_groundtruth(LogReader(marked))
    rows = []
    for seed in SEEDS:
        traj = replay(ReplayRequest(log=marked, tracker="colorpf", seed=seed, config=config)).trajectory
        s = scores(traj, gt)[0]
        s["confident_wrong"] = confident_wrong(traj, gt)
        s["frames"] = len(frames)
        s["held_or_predicted"] = int((traj["status"] == "predicted").sum())
        rows.append(s)
    pf = {k: float(np.mean([r[k] for r in rows if r[k] is not None])) for k in ("auc", "precision20", "coverage")}
    pf["auc_per_seed"] = [r["auc"] for r in rows]
    pf["precision20_per_seed"] = [r["precision20"] for r in rows]
    pf["confident_wrong"] = sum(r["confident_wrong"] for r in rows)
    pf["predicted_rows"] = [r["held_or_predicted"] for r in rows]
    c = scores(csrt(py, folder, box, 0, tmp / name), gt)[0]
    return {"colorpf": pf, "csrt": {k: c[k] for k in ("auc", "precision20", "coverage")}}


def table(results: dict) -> str:
    base = results["none"]["colorpf"]["auc"]
    lines = ["| perturbation | colour PF AUC (seeds 0-2) | ΔAUC | P@20 | with a position | confident wrong | "
             "CSRT AUC | CSRT P@20 | CSRT with a position |", "|---|---|---|---|---|---|---|---|---|"]
    for name, r in results.items():
        p, c = r["colorpf"], r["csrt"]
        seeds = " / ".join(f"{a:.2f}" for a in p["auc_per_seed"])
        lines.append(f"| {name} | {p['auc']:.3f} ({seeds}) | {p['auc'] - base:+.3f} | {p['precision20']:.2f} | "
                     f"{p['coverage']:.2f} | {p['confident_wrong']} | {c['auc']:.3f} | {c['precision20']:.2f} | "
                     f"{c['coverage']:.2f} |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--only", help="comma-separated perturbations (the outputs are then not written)")
    ap.add_argument("--config", help="colour-PF overrides, a JSON file")
    args = ap.parse_args()
    if not REAL.is_dir():
        sys.exit(f"{REAL} is missing")
    config = json.loads(Path(args.config).read_text()) if args.config else {}
    py = ensure_venv(DEFAULT_VENV)
    seqs = perturbations(*load())
    names = args.only.split(",") if args.only else list(seqs)
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            results[name] = run(name, seqs[name], Path(tmp), py, config)
            print(name, json.dumps(results[name]), flush=True)
    print(table(results) if "none" in results else json.dumps(results, indent=1))
    if args.only or args.config:
        return
    (HERE / "colorpf_robustness.json").write_text(json.dumps(results, indent=2) + "\n")
    md = HERE / "colorpf_robustness.md"  # only the table between the markers is rewritten
    old = md.read_text() if md.exists() else "# Colour PF: robustness\n\n<!-- table -->\n<!-- /table -->\n"
    head, tail = old.split("<!-- table -->")[0], old.split("<!-- /table -->")[1]
    md.write_text(head + "<!-- table -->\n" + table(results) + "\n<!-- /table -->" + tail)


if __name__ == "__main__":
    cv2.setNumThreads(1)
    main()
