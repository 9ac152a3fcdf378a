"""Is the colour PF's "measured" true on real footage? otb_crossing with one mark, as a user would.

    python docs/colorpf_status.py        # writes docs/colorpf_status.md (about 40 s)

Records ``../shared/data/real/otb_crossing`` (image folder + OTB ground truth), marks the first
frame's ground-truth box, replays ``--tracker colorpf`` with the defaults (seed 0) and reports, per
status, how far the rows are from the truth: the share of ``measured`` rows more than 20 px off or
not overlapping the true box at all (IoU 0) is the confident-wrong rate this page exists to show.
The same for the previous defaults (no foreground cue, no neighbour check: ``PREVIOUS``), the
per-frame cues measured on that replay, and the confident-wrong counts over tracker seeds 0-4.
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import polars as pl

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
OTB = ROOT.parent / "shared" / "data" / "real" / "otb_crossing"
sys.path.insert(0, str(ROOT))

from trackreplay.replay.core.engine import ReplayRequest, iter_steps, replay  # noqa: E402
from trackreplay.trackers.colorpf.foreground import neighbour_shares  # noqa: E402
from trackreplay.replay.analysis.eval import evaluate  # noqa: E402
from trackreplay.trackers.colorpf.likelihood import measure  # noqa: E402
from trackreplay.trackers.geometry.box import iou  # noqa: E402
from trackreplay.replay.log.groundtruth import read_groundtruth  # noqa: E402
from trackreplay.replay.log.reader import LogReader  # noqa: E402

FAR_PX = 20.0
# the defaults before issue 7's foreground cue and neighbour check (and before the early background
# without the tracked box and the hold, which came after them)
PREVIOUS = {"likelihood": {"foreground": 0.0}, "neighbour_check": False, "reference": {"exclude": 0.0},
            "hold": {"enabled": False}}
SEEDS = (0, 1, 2, 3, 4)


def cli(*args: str) -> str:
    done = subprocess.run([sys.executable, "-m", "trackreplay", *args], capture_output=True, text=True, check=True)
    return (done.stdout + done.stderr).strip()


def runs(frames: list[int]) -> str:
    out: list[list[int]] = []
    for f in frames:
        if out and f == out[-1][1] + 1:
            out[-1][1] = f
        else:
            out.append([f, f])
    return ", ".join(f"{a}-{b}" if a != b else str(a) for a, b in out) or "none"


def cues(log: Path, config: dict) -> pl.DataFrame:
    """Per frame, the same replay stepped (same seed): the particle spread (px, weighted std of the
    positions, larger axis), the neighbour margin: the estimate box's S minus the best S of the
    eight boxes one box width / half a box height around it, and the neighbour foreground: the
    largest foreground share of the four boxes beside the estimate (left, right, above, below)
    divided by the marked box's (P_detect / P_square); the neighbour check says "predicted" above 1."""
    rows = []
    steps = iter_steps(ReplayRequest(log=log, tracker="colorpf", config=config))
    for step in steps:
        im = step.intermediates
        if im.mode != "track":
            continue
        e, w = im.estimate, im.weights
        mean = w @ im.particles[:, :2]
        spread = float(np.sqrt(w @ (im.particles[:, :2] - mean) ** 2).max())
        offsets = np.array([[dx * e[2], dy * e[3] * 0.5] for dx in (-1, 0, 1) for dy in (-1, 0, 1) if dx or dy])
        around = np.tile(e, (len(offsets), 1))
        around[:, :2] += offsets
        near = measure(steps.tracker.model, step.frame.image, around, steps.tracker.reference.histogram)
        tr = steps.tracker
        fg = float("nan")
        if tr.background_image is not None and tr.reference.p_detect > 0:
            shares = neighbour_shares(step.frame.image, tr.background_image, e, tr.config.reference.threshold,
                                      tr.config.reference.open_px)
            fg = float(shares.max()) / (tr.reference.p_detect / tr.reference.p_square)
        rows.append({"frame": step.frame.index, "spread": spread, "margin": im.estimate_similarity - float(near.similarity.max()),
                     "neighbour_fg": fg})
    return pl.DataFrame(rows)


def status_rows(fr: pl.DataFrame) -> tuple[list[str], pl.DataFrame]:
    """The per-status table's rows and the frames with a position (with their IoU)."""
    fr = fr.filter(pl.col("status").is_not_null()).sort("frame")
    has = fr.filter(pl.col("est_x").is_not_null())
    overlap = iou(has.select("est_x", "est_y", "est_w", "est_h").to_numpy(), has.select("x", "y", "w", "h").to_numpy(), centred=True)
    has = has.with_columns(pl.Series("iou", overlap))
    lines = []
    for status in ("measured", "predicted", "lost"):
        part = has.filter(pl.col("status") == status)
        n = fr.filter(pl.col("status") == status).height
        if not part.height:
            lines.append(f"| {status} | {n} | – | – | – |")
            continue
        err = part["centre_error"].to_numpy()
        lines.append(f"| {status} | {n} | {np.median(err):.1f} | {int((err > FAR_PX).sum())} | {int((part['iou'] <= 0).sum())} |")
    return lines, has


