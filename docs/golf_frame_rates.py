"""Golf tracker (seed 000) on synthetic tee shots at 30-240 fps: what is `measured` off the ball?

    python docs/golf_frame_rates.py [--workdir DIR]     (about 4 minutes)

A high-speed camera sees the far ball as a 1-3 px speck among cloud puffs for many more frames than
a 30 fps one. Each shot is the test suite's 640x360 tee shot (the operator zoomed as at 720p, seeds
0-3), cut at 3 s (launch, climb, loss over the top of the picture, descent into view), at 30, 60,
120 and 240 fps, plus the default 720p shot at 240 fps cut at 1 s and 2 s. Every log is replayed
with the default configuration (seed 0) and with each of three guards turned off, so each guard's
part is measured on the same logs:

- ``lut.other_min_share = 0``: the other LUT tried on a miss wherever, even over a background it
  never saw (the ground LUT over open sky passes cloud puffs);
- ``validate.confirm_max_nearer = 0``: a track confirmed after a loss whatever its blobs' size
  says about its range against the 3-D filter's;
- ``particles.strike_min_area_px = 0``: a speck seen still and then missed opens a strike's wide
  search.

Reported per run: visible frames measured within 5 px (the issue's detection rate), `measured` rows
more than 10 px from the ball or while it is not in view (confident wrong), and the worst of those.
Writes docs/golf_frame_rates.md and docs/golf_frame_rates.json. Deterministic.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))

import polars as pl  # noqa: E402

from trackreplay.recorder.synth.golf.flight import Launch  # noqa: E402
from trackreplay.recorder.synth.golf.operator import OperatorConfig  # noqa: E402
from trackreplay.recorder.synth.golf.scene import GolfSceneConfig, write_golf_teeshot  # noqa: E402
from trackreplay.replay.core.engine import ReplayRequest, iter_steps  # noqa: E402
from trackreplay.replay.log.groundtruth import read_groundtruth  # noqa: E402
from trackreplay.replay.log.reader import LogReader  # noqa: E402

SMALL = dict(  # tests/trackers/golf/test_golf_scene.py's SHOT
    width=640, height=360,
    launch=Launch(speed=32.0, elevation=24.0, azimuth=0.0, backspin_rpm=7000.0),
    operator=OperatorConfig(size_tee_px=20.0, size_launch_px=7.0, size_landing_px=14.0, size_ground_px=16.0),
)
SHOTS = {f"640x360 {fps} fps seed {seed}": dict(SMALL, seed=seed, fps=float(fps), duration=3.0)
         for fps in (30, 60, 120, 240) for seed in range(4)}
SHOTS |= {f"720p 240 fps {d:g} s": dict(fps=240.0, duration=d) for d in (1.0, 2.0)}
CONFIGS = {
    "default": None,
    "other LUT anywhere": {"lut": {"other_min_share": 0.0}},
    "no range check": {"validate": {"confirm_max_nearer": 0.0}},
    "specks struck": {"particles": {"strike_min_area_px": 0.0}},
    "all three off (before)": {"lut": {"other_min_share": 0.0}, "validate": {"confirm_max_nearer": 0.0},
                               "particles": {"strike_min_area_px": 0.0}},
}
WRONG_PX = 10.0


def evaluate(log: Path, config: dict | None) -> dict:
    truth = {r["frame"]: r for r in read_groundtruth(LogReader(log)).filter(pl.col("id") == 1).iter_rows(named=True)}
    visible = within = 0
    wrong: list[float] = []
    for step in iter_steps(ReplayRequest(log=log, tracker="golf", config=config, seed=0)):
        t, s = truth[step.frame.index], step.states[0]
        seen = bool(t["visible"]) and t["x"] is not None
        visible += seen
        if s.status != "measured":
            continue
        error = math.hypot(s.x - t["x"], s.y - t["y"]) if t["x"] is not None else math.inf
        within += seen and error <= 5.0
        if error > WRONG_PX or not seen:
            wrong.append(error)
    return {"visible": visible, "within_5px": within / max(visible, 1), "wrong": len(wrong),
            "worst_px": max(wrong) if wrong else None}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workdir", type=Path, help="keep the logs here (default: a temporary folder)")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        work = args.workdir or Path(tmp)
        work.mkdir(parents=True, exist_ok=True)
        rows = []
        for name, shot in SHOTS.items():
            log = work / (name.replace(" ", "_") + ".mcap")
            if not log.exists():
                write_golf_teeshot(log, GolfSceneConfig(**shot))
            for cfg_name, cfg in CONFIGS.items():
                rows.append({"shot": name, "config": cfg_name, **evaluate(log, cfg)})
                r = rows[-1]
                print(f"{name:26s} {cfg_name:20s} within 5 px {r['within_5px']:6.1%}  wrong {r['wrong']:3d}", flush=True)
    (HERE / "golf_frame_rates.json").write_text(json.dumps(rows, indent=1) + "\n")
    write_page(rows)


def write_page(rows: list[dict]) -> None:
    by = {(r["shot"], r["config"]): r for r in rows}
    names = list(CONFIGS)
    lines = [
        "# Golf tracker at 30-240 fps: what is `measured` off the ball",
        "",
        "> Stays a script, not a `trackreplay evaluate` manifest (docs/README.md): `golf_frame_rates.py`: each of three "
        "guards turned off in turn on the same logs, a configuration ablation `evaluate` does not express (it replays "
        "every tracker with its defaults).",
        "",
        "Written by `python docs/golf_frame_rates.py` (deterministic; see its docstring for the shots). Each cell:",
        f"visible frames `measured` within 5 px / `measured` rows more than {WRONG_PX:g} px off the ball or while it is",
        "out of view (worst, px). *default* is the tracker as shipped; each other column turns one guard off.",
        "",
        "| shot | " + " | ".join(names) + " |",
        "|---|" + "---|" * len(names),
    ]
    for shot in SHOTS:
        cells = []
        for c in names:
            r = by[(shot, c)]
            cells.append(f"{r['within_5px']:.1%} / {r['wrong']}{worst_text(r['worst_px'])}")
        lines.append(f"| {shot} | " + " | ".join(cells) + " |")
    before = names[-1]
    worse = [s for s in SHOTS if by[(s, "default")]["within_5px"] < by[(s, before)]["within_5px"] - 0.01]
    total = {c: sum(by[(s, c)]["wrong"] for s in SHOTS) for c in names}
    mean = {c: sum(by[(s, c)]["within_5px"] for s in SHOTS) / len(SHOTS) for c in names}
    lines += [
        "| **all shots** | " + " | ".join(f"{mean[c]:.1%} mean / **{total[c]}**" for c in names) + " |",
        "",
        "What each guard is (all three are in `trackers/golf`; the tests that fail without them are named in",
        "`tests/trackers/golf/test_golf_scene.py` and `test_golf_honest.py`):",
        "",
        "- **other LUT only over its own background** (`lut.other_min_share`, 0.05): on a miss the other LUT is",
        "  tried only where its background is at least 5 % of the search region. The ground LUT, learned at",
        "  the tee, has never seen a cloud: over open sky it passes cloud puffs as ball, and a 1-3 px ball",
        "  among them was `measured` on puffs 15-40 px away.",
        "- **range check on a confirmation** (`validate.confirm_max_nearer`, 2): with encoders and the 3-D",
        "  filter running, a track confirmed after a loss whose blobs would put the ball more than twice as",
        "  near as the filter's range (less 3 sigma) is refused (verdict `too_near`). At 240 fps the ball",
        "  leaves the top of the 720p picture; a 96-133 px cloud puff sliding with the tilting camera was",
        "  confirmed, then followed for 26 frames ~200 px off the ball.",
        "- **no strike search for a speck** (`particles.strike_min_area_px`, 4): a ball seen still and then",
        "  missed is taken as struck and its samples' velocities open up; not for a target under 4 px. A far",
        "  ball rolling along the line of sight looks still, and the wide search then took 1-6 px specks",
        "  25-45 px off the 1 px ball for it.",
        "",
        "Since `blobs.complete_streak` (2026-11-28: a blob that is the bright end of a faint streak is measured",
        "at the whole streak's centre) the 720p 240 fps shots no longer lose the ball where the range check and",
        "the speck rule were needed: with either off they now read 0 wrong rows (before: 26, 227 px worst, and",
        "13, 81 px). The guards stay for the cases they were built on; their tests replay the 240 fps scene",
        "without the streak completion (`test_golf_scene.py`) or use crafted frames (`test_golf_honest.py`).",
        "",
        "The price, where the default finds fewer frames than with all three off: "
        + ("; ".join(f"{s}: {by[(s, 'default')]['within_5px']:.1%} (was {by[(s, before)]['within_5px']:.1%}, "
                     f"{by[(s, before)]['wrong']} wrong rows)" for s in worse) if worse else "none") + ".",
        "A ball that the wide search found again only after measuring specks or puffs is now `lost` until",
        "a confirmation or a mark instead.",
        "",
    ]
    (HERE / "golf_frame_rates.md").write_text("\n".join(lines))


def worst_text(worst: float | None) -> str:
    if worst is None:
        return ""
    return " (out of view)" if math.isinf(worst) else f" ({worst:.0f})"


if __name__ == "__main__":
    main()
