"""Per-frame cost of the gradient-flow step (seed 004, on-line form) vs OpenCV's pyramidal LK.

Ours: one warm-started refinement (eq. 25) over the whole window plus the eq. 11 velocity — what
the tracker does per frame. LK: ``cv2.calcOpticalFlowPyrLK`` on the same two windows, (a) at every
pixel of the window (a dense field like ours), (b) on a grid every 4 px; with OpenCV's default
21×21 window and 3 pyramid levels, and (c) at every pixel with a 5×5 window and no pyramid (our
neighbourhood). Windows: the paper's 51×51 FOV and a larger 201×201. One thread for both
(``cv2.setNumThreads(1)``); each time is the median of many repeats, all measured in one run.

Usage: python benchmarks/bench_flow_step.py [--repeats 200]
Writes benchmarks/results/flow_step.json and prints a table.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks.machine import describe  # noqa: E402
from trackreplay.replay.runs.bench import median_seconds  # noqa: E402
from trackreplay.trackers.flow.config import FlowConfig  # noqa: E402
from trackreplay.trackers.flow.refine import online_step  # noqa: E402
from trackreplay.trackers.flow.velocity import histogram_edges, object_velocity  # noqa: E402

LK_CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 30, 0.01)


def scene(size: int, shift: tuple[int, int], seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Two windows of a smooth random background with a bright square that moved by ``shift``."""
    rng = np.random.default_rng(seed)
    k = np.fft.fftfreq(size)
    lowpass = np.exp(-2 * (np.pi * 3.0) ** 2 * (k[:, None] ** 2 + k[None, :] ** 2))
    spec = np.fft.fft2(rng.normal(size=(size, size))) * lowpass
    back = np.real(np.fft.ifft2(spec))
    back = np.round(20 + 160 * (back - back.min()) / np.ptp(back)).astype(np.uint8)
    frames = []
    c = size // 2
    for dx, dy in ((0, 0), shift):
        img = back.copy()
        img[c - 6 + dy : c + 7 + dy, c - 6 + dx : c + 7 + dx] = 200
        frames.append(img)
    return frames[0], frames[1]


def bench_window(size: int, repeats: int) -> list[dict]:
    a8, b8 = scene(size, (2, 1))
    a, b = a8.astype(np.float32), b8.astype(np.float32)
    cfg = FlowConfig(fov=size if size % 2 else size + 1)
    edges = histogram_edges(cfg.hist_range, cfg.hist_bin)
    warm = online_step(a, b, None, cfg, step=0)
    for step in range(1, 4):  # a few frames in, σ has reached its final value
        warm = online_step(a, b, warm, cfg, step=step)

    def ours() -> None:
        object_velocity(online_step(a, b, warm, cfg, step=10), cfg.epsilon, edges)

    ys, xs = np.mgrid[0:size, 0:size]
    every = np.stack([xs.ravel(), ys.ravel()], 1).astype(np.float32).reshape(-1, 1, 2)
    gy, gx = np.mgrid[0:size:4, 0:size:4]
    grid = np.stack([gx.ravel(), gy.ravel()], 1).astype(np.float32).reshape(-1, 1, 2)

    def lk(points: np.ndarray, win: int, levels: int):
        return lambda: cv2.calcOpticalFlowPyrLK(a8, b8, points, None, winSize=(win, win), maxLevel=levels, criteria=LK_CRITERIA)

    t_ours = median_seconds(ours, repeats)
    rows = [{"window": size, "method": "ours: online_step + eq. 11 (5x5 LS, dense)", "points": size * size, "median_ms": t_ours * 1e3}]
    for name, points, win, levels in (
        ("LK 21x21, 3 levels, every pixel", every, 21, 3),
        ("LK 21x21, 3 levels, grid every 4 px", grid, 21, 3),
        ("LK 5x5, no pyramid, every pixel", every, 5, 0),
    ):
        t = median_seconds(lk(points, win, levels), repeats)
        rows.append({"window": size, "method": name, "points": int(points.shape[0]), "median_ms": t * 1e3})
    for row in rows:
        row["ours_over_this"] = t_ours * 1e3 / row["median_ms"]
    return rows


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeats", type=int, default=200, help="repeats for the 51x51 window (201x201 uses a tenth, at least 10)")
    ap.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results" / "flow_step.json")
    args = ap.parse_args()
    cv2.setNumThreads(1)
    rows = bench_window(51, args.repeats) + bench_window(201, max(10, args.repeats // 10))
    machine = describe()
    machine["cv2"] = cv2.__version__
    machine["numpy"] = np.__version__
    result = {
        "benchmark": "flow_step",
        "description": "per-frame gradient-flow step (on-line, eq. 25 + eq. 11) vs cv2.calcOpticalFlowPyrLK, same window",
        "opencv_threads": 1,
        "timing": "median of repeats after one warm-up call; all in one process",
        "machine": machine,
        "results": rows,
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=2) + "\n")
    print(f"{'window':>7}  {'method':<46} {'points':>7} {'median ms':>10} {'ours/this':>9}")
    for r in rows:
        print(f"{r['window']:>7}  {r['method']:<46} {r['points']:>7} {r['median_ms']:>10.3f} {r['ours_over_this']:>9.2f}")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