def main() -> int:
    if not OTB.is_dir():
        print(f"skipped: {OTB} is absent")
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        log, marked, traj = Path(tmp) / "c.mcap", Path(tmp) / "m.mcap", Path(tmp) / "t.parquet"
        cli("record", str(log), "--images", str(OTB / "img"), "--fps", "30", "--groundtruth",
            str(OTB / "groundtruth_rect.txt"), "--quiet")
        x, y, w, h = (float(v) for v in (OTB / "groundtruth_rect.txt").read_text().split()[0].split(","))
        cli("annotate", str(log), "--frame", "0", "--box", f"{x - 1},{y - 1},{w},{h}", "--out", str(marked))
        said = cli("replay", str(marked), "--tracker", "colorpf", "--export", str(traj), "--interpolate", "none", "--quiet")
        gt = read_groundtruth(LogReader(marked))
        _, fr = evaluate(pl.read_parquet(traj), gt)
        _, fr_prev = evaluate(replay(ReplayRequest(log=marked, tracker="colorpf", seed=0, config=PREVIOUS)).trajectory, gt)
        cue = cues(marked, PREVIOUS)
        per_seed = {}
        for name, cfg in (("defaults", {}), ("previous defaults", PREVIOUS)):
            counts = []
            for seed in SEEDS:
                _, f = evaluate(replay(ReplayRequest(log=marked, tracker="colorpf", seed=seed, config=cfg)).trajectory, gt)
                m = f.filter(pl.col("status") == "measured")
                counts.append(f"{int((m['centre_error'] > FAR_PX).sum())}/{m.height}")
            per_seed[name] = counts
    table, has = status_rows(fr)
    table_prev, has_prev = status_rows(fr_prev)
    header = ["| status | rows | median centre error px | > 20 px | IoU 0 (no overlap with the true box) |",
              "|---|---|---|---|---|"]
    lines = [
        "# Colour PF: is `measured` true on otb_crossing? (one mark, defaults, seed 0)",
        "",
        "Generated by `python docs/colorpf_status.py`: the clip recorded from its image folder, the first frame's",
        "ground-truth box marked, `trackreplay replay --tracker colorpf` with the default configuration.",
        f"Replay said: `{said.splitlines()[-1]}`.",
        "",
        "**Defaults** (Epanechnikov kernel, adaptive reference, foreground cue, neighbour check, region refinement,",
        "early background without the tracked box, hold on the motion prediction):",
        "",
        *header, *table,
        "",
        "**Previous defaults** (no foreground cue, no neighbour check, plain early median, no hold; same seed):",
        "",
        *header, *table_prev,
    ]
    far = has_prev.filter((pl.col("status") == "measured") & (pl.col("centre_error") > FAR_PX))
    none = has_prev.filter((pl.col("status") == "measured") & (pl.col("iou") <= 0))
    good = has_prev.filter((pl.col("status") == "measured") & (pl.col("centre_error") <= 10)).join(cue, on="frame")
    wrong = far.join(cue, on="frame")
    far_now = has.filter((pl.col("status") == "measured") & (pl.col("centre_error") > FAR_PX))

    def span(df: pl.DataFrame, col: str) -> str:
        v = df[col].drop_nans().to_numpy() if df.height else np.zeros(0)
        return f"{v.min():.2f}-{v.max():.2f} (median {np.median(v):.2f})" if v.size else "–"

    lines += [
        "",
        "`measured` rows more than 20 px off / all `measured` rows, tracker seeds "
        f"{SEEDS[0]}-{SEEDS[-1]}: defaults {', '.join(per_seed['defaults'])}; previous defaults "
        f"{', '.join(per_seed['previous defaults'])}.",
        "",
        "Per-frame cues on the previous defaults' `measured` rows (seed 0):",
        "",
        "| `measured` rows (previous defaults) | particle spread px | neighbour margin (S of the box − best S of "
        "the 8 boxes around it) | neighbour foreground (largest share of the 4 boxes beside it / the mark's share) |",
        "|---|---|---|---|",
        f"| within 10 px ({good.height}) | {span(good, 'spread')} | {span(good, 'margin')} | {span(good, 'neighbour_fg')} |",
        f"| more than {FAR_PX:.0f} px off ({wrong.height}) | {span(wrong, 'spread')} | {span(wrong, 'margin')} | "
        f"{span(wrong, 'neighbour_fg')} |",
        "",
        f"Previous defaults: `measured` rows more than {FAR_PX:.0f} px from the truth: frames {runs(far['frame'].to_list())}; "
        f"with no overlap at all: frames {runs(none['frame'].to_list())}. Defaults: frames "
        f"{runs(far_now['frame'].to_list())}.",
        "",
        "**What this shows.** While a dark car passes behind the walker (frames ~28-48) the box slides up and",
        "left onto the car, whose H-S colours the walker's dark clothes share: the colour likelihood scores it",
        "as well as the walker, and neither colour cue above (particle spread, neighbour margin) separates",
        "those frames from the good ones. The car is, however, a moving region much larger than the walker:",
        "a box of the target's size beside the estimate holds more foreground (against eq. (7)'s background)",
        f"than the marked box did (ratio {span(wrong, 'neighbour_fg')} on the wrong rows above, at most "
        f"{np.nanmax(good['neighbour_fg'].to_numpy()) if good.height else float('nan'):.2f} on those within 10 px:",
        "a thin margin on that side, in a clear gap at 1). The neighbour check",
        "(`ColorPfConfig.neighbour_check`, default) reports such rows `predicted`: the colour match does not",
        "vouch for the position there. The foreground cue in the likelihood (`likelihood.foreground`) pulls",
        "the box back sooner but does not keep it off the car (the car is foreground too), so the",
        "position is still wrong on those frames; they are now said to be unsure. Both need a static",
        "camera (as eq. (7) does) and are off until a background exists. On the same condition the hold",
        "(`hold.enabled`, default) keeps the estimate on the motion prediction (the last estimate plus the",
        "track's velocity) instead of the colour's; with the early background left without the tracked box",
        "(`reference.exclude`, default) the background exists by frame 24, before the car arrives, and the box",
        "stays within ~11 px of the walker through the car frames (docs/colorpf.md).",
        "",
    ]
    (HERE / "colorpf_status.md").write_text("\n".join(lines))
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
