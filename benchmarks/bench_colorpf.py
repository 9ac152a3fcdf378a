"""Colour-PF step cost vs N (linear?) and vs OpenCV's CSRT per frame on the same sequence, in one run.

    python benchmarks/bench_colorpf.py [--csrt-venv DIR]

CSRT lives only in opencv-contrib-python-headless, which must never share a venv with our
opencv-python-headless: the CSRT side runs in its own venv (built here on first use:
``python -m venv DIR && DIR/bin/pip install opencv-contrib-python-headless numpy``), fed image files.
Both sides: one OpenCV thread, the tracker's step alone timed (decode excluded). Results with the
machine and its load average (start and end: the machine may be shared) in benchmarks/results/colorpf.json.
The step times by N are the defaults'; N = 40 also for the paper's pipeline and with every switch on.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from benchmarks.machine import describe  # noqa: E402
from trackreplay.replay.log.frames import FrameTopics, iter_frames  # noqa: E402
from trackreplay.trackers.frame import Frame  # noqa: E402
from trackreplay.replay.log.reader import LogReader  # noqa: E402
from trackreplay.replay.core.config import config_from_dict  # noqa: E402
from trackreplay.trackers.colorpf.config import PAPER, ColorPfConfig  # noqa: E402

# N = 40 step time of other pipelines: the paper's, ours without the camera-motion measurement, and every switch of ours on
VARIANTS = {"paper": PAPER, "defaults": {}, "defaults, camera taken as fixed": {"camera": {"compensate": False}},
            "all switches": {"likelihood": {"parts": 2}, "motion": {"model": "constant_velocity"},
                             "refine": {"mode": "meanshift"}, "size": {"no_plane": "random_walk"}}}
from trackreplay.trackers.colorpf.camera import shift_image  # noqa: E402
from trackreplay.trackers.colorpf.tracker import ColorPfTracker  # noqa: E402
from trackreplay.replay.runs.csrt import SIDE as CSRT_SIDE  # noqa: E402  (the CSRT side evaluate runs too)

DEFAULT_VENV = Path.home() / ".cache" / "trackreplay" / "csrt-venv"


def ensure_venv(venv: Path) -> Path:
    py = venv / "bin" / "python"
    if not py.exists():
        subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
        subprocess.run([str(venv / "bin" / "pip"), "install", "-q", "opencv-contrib-python-headless", "numpy"], check=True)
    return py


def colorpf_times(frames, n: int, repeats: int = 3, overrides: dict | None = None) -> np.ndarray:
    """Per-frame step times (s), the median over ``repeats`` passes; ``overrides`` a ``[colorpf]`` dict."""
    runs = []
    config = config_from_dict(ColorPfConfig, {**(overrides or {}), "n_particles": n})
    for _ in range(repeats):
        tracker = ColorPfTracker(config, np.random.default_rng(0))
        t = []
        for f in frames:
            t0 = time.perf_counter()
            tracker.step(f)
            t.append(time.perf_counter() - t0)
        runs.append(t)
    return np.median(np.array(runs), axis=0)


def panned(frame: Frame, dx: float) -> Frame:
    """``frame`` seen by a camera panned ``dx`` px right (its content ``dx`` px left, the edge repeated)."""
    if dx == 0.0:
        return frame
    return dataclasses.replace(frame, image=shift_image(frame.image, np.array([-dx, 0.0])), encoded=None, encoding=None)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("log", type=Path, help="a marked log (e.g. otb_crossing recorded and annotated)")
    ap.add_argument("--csrt-venv", type=Path, default=DEFAULT_VENV)
    ap.add_argument("--out", type=Path, default=HERE / "results" / "colorpf.json")
    ap.add_argument("--pan", type=float, default=0.0,
                    help="px per frame: the camera pans right (content shifted left, edge repeated) from the mark on, "
                         "a moving camera for both sides (results/colorpf_panned.json: --pan 0.5)")
    args = ap.parse_args()
    cv2.setNumThreads(1)
    frames = list(iter_frames(LogReader(args.log), FrameTopics()))
    mark = frames[0].all_hints[0]
    start = [panned(f, args.pan * (f.index - mark.frame)) for f in frames if f.index >= mark.frame]
    result = {"machine": describe(), "log": args.log.name, "pan_px_per_frame": args.pan, "frames": len(start),
              "image": list(start[0].image.shape), "load_average_start": list(os.getloadavg())}
    per_n = {}
    for n in (10, 20, 40, 80, 160, 320):
        t = colorpf_times(start, n)
        per_n[n] = float(np.median(t[1:]) * 1e3)
    result["colorpf_step_ms_by_N"] = per_n
    ns = np.array(sorted(per_n)), np.array([per_n[k] for k in sorted(per_n)])
    slope, intercept = np.polyfit(ns[0], ns[1], 1)
    result["linear_fit_ms"] = {"per_particle": float(slope), "fixed": float(intercept),
                               "max_relative_residual": float(np.max(np.abs(slope * ns[0] + intercept - ns[1]) / ns[1]))}
    result["ratio_320_over_40"] = per_n[320] / per_n[40]
    result["colorpf_step_ms_N40_by_variant"] = {name: float(np.median(colorpf_times(start, 40, overrides=o)[1:]) * 1e3)
                                                for name, o in VARIANTS.items()}
    py = ensure_venv(args.csrt_venv)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for f in start:
            cv2.imwrite(str(folder / f"{f.index:06d}.png"), f.image)
        box = f"{mark.x - mark.w / 2 + 0.5},{mark.y - mark.h / 2 + 0.5},{mark.w},{mark.h}"
        out = folder / "csrt.json"
        subprocess.run([str(py), str(CSRT_SIDE), str(folder), box, str(out)], check=True)
        csrt = json.loads(out.read_text())
    result["csrt_opencv"] = csrt["opencv"]
    result["csrt_step_ms"] = float(np.median(csrt["times"]) * 1e3)
    result["csrt_over_colorpf_N40"] = result["csrt_step_ms"] / per_n[40]
    result["csrt_over_colorpf_N40_by_variant"] = {k: result["csrt_step_ms"] / v
                                                  for k, v in result["colorpf_step_ms_N40_by_variant"].items()}
    result["load_average_end"] = list(os.getloadavg())
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=2) + "\n")
    print(json.dumps({k: v for k, v in result.items() if k != "machine"}, indent=2))


if __name__ == "__main__":
    main()
