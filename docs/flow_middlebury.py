"""Dense-flow accuracy of the gradient method (seed 004) on Middlebury Dimetrodon, vs pyramidal LK.

Runs our offline refinement (eq. 7–10 with coarse-to-fine smoothing) on the full grey frame10 →
frame11, and OpenCV's ``calcOpticalFlowPyrLK`` on a grid of points every 4 px, in one process,
and compares end-point errors against ``flow10.flo``. Writes ``flow_middlebury.md`` and
``flow_middlebury.png`` beside this script.

    PYTHONPATH=. python docs/flow_middlebury.py [--data DIR] [--repeats N]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import cv2
import numpy as np

from trackreplay.trackers.flow.config import FlowConfig
from trackreplay.trackers.flow.refine import refine_flow

DEFAULT_DATA = Path("/work/shared/data/real/flow_middlebury/Dimetrodon")
HERE = Path(__file__).resolve().parent
GRID = 4
LK_WINDOW = 21  # OpenCV's default window
LK_LEVELS = 3
OURS = {
    "ours, paper (single scale, 5×5, σ 2→0)": FlowConfig(online=False),
    "ours + Gaussian pyramid (3 levels, 7×7)": FlowConfig(online=False, pyramid_levels=3, neighbourhood=7),
}


def read_flo(path: Path) -> np.ndarray:
    """Middlebury .flo: float32 magic 202021.25, int32 width, height, then (u, v) interleaved."""
    data = path.read_bytes()
    if np.frombuffer(data[:4], np.float32)[0] != np.float32(202021.25):
        raise ValueError(f"{path} is not a .flo file (bad magic number)")
    w, h = (int(v) for v in np.frombuffer(data[4:12], np.int32))
    return np.frombuffer(data[12 : 12 + 8 * w * h], np.float32).reshape(h, w, 2)


def timed(fn, repeats: int):
    times, out = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return out, float(np.median(times))


def epe_stats(epe: np.ndarray) -> tuple[int, float, float, float]:
    return int(epe.size), float(epe.mean()), float(np.median(epe)), float(np.sqrt(np.mean(epe**2)))


def flow_colour(u: np.ndarray, v: np.ndarray, max_mag: float) -> np.ndarray:
    """Hue = direction, brightness = speed (saturating at ``max_mag``); black where unknown."""
    ok = np.isfinite(u) & np.isfinite(v)
    uu, vv = np.where(ok, u, 0), np.where(ok, v, 0)
    hsv = np.zeros(u.shape + (3,), np.uint8)
    hsv[..., 0] = ((np.degrees(np.arctan2(vv, uu)) % 360) / 2).astype(np.uint8)
    hsv[..., 1] = 255
    hsv[..., 2] = np.where(ok, np.clip(np.hypot(uu, vv) / max_mag, 0, 1) * 255, 0).astype(np.uint8)
    return cv2.cvtColor(hsv, cv2.COLOR_HSV2RGB)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=DEFAULT_DATA, help="folder with frame10.png, frame11.png, flow10.flo")
    parser.add_argument("--repeats", type=int, default=5, help="timing repeats (median reported)")
    args = parser.parse_args(argv)
    needed = [args.data / n for n in ("frame10.png", "frame11.png", "flow10.flo")]
    missing = [str(p) for p in needed if not p.exists()]
    if missing:
        print(f"flow_middlebury: data not found ({', '.join(missing)}); nothing to do.")
        return 0
    cv2.setNumThreads(1)
    a8 = cv2.imread(str(needed[0]), cv2.IMREAD_GRAYSCALE)
    b8 = cv2.imread(str(needed[1]), cv2.IMREAD_GRAYSCALE)
    gt = read_flo(needed[2])
    known = np.all(np.abs(gt) < 1e9, axis=2)
    a, b = a8.astype(np.float32), b8.astype(np.float32)
    h, w = a.shape

    dense = {}
    for name, cfg in OURS.items():
        flow, seconds = timed(lambda cfg=cfg: refine_flow(a, b, cfg), args.repeats)
        dense[name] = (flow, seconds)

    ys, xs = np.mgrid[GRID : h - GRID : GRID, GRID : w - GRID : GRID]
    pts = np.stack([xs.ravel(), ys.ravel()], axis=1).astype(np.float32)
    criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 30, 0.01)
    def lk_run():
        return cv2.calcOpticalFlowPyrLK(
            a8, b8, pts.reshape(-1, 1, 2), None, winSize=(LK_WINDOW, LK_WINDOW), maxLevel=LK_LEVELS, criteria=criteria
        )

    (p1, status, _), lk_seconds = timed(lk_run, args.repeats)
    lk = p1.reshape(-1, 2) - pts
    xi, yi = xs.ravel(), ys.ravel()
    common = status.ravel().astype(bool) & known[yi, xi]
    for flow, _ in dense.values():
        common &= flow.valid[yi, xi]
    gt_pts = gt[yi, xi]

    lk_err = np.hypot(*(lk[common] - gt_pts[common]).T)
    rows = [("OpenCV calcOpticalFlowPyrLK (21×21, 3 levels)", "grid", *epe_stats(lk_err), lk_seconds, "sparse: grid points only")]
    for name, (flow, seconds) in dense.items():
        err = np.hypot(flow.u[yi, xi] - gt_pts[:, 0], flow.v[yi, xi] - gt_pts[:, 1])
        rows.append((name, "grid", *epe_stats(err[common]), seconds, "dense field, sampled at the grid"))
    epe_maps = {}
    for name, (flow, seconds) in dense.items():
        ok = flow.valid & known
        epe = np.hypot(flow.u - gt[..., 0], flow.v - gt[..., 1])
        epe_maps[name] = np.where(ok, epe, np.nan)
        rows.append((name, "all valid", *epe_stats(epe[ok]), seconds, f"density {ok.sum() / known.sum():.1%} of known pixels"))

    mag = np.hypot(gt[..., 0], gt[..., 1])[known]
    lines = [
        "# Dense flow on Middlebury Dimetrodon (frame10 → frame11, grey)",
        "",
        f"Generated by `docs/flow_middlebury.py` in one run; runtimes are medians of {args.repeats} repeats on one thread",
        f"(`cv2.setNumThreads(1)`). Ground-truth motion: median {np.median(mag):.2f} px, 99th percentile {np.percentile(mag, 99):.2f} px,",
        f"max {mag.max():.2f} px. Image {w}×{h}.",
        "",
        "| method | points | n | mean EPE | median EPE | RMS EPE | runtime (s) | note |",
        "|---|---|---:|---:|---:|---:|---:|---|",
    ]
    for name, where, n, mean, med, rms, sec, note in rows:
        lines.append(f"| {name} | {where} | {n} | {mean:.3f} | {med:.3f} | {rms:.3f} | {sec:.3f} | {note} |")
    lines += [
        "",
        f"\"grid\" = every {GRID} px where LK converged (status 1), the ground truth is known and both of our",
        "configurations accepted the pixel (cond(G) ≤ cond_max and enough gradient energy), so the grid rows",
        "compare the same points. \"all valid\" = every pixel our method accepted.",
        "",
        "How to read it:",
        "",
        "- LK is **pyramidal** (3 levels) with a 21×21 window; ours in the paper's form is **single scale** with a",
        "  5×5 least-squares neighbourhood and a coarse-to-fine *blur* schedule (σ = 2, 1, 0.5, 0). Blurring",
        "  extends the linear range of eq. 3 by about σ, so motions of several pixels still bias it; the small",
        "  5×5 neighbourhood also makes each estimate noisier than LK's 441-pixel window.",
        "- `pyramid_levels` (not in the paper) runs the same refinement on a Gaussian pyramid first; with a 7×7",
        "  neighbourhood it roughly halves our error here. The tracker keeps the paper's single-scale default:",
        "  its FOV is background-compensated, so the target's residual motion per frame is small.",
        "- LK is timed on the grid points only (sparse); ours computes a dense field over every pixel.",
        "- Pixels we reject (eq. 8's condition number or the gradient-energy floor; white in the EPE maps) lie",
        "  in low-texture areas, where LK still answers from its larger window.",
    ]
    (HERE / "flow_middlebury.md").write_text("\n".join(lines) + "\n")

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 3, figsize=(15, 8))
    vmax = float(np.percentile(mag, 99))
    gt_show = np.where(known[..., None], gt, np.nan)
    axes[0, 0].imshow(flow_colour(gt_show[..., 0], gt_show[..., 1], vmax))
    axes[0, 0].set_title("ground truth (hue = direction)")
    for ax, (name, (flow, _)) in zip(axes[0, 1:], dense.items()):
        ax.imshow(flow_colour(flow.u, flow.v, vmax))
        ax.set_title(name, fontsize=9)
    for ax in axes[0]:
        ax.axis("off")
    for ax, (name, epe) in zip(axes[1, :2], epe_maps.items()):
        im = ax.imshow(epe, vmin=0, vmax=1.5, cmap="magma")
        ax.set_title(f"EPE: {name}", fontsize=9)
        ax.axis("off")
        fig.colorbar(im, ax=ax, fraction=0.03)
    bins = np.linspace(0, 2, 41)
    axes[1, 2].hist(np.clip(lk_err, 0, 2), bins, histtype="step", label="LK pyramidal (grid)")
    for name, (flow, _) in dense.items():
        err = np.hypot(flow.u[yi, xi] - gt_pts[:, 0], flow.v[yi, xi] - gt_pts[:, 1])[common]
        axes[1, 2].hist(np.clip(err, 0, 2), bins, histtype="step", label=name.split(" (")[0] + " (grid)")
    axes[1, 2].set_xlabel("end-point error, px (last bin: ≥ 2)")
    axes[1, 2].set_ylabel("points")
    axes[1, 2].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(HERE / "flow_middlebury.png", dpi=80)
    print("\n".join(lines[6 : 8 + len(rows)]))
    print(f"wrote {HERE / 'flow_middlebury.md'} and {HERE / 'flow_middlebury.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
