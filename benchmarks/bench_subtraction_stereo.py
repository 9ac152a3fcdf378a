"""Subtraction stereo (SGBM on foreground crops) vs full-frame SGBM on the same pairs, in one run.

    python benchmarks/bench_subtraction_stereo.py [--repeats 7] [--out benchmarks/results/subtraction_stereo.json]

Issue 8's target: at 5-20 % foreground, subtraction stereo >= 5x faster than full-frame SGBM and
the same disparity (within 1 px) on >= 98 % of the foreground pixels. Three kinds of pairs:

- ``synthetic``: a textured background plane and textured elliptical "people" at nearer, known
  integer disparities, VGA like the paper's rig, foreground fraction set to 5/10/15/20 %; the mask
  is the true left foreground. Two SGBM settings: the group tracker's (16 disparities, people at
  8-14 px as on the paper's rig) and a wide one (64 disparities, people at 30-50 px).
- ``middlebury``: teddy and cones (450x375, 64 disparities); the foreground is the nearest
  5/10/15/20 % of the pixels by ground-truth disparity (the objects in front), so the disparity
  error of both methods against the ground truth can be measured on it (bad-pixel rate at 1 px,
  mean absolute error) besides their agreement.
- ``groups-scene``: frames of ``trackreplay synth groups-crossing`` with the tracker's own mask
  (background subtraction against the median of the lead-in) and its own settings.

Timed: ``full_disparity`` vs ``subtraction_stereo`` (crop finding + SGBM per crop + masking),
given the same grey images and mask; the background subtraction is not timed (the tracker does it
anyway for KLT). One OpenCV thread, as in a replay. The two are timed interleaved, ``--repeats``
times each; ``full_ms``/``sub_ms``/``speedup`` are medians of the process's CPU time per call
(``speedup_wall`` the same on the wall clock), with the load average before and after (the machine
may be shared). "agree" = of the foreground pixels the full frame gave a disparity, the share where
subtraction stereo gave one within 1 px (a missing value counts against it); "agree_both" = the
same over the pixels where both gave one (``disparity_agreement``). "area_bound_speedup" = frame
pixels / (foreground pixels + the disparity range's columns left of every foreground run in a row):
the ceiling of any crop scheme when SGBM's cost follows the pixels it is run on (measured: ~45-68 ns
per pixel at 16 disparities from 32 px to 640 px wide, 0.08 ms for a 40x40 crop, so per-call
overhead is not what limits). ``hug_sweep``: crops that hug the silhouette (``band_px``) and smaller
margins, on the synthetic pairs.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import cv2
import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))

from benchmarks.machine import describe  # noqa: E402
from trackreplay.trackers.geometry.subtraction_stereo import (  # noqa: E402
    SgbmConfig, disparity_agreement, full_disparity, make_matcher, subtraction_stereo)

MIDDLEBURY = ROOT.parent / "shared" / "data" / "real" / "stereo_middlebury"
FRACTIONS = (0.05, 0.10, 0.15, 0.20)
MARGIN = 8  # the group tracker's stereo.margin_px


def _texture(rng: np.random.Generator, h: int, w: int, blur: float = 1.2) -> np.ndarray:
    t = rng.uniform(0, 255, (h, w)).astype(np.float32)
    t = cv2.GaussianBlur(t, (0, 0), blur)
    t = (t - t.min()) / max(float(np.ptp(t)), 1e-6) * 200 + 28
    return t


def synthetic_pair(fraction: float, rng: np.random.Generator, disparities: tuple[int, int], w: int = 640, h: int = 480,
                   bg_disparity: int = 2, people: int = 3, noise: float = 2.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Left, right (uint8 grey) and the true left foreground mask: ``people`` textured ellipses
    (height 2.5x width) at integer disparities in ``disparities`` over a plane at ``bg_disparity``;
    ellipses sized so that the mask covers ``fraction`` of the frame, placed side by side."""
    dmax = disparities[1] + bg_disparity + 2
    bg = _texture(rng, h, w + dmax)
    left = bg[:, :w].copy()
    right = bg[:, bg_disparity:bg_disparity + w].copy()
    mask = np.zeros((h, w), bool)
    a = np.sqrt(fraction * w * h / people / (2.5 * np.pi))  # semi-axes a (x) and 2.5a (y)
    b = 2.5 * a
    slots = np.linspace(0, w, people + 1)
    for k in range(people):
        d = int(rng.integers(disparities[0], disparities[1] + 1))
        lo, hi = slots[k] + a + d + 2, slots[k + 1] - a - 2
        cx = float(rng.uniform(lo, max(hi, lo + 1)))
        cy = float(rng.uniform(b + 2, h - b - 2)) if h - 2 * b > 4 else h / 2
        tex = _texture(rng, h, w + dmax, blur=1.0)
        yy, xx = np.mgrid[0:h, 0:w]
        inside_l = ((xx - cx) / a) ** 2 + ((yy - cy) / b) ** 2 <= 1.0
        inside_r = ((xx - (cx - d)) / a) ** 2 + ((yy - cy) / b) ** 2 <= 1.0
        left[inside_l] = tex[:, :w][inside_l]
        right[inside_r] = tex[:, d:d + w][inside_r]  # right pixel u sees the object's point at left u + d
        mask |= inside_l
    out = []
    for img in (left, right):
        img = img + noise * rng.standard_normal(img.shape).astype(np.float32)
        out.append(np.clip(np.round(img), 0, 255).astype(np.uint8))
    return out[0], out[1], mask


