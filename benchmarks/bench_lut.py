"""Colour-LUT rebuild cost, measured in one run on one machine: the decision over the colour
histogram's support (``appearance.lut.two_class_table``) vs the same arithmetic over the whole
coarse cube (the baseline it replaced), on the counts the golf tracker actually builds.

Replays a synthetic 720p tee shot with the golf tracker, keeps the (foreground, background) counts
of every LUT rebuild, then times both forms on each (interleaved, median of repeats) and checks the
tables are equal. Usage: python benchmarks/bench_lut.py [--repeats 7]
Writes benchmarks/results/lut.json and prints the ratio.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks.machine import describe  # noqa: E402
import trackreplay.trackers.appearance.lut as lut  # noqa: E402
from trackreplay.recorder.synth.golf.scene import GolfSceneConfig, write_golf_teeshot  # noqa: E402
from trackreplay.replay.runs.bench import median_seconds  # noqa: E402
from trackreplay.replay.core.engine import ReplayRequest, iter_steps  # noqa: E402


def whole_cube(foreground, background, *, smooth, foreground_weight, min_count, background_scale=1.0):
    """The baseline: smoothing and decision over the whole coarse cube."""
    fg = lut._smooth3_dense(foreground, smooth)
    bg = lut._smooth3_dense(background, smooth) * background_scale
    return (foreground_weight * fg > bg) & (fg > min_count)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results" / "lut.json")
    args = ap.parse_args()
    builds = []
    original = lut.two_class_table

    def recording(foreground, background, **kw):
        builds.append((foreground.copy(), background.copy(), kw))
        return original(foreground, background, **kw)

    lut.two_class_table = recording
    try:
        with tempfile.TemporaryDirectory() as tmp:
            log = Path(tmp) / "tee.mcap"
            write_golf_teeshot(log, GolfSceneConfig(duration=8.0))
            frames = sum(1 for _ in iter_steps(ReplayRequest(log=log, tracker="golf")))
    finally:
        lut.two_class_table = original
    rows = []
    for fg, bg, kw in builds:
        assert np.array_equal(original(fg, bg, **kw), whole_cube(fg, bg, **kw)), "the two forms disagree"
        t_cube = median_seconds(lambda: whole_cube(fg, bg, **kw), args.repeats)
        t_support = median_seconds(lambda: original(fg, bg, **kw), args.repeats)
        rows.append({"support_ms": 1e3 * t_support, "whole_cube_ms": 1e3 * t_cube,
                     "fg_cells": int(np.count_nonzero(fg)), "bg_cells": int(np.count_nonzero(bg))})
    support = float(np.median([r["support_ms"] for r in rows]))
    cube = float(np.median([r["whole_cube_ms"] for r in rows]))
    result = {"machine": describe(), "frames": frames, "rebuilds": len(rows), "median_support_ms": support,
              "median_whole_cube_ms": cube, "ratio_whole_cube_over_support": cube / support, "builds": rows}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=2))
    print(f"{len(rows)} LUT rebuilds in {frames} frames: {support:.2f} ms over the support vs {cube:.2f} ms over the "
          f"whole cube ({cube / support:.1f}x), tables equal; wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