def middlebury_pair(name: str, fraction: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None:
    """Left, right (grey), foreground = the nearest ``fraction`` of the known pixels, ground truth (px, NaN unknown)."""
    d = MIDDLEBURY / name
    if not (d / "im2.png").is_file():
        return None
    left = cv2.imread(str(d / "im2.png"), cv2.IMREAD_GRAYSCALE)
    right = cv2.imread(str(d / "im6.png"), cv2.IMREAD_GRAYSCALE)
    raw = cv2.imread(str(d / "disp2.png"), cv2.IMREAD_GRAYSCALE)
    gt = np.where(raw > 0, raw.astype(np.float32) / 4.0, np.nan).astype(np.float32)
    known = np.isfinite(gt)
    threshold = np.quantile(gt[known], 1.0 - fraction * raw.size / known.sum())
    mask = known & (gt >= threshold)
    mask = cv2.morphologyEx(mask.astype(np.uint8), cv2.MORPH_OPEN, np.ones((3, 3), np.uint8)).astype(bool)
    return left, right, mask, gt


def groups_scene_pairs(frames: int) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """(left, right, mask) from groups-crossing at 48 fps, the mask as the tracker makes it."""
    from trackreplay.recorder.synth.groups.scene import GroupScene, GroupSceneConfig
    from trackreplay.trackers.foreground.background import MedianBackground, foreground_mask
    from trackreplay.trackers.groups.config import GroupsConfig

    bgc = GroupsConfig().background
    scene = GroupScene(GroupSceneConfig(scene="groups-crossing"))
    model = MedianBackground(bgc.frames)
    for i in range(bgc.frames):
        model.add(scene.render(i)[0])
    bg = model.model()
    out = []
    lead = scene.cfg.lead_in
    for i in np.linspace(lead + 10, scene.frames - 10, frames).astype(int).tolist():
        left, right, _, _ = scene.render(i)
        mask = foreground_mask(left, bg, bgc.threshold, open_px=bgc.open_px)
        out.append((cv2.cvtColor(left, cv2.COLOR_BGR2GRAY), cv2.cvtColor(right, cv2.COLOR_BGR2GRAY), mask))
    return out


def timed(fn) -> tuple[float, float]:
    """(wall, CPU) seconds of one call. With one OpenCV thread the process's CPU time is the work
    itself, much less disturbed than the wall clock by other jobs on a shared machine."""
    w0, c0 = time.perf_counter(), time.process_time()
    fn()
    return time.perf_counter() - w0, time.process_time() - c0


def area_bound(mask: np.ndarray, cfg: SgbmConfig) -> float:
    """The most any crop scheme can gain if SGBM's cost is proportional to the pixels it is run on:
    frame pixels / (foreground pixels + the ``min_disparity + num_disparities`` columns to the left
    of every run of foreground in a row, which a crop must hold for the run's first pixels to be
    matched). No margin, no context rows: a ceiling, not a method."""
    m = mask.astype(np.int8)
    runs = int((np.diff(m, axis=1, prepend=0) == 1).sum())
    return float(mask.size / (mask.sum() + runs * (cfg.min_disparity + cfg.num_disparities)))


def compare(left: np.ndarray, right: np.ndarray, mask: np.ndarray, cfg: SgbmConfig, repeats: int,
            gt: np.ndarray | None = None, margin: int = MARGIN, band_px: int = 0) -> dict:
    matcher = make_matcher(cfg)
    full = full_disparity(left, right, cfg, matcher)
    sub = subtraction_stereo(left, right, mask, cfg, margin=margin, matcher=matcher, band_px=band_px)
    t_full, t_sub = [], []
    for _ in range(repeats):  # interleaved: a burst of load elsewhere hits both
        t_full.append(timed(lambda: full_disparity(left, right, cfg, matcher)))
        t_sub.append(timed(lambda: subtraction_stereo(left, right, mask, cfg, margin=margin, matcher=matcher, band_px=band_px)))
    (wall_full, cpu_full), (wall_sub, cpu_sub) = np.median(t_full, axis=0), np.median(t_sub, axis=0)
    ref = mask & np.isfinite(full)
    agree = float((np.abs(np.nan_to_num(sub.disparity[ref], nan=1e9) - full[ref]) <= 1.0).mean()) if ref.any() else float("nan")
    agree_both, exact, n_both = disparity_agreement(sub.disparity, full, mask, 1.0)
    row = {
        "foreground": round(float(mask.mean()), 4), "crop_area": round(sub.matched_px / mask.size, 4),
        "crops": int(len(sub.crops)), "full_ms": round(1e3 * cpu_full, 3), "sub_ms": round(1e3 * cpu_sub, 3),
        "speedup": round(float(cpu_full / cpu_sub), 2), "speedup_wall": round(float(wall_full / wall_sub), 2),
        "area_bound_speedup": round(area_bound(mask, cfg), 2),
        "agree": round(agree, 4), "agree_both": round(agree_both, 4), "exact_both": round(exact, 4),
        "density_full": round(float(np.isfinite(full[mask]).mean()), 4),
        "density_sub": round(float(np.isfinite(sub.disparity[mask]).mean()), 4),
    }
    if gt is not None:
        for key, d in (("full", full), ("sub", sub.disparity)):
            on = mask & np.isfinite(gt) & np.isfinite(d)
            err = np.abs(d[on] - gt[on])
            row[f"{key}_bad1"] = round(float((err > 1.0).mean()), 4)  # of the pixels it gave a disparity
            row[f"{key}_mae"] = round(float(err.mean()), 3)
            allfg = mask & np.isfinite(gt)  # missing counted as bad (Middlebury's "all" convention, densities differ)
            row[f"{key}_bad1_missing_bad"] = round(float(1.0 - (on.sum() - (err > 1.0).sum()) / allfg.sum()), 4)
    return row


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeats", type=int, default=9)
    ap.add_argument("--seeds", type=int, default=3, help="synthetic pairs per fraction and setting")
    ap.add_argument("--scene-frames", type=int, default=8)
    ap.add_argument("--out", type=Path, default=HERE / "results" / "subtraction_stereo.json")
    args = ap.parse_args()
    cv2.setNumThreads(1)
    load_before = [round(x, 2) for x in os.getloadavg()]
    started = time.perf_counter()
    settings = {
        "tracker_16": (SgbmConfig(), (8, 14)),
        "wide_64": (SgbmConfig(num_disparities=64), (30, 50)),
    }
    synthetic = []
    for name, (cfg, drange) in settings.items():
        for fraction in FRACTIONS:
            rows = [compare(*synthetic_pair(fraction, np.random.default_rng(1000 * s + int(fraction * 100)), drange), cfg,
                            args.repeats) for s in range(args.seeds)]
            med = {k: float(np.median([r[k] for r in rows])) for k in rows[0]}
            synthetic.append({"setting": name, "target_fraction": fraction, "median_over_pairs": med, "pairs": rows})
            print(f"synthetic {name:10s} fg {med['foreground']:.3f} crops {med['crop_area']:.3f} of the frame: "
                  f"full {med['full_ms']:.1f} ms sub {med['sub_ms']:.1f} ms x{med['speedup']:.2f} agree {med['agree']:.4f}")
    middlebury = []
    wide = SgbmConfig(num_disparities=64)
    for name in ("teddy", "cones"):
        for fraction in FRACTIONS:
            pair = middlebury_pair(name, fraction)
            if pair is None:
                continue
            left, right, mask, gt = pair
            r = compare(left, right, mask, wide, args.repeats, gt=gt)
            middlebury.append({"image": name, "target_fraction": fraction, **r})
            print(f"middlebury {name:5s} fg {r['foreground']:.3f} crops {r['crop_area']:.3f}: x{r['speedup']:.2f} "
                  f"agree {r['agree']:.4f}; bad1 full {r['full_bad1']:.4f} sub {r['sub_bad1']:.4f}; "
                  f"mae full {r['full_mae']:.3f} sub {r['sub_mae']:.3f}")
    sweep = []  # margin trades speed for agreement (the subtraction_stereo docstring's promise)
    for fraction in (0.05, 0.20):
        pair = synthetic_pair(fraction, np.random.default_rng(7 + int(fraction * 100)), settings["tracker_16"][1])
        for margin in (0, 4, 8, 16):
            r = compare(*pair, SgbmConfig(), args.repeats, margin=margin)
            sweep.append({"pair": f"synthetic tracker_16 {fraction:.2f}", "margin_px": margin, **r})
        for name in ("teddy", "cones"):
            mb = middlebury_pair(name, fraction)
            for margin in (0, 8, 16) if mb is not None else ():
                r = compare(*mb[:3], wide, args.repeats, gt=mb[3], margin=margin)
                sweep.append({"pair": f"middlebury {name} {fraction:.2f}", "margin_px": margin, **r})
    for r in sweep:
        print(f"margin {r['margin_px']:2d} {r['pair']:28s} crops {r['crop_area']:.3f} x{r['speedup']:.2f} agree {r['agree']:.4f}")
    hug = []  # crops that hug the silhouette (band_px > 0) vs one box per region, on the same pairs
    for fraction in FRACTIONS:
        pairs = [synthetic_pair(fraction, np.random.default_rng(1000 * s + int(fraction * 100)), settings["tracker_16"][1])
                 for s in range(args.seeds)]
        for band, margin in ((0, 8), (0, 4), (0, 0), (32, 8), (32, 4), (32, 0), (16, 0)):
            rows = [compare(*p, SgbmConfig(), args.repeats, margin=margin, band_px=band) for p in pairs]
            med = {k: float(np.median([r[k] for r in rows])) for k in rows[0]}
            hug.append({"setting": "tracker_16", "target_fraction": fraction, "band_px": band, "margin_px": margin,
                        "median_over_pairs": med})
            print(f"hug fg {fraction:.2f} band {band:2d} margin {margin}: crops {med['crop_area']:.3f} ({med['crops']:.0f}) "
                  f"x{med['speedup']:.2f} (area bound x{med['area_bound_speedup']:.2f}) agree {med['agree']:.4f}")
    scene_rows = [compare(l, r, m, SgbmConfig(), args.repeats) for l, r, m in groups_scene_pairs(args.scene_frames)]
    scene = {k: float(np.median([r[k] for r in scene_rows])) for k in scene_rows[0]}
    print(f"groups-crossing (tracker's mask, 16 disparities): fg {scene['foreground']:.3f} x{scene['speedup']:.2f} "
          f"agree {scene['agree']:.4f}")
    results = {
        "machine": {**describe(), "nproc": os.cpu_count(),
                    "note": "shared machine (other developers' tests and benchmarks ran at the same time): medians of "
                            "interleaved repeats; ratios are from one run"},
        "load_average_before": load_before, "load_average_after": [round(x, 2) for x in os.getloadavg()],
        "seconds": round(time.perf_counter() - started, 1), "repeats": args.repeats, "opencv_threads": 1,
        "margin_px": MARGIN, "synthetic": synthetic, "middlebury": middlebury,
        "margin_sweep": sweep, "hug_sweep": hug,
        "groups_crossing": {"median_over_frames": scene, "frames": scene_rows},
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(results, indent=2) + "\n")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
