"""Golf tracker (seed 000) on a real broadcast approach shot, with no encoders and no ground truth.

    python docs/golf_real.py        (needs matplotlib: pip install -e '.[docs]')

Records ../shared/data/real/golf_broadcast_approach/demo.mp4 to MCAP (JPEG) with `trackreplay
record`, marks the ball on four early frames with `trackreplay annotate --from-csv` (the boxes a
user would click), replays the golf tracker with `trackreplay replay` (image coordinates only: the
clip has no encoders) and compares with the hand-checked positions in
docs/data/golf_broadcast_reference.csv; then, as issue 10 measures, the same with one mark per clip
on the approach and on ../shared/data/real/golf_iron_shot_sky/vid1.mp4 (iron shot into the sky,
reference.csv beside it; skipped when absent). Writes docs/golf_real.md, docs/golf_real_error.png (distance
per frame) and docs/golf_real_frames.png (contact sheet). Skips with a message when the clip is
absent. Deterministic: replay seed 0; the pictures come from stepping the same tracker with the
same seed (checked equal to the CLI replay), which also gives the silhouettes drawn in them.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))

import cv2  # noqa: E402
import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import polars as pl  # noqa: E402

from trackreplay.replay.core.engine import ReplayRequest, iter_steps, replay  # noqa: E402
from trackreplay.trackers.golf.config import GolfConfig, ReinitConfig  # noqa: E402

CLIP_DIR = ROOT.parent / "shared" / "data" / "real" / "golf_broadcast_approach"
VIDEO = CLIP_DIR / "demo.mp4"
REFERENCE = HERE / "data" / "golf_broadcast_reference.csv"
# Top-left x, y, width, height of the boxes a user clicks on the ball (label "ball").
MARKS = "frame,x,y,w,h\n12,343,177,6,6\n16,329,179,6,6\n20,313,201,6,6\n30,296,251,6,6\n"
SHEET_FRAMES = (12, 22, 24, 35, 70, 105, 112, 130, 150, 180, 200, 206)
TILE = 220
MAX_PNG_BYTES = 400_000
IRON_DIR = ROOT.parent / "shared" / "data" / "real" / "golf_iron_shot_sky"
# The approach's ball is in view up to frame 216 (rolling over the cup's liner from 208, dropping on
# 216; checked by eye on 2x crops of frames 206-221) and in the hole from 217 on. The reference ends at
# 206, so frames 207-216 count neither way. Versions of this page before 2026-11-27 counted "gone" from
# 208, as if the ball had dropped in then.
HOLED = 217
# One mark per clip, as a user would (issue 10): (key, label, video, reference, marks.csv, first frame with the ball gone).
ONE_MARK = [
    ("approach1", "approach, one mark at 20 (box 312,200,8,8)", VIDEO, REFERENCE, "frame,x,y,w,h\n20,312,200,8,8\n", HOLED),
    ("approach4", "approach, four marks (12, 16, 20, 30)", VIDEO, REFERENCE, MARKS, HOLED),
    # a review's case: one mark at 12 measured pieces of the empty cup liner on 213-219 and 224, up to 31 px off
    ("approach12", "approach, one mark at 12 (box 343,177,6,6)", VIDEO, REFERENCE, "frame,x,y,w,h\n12,343,177,6,6\n", HOLED),
    ("iron1", "iron shot into the sky, one mark at 458 (box 593,1016,22,22)", IRON_DIR / "vid1.mp4", IRON_DIR / "reference.csv",
     "frame,x,y,w,h\n458,593,1016,22,22\n", 612),
    # a review's case: the same clip turned on its side (1280x720), the ball as large as in the 1280-line
    # frame: by the height's scale alone it was lost 2 frames after launch (see TURNED)
    ("iron1turned", "iron shot turned to 1280x720, one mark at 458 (box 242,593,22,22)", IRON_DIR / "vid1.mp4",
     IRON_DIR / "reference.csv", "frame,x,y,w,h\n458,242,593,22,22\n", 612),
]
TURNED = {"iron1turned"}  # recorded from the clip's frames turned 90° clockwise, the reference turned with them
# Earlier versions (numbers as their commits measured them): measured, <=5 px, <=10 px, confident wrong, measured while gone.
PREVIOUS = {
    "approach1": [("before issue 10", 0.744, 0.069, 0.103, 127, "28 of 28"), ("issue 10, first step (67ad786)", 0.903, 1.0, 1.0, 0, "28 of 28")],
    "approach4": [("before issue 10", 0.903, 0.761, 0.949, 5, "27 of 28"), ("issue 10, first step (67ad786)", 0.969, 0.995, 1.0, 0, "20 of 28")],
    "iron1": [("before issue 10", 1.0, 0.333, 0.333, 14, "44 of 44"), ("issue 10, first step (67ad786)", 0.952, 0.300, 0.300, 14, "44 of 44")],
    "iron1turned": [("height scale only (a836b49)", 0.048, 1.0, 1.0, 0, "0 of 44")],
}
CONFIGS = [("re-init + centre (default)", True, "centre"), ("no re-init + centre", False, "centre"),
           ("re-init + stay (paper)", True, "stay"), ("no re-init + stay", False, "stay")]


def cli(*args: str) -> tuple[str, str]:
    """Run ``trackreplay ARGS``; (stdout, stderr)."""
    proc = subprocess.run([sys.executable, "-m", "trackreplay", *args], cwd=ROOT, capture_output=True, text=True,
                          env=dict(os.environ, PYTHONPATH=str(ROOT)))
    if proc.returncode != 0:
        raise SystemExit(f"trackreplay {' '.join(args[:1])} failed: {proc.stderr.strip()}")
    return proc.stdout, proc.stderr


def held_from(ok: np.ndarray, frames: np.ndarray, start: int) -> int:
    """Consecutive reference frames from ``start`` on which ``ok`` holds."""
    run = 0
    for f, good in zip(frames, ok):
        if f < start:
            continue
        if not good:
            break
        run += 1
    return run


def compare(traj: pl.DataFrame, ref: pl.DataFrame) -> pl.DataFrame:
    est = traj.filter(pl.col("track_id") == 1).select("frame", pl.col("x").alias("ex"), pl.col("y").alias("ey"), "status")
    j = ref.join(est, on="frame", how="left").sort("frame")
    return j.with_columns((((pl.col("ex") - pl.col("x")) ** 2 + (pl.col("ey") - pl.col("y")) ** 2).sqrt()).alias("dist"))


def category(status: str | None, d: float | None) -> str:
    if status is None or status == "lost":
        return "lost (no position)"
    if status == "predicted":
        return "predicted"
    return "measured ≤ 5 px" if d <= 5 else ("measured 5-10 px" if d <= 10 else "measured > 10 px")


def segments(j: pl.DataFrame) -> list[tuple[int, int, str, float, float]]:
    """Runs of consecutive reference frames in the same category, with their distance range."""
    out: list[list] = []
    for f, s, d in zip(j["frame"], j["status"], j["dist"]):
        c = category(s, d)
        if out and out[-1][2] == c and out[-1][1] == f - 1:
            out[-1][1] = f
            if d is not None:
                out[-1][3], out[-1][4] = min(out[-1][3], d), max(out[-1][4], d)
        else:
            out.append([f, f, c, d if d is not None else np.inf, d if d is not None else -np.inf])
    return [tuple(x) for x in out]


def step_through(log: Path, ref: pl.DataFrame) -> tuple[dict[int, dict], tuple[str, ...]]:
    """The same run as the CLI (the engine's own loop, same seed), keeping per frame what the
    pictures and the text need: status, re-initialisation, gate targets, particle spread and
    predicted mean, and the blob nearest to the reference centre (area, circularity, gate verdict)."""
    where = {int(r["frame"]): (r["x"], r["y"]) for r in ref.iter_rows(named=True)}
    keep: dict[int, dict] = {}
    steps = iter_steps(ReplayRequest(log=log, tracker="golf", config=GolfConfig()))
    for step in steps:
        frame, states, im = step.frame, step.states, step.intermediates
        gated, search = im.blobs, im.search
        row = {"status": states[0].status if states else None, "reinit": im.reinit.kind, "blobs": len(gated.blobs),
               "target_area": float(gated.targets[0]), "target_circ": float(gated.targets[1]),
               "spread": float(np.max(search.spread)) if np.isfinite(search.spread).all() else np.nan,
               "ball_blob": None, "cloud_off": np.nan, "detector": im.silhouette.lut_name,
               "verdict": im.validation.verdict,
               "x": None if not states else states[0].x, "y": None if not states else states[0].y}
        if frame.index in where and states:
            rx, ry = where[frame.index]
            row["cloud_off"] = float(np.hypot(search.centre[0] - rx, search.centre[1] - ry))
            if len(gated.blobs):
                c = gated.blobs.centroid
                near = int(np.argmin(np.hypot(c[:, 0] - rx, c[:, 1] - ry)))
                if np.hypot(c[near, 0] - rx, c[near, 1] - ry) <= 3:
                    row["ball_blob"] = (float(gated.blobs.area[near]), float(gated.blobs.circularity[near]),
                                        gated.reasons[int(gated.reason[near])])
        if frame.index in SHEET_FRAMES:
            row.update(image=frame.image.copy(), silhouette=im.silhouette.mask.copy(), offset=im.silhouette.offset.copy(),
                       est=None if not states or states[0].x is None else (states[0].x, states[0].y))
        keep[frame.index] = row
    return keep, steps.tracker.luts.names


def contact_sheet(steps: dict[int, dict], j: pl.DataFrame, path: Path) -> tuple[int, int, int]:
    by_frame = {int(r["frame"]): r for r in j.iter_rows(named=True)}
    tiles = []
    for k in SHEET_FRAMES:
        s, r = steps[k], by_frame[k]
        half = int(max(20, 1.6 * max(r["w"], r["h"]) + 8))  # the crop grows with the ball
        cx, cy = int(round(r["x"])), int(round(r["y"]))
        image = s["image"]
        x0, y0 = int(np.clip(cx - half, 0, image.shape[1] - 2 * half)), int(np.clip(cy - half, 0, image.shape[0] - 2 * half))
        crop = image[y0:y0 + 2 * half, x0:x0 + 2 * half].copy()
        # silhouette pixels (what the colour LUT passed) tinted magenta
        sil = np.zeros(crop.shape[:2], bool)
        m, (ox, oy) = s["silhouette"].astype(bool), s["offset"]
        ys, xs = np.nonzero(m)
        xs, ys = xs + ox - x0, ys + oy - y0
        inside = (xs >= 0) & (ys >= 0) & (xs < crop.shape[1]) & (ys < crop.shape[0])
        sil[ys[inside], xs[inside]] = True
        crop[sil] = (0.4 * crop[sil] + 0.6 * np.array([255, 0, 255])).astype(np.uint8)
        scale = TILE / crop.shape[0]
        tile = cv2.resize(crop, (TILE, TILE), interpolation=cv2.INTER_NEAREST)

        def at(x: float, y: float) -> tuple[int, int]:
            return int(round((x - x0 + 0.5) * scale)), int(round((y - y0 + 0.5) * scale))

        radius = max(6, int(round(0.5 * max(r["w"], r["h"]) * scale)) + 4)
        cv2.circle(tile, at(r["x"], r["y"]), radius, (0, 220, 0), 1, cv2.LINE_AA)
        if s["est"] is not None:
            colour = (0, 0, 255) if s["status"] == "measured" else (0, 165, 255)
            ex, ey = at(*s["est"])
            if 0 <= ex < TILE and 0 <= ey < TILE:
                cv2.drawMarker(tile, (ex, ey), colour, cv2.MARKER_CROSS, 16, 2, cv2.LINE_AA)
            else:  # off the crop: an arrow from the centre towards it
                c = np.array([TILE / 2, TILE / 2])
                d = np.array([ex, ey]) - c
                tip = c + d / np.abs(d).max() * (TILE / 2 - 6)
                cv2.arrowedLine(tile, tuple(int(v) for v in c + d / np.linalg.norm(d) * 30), tuple(int(v) for v in tip),
                                colour, 2, cv2.LINE_AA, tipLength=0.2)
        dist = "-" if r["dist"] is None else f"{r['dist']:.1f} px"
        label = f"{k} {s['status'] or 'none'} {dist}"
        cv2.rectangle(tile, (0, 0), (TILE, 20), (30, 30, 30), -1)
        cv2.putText(tile, label, (4, 15), cv2.FONT_HERSHEY_SIMPLEX, 0.45, (255, 255, 255), 1, cv2.LINE_AA)
        cv2.putText(tile, f"x{scale:.1f}", (TILE - 40, TILE - 6), cv2.FONT_HERSHEY_SIMPLEX, 0.4, (255, 255, 255), 1, cv2.LINE_AA)
        tiles.append(cv2.copyMakeBorder(tile, 2, 2, 2, 2, cv2.BORDER_CONSTANT, value=(0, 0, 0)))
    grid = np.vstack([np.hstack(tiles[i:i + 4]) for i in range(0, len(tiles), 4)])
    ok, buf = cv2.imencode(".png", grid, [cv2.IMWRITE_PNG_COMPRESSION, 9])
    if len(buf) > MAX_PNG_BYTES:
        grid = cv2.resize(grid, None, fx=0.75, fy=0.75, interpolation=cv2.INTER_AREA)
        ok, buf = cv2.imencode(".png", grid, [cv2.IMWRITE_PNG_COMPRESSION, 9])
    path.write_bytes(buf.tobytes())
    return grid.shape[1], grid.shape[0], len(buf)


def error_plot(j: pl.DataFrame, path: Path) -> None:
    f = j["frame"].to_numpy()
    d = j["dist"].fill_null(np.nan).to_numpy().astype(float)
    st = j["status"].fill_null("none").to_numpy()
    fig, ax = plt.subplots(figsize=(10, 3.8))
    ax.axvspan(24.5, 40.5, color="0.88", lw=0, label="landing and first hop (by eye)")
    ax.axvspan(206.5, HOLED - 0.5, color="#f3d9a4", lw=0, label=f"ball over the cup, not in the reference (207-{HOLED - 1})")
    ax.axvspan(HOLED - 0.5, f.max() + 0.5, color="#e8c07a", lw=0, label=f"ball in the hole ({HOLED}-)")
    m, p = st == "measured", st == "predicted"
    ax.semilogy(f[m], np.clip(d[m], 0.05, None), ".", ms=4, color="tab:blue", label="measured")
    ax.semilogy(f[p], np.clip(d[p], 0.05, None), "x", ms=4, color="tab:orange", label="predicted")
    lost = (st == "lost") | (st == "none")
    ax.plot(f[lost], np.full(lost.sum(), 300.0), "|", ms=10, color="tab:red", label="lost (no position)")
    ax.plot(f, 0.5 * np.maximum(j["w"].to_numpy(), j["h"].to_numpy()), "-", color="0.4", lw=0.8,
            label="reference ball radius (blob)")
    ax.axhline(5, color="0.5", lw=0.6, ls="--")
    ax.axhline(10, color="0.5", lw=0.6, ls=":")
    ax.set_ylim(0.05, 500)
    ax.set_xlim(10, 211)
    ax.set_xlabel("frame (dashed: 5 px, dotted: 10 px)")
    ax.set_ylabel("distance to reference (px)")
    ax.set_title("Golf tracker on a real broadcast approach shot (no encoders, default config)", fontsize=10)
    ax.legend(fontsize=7, loc="upper left", ncol=3)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def main() -> int:
    if not VIDEO.is_file():
        print(f"{CLIP_DIR} (demo.mp4) is absent: skipping the real-clip evidence", file=sys.stderr)
        return 0
    ref = pl.read_csv(REFERENCE, comment_prefix="#")
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        (tmp / "marks.csv").write_text(MARKS)
        log, marked, traj_path = tmp / "clip.mcap", tmp / "marked.mcap", tmp / "traj.parquet"
        said = "\n".join(cli("record", str(log), "--video", str(VIDEO), "--encoding", "jpeg"))
        said_record = next((line.split("\r")[-1].strip() for line in said.splitlines() if "wrote" in line), "")
        said_record = said_record[said_record.find("wrote"):].replace(str(log), log.name)
        said_annotate = cli("annotate", str(log), "--from-csv", str(tmp / "marks.csv"), "--label", "ball", "--out", str(marked))[0].strip()
        out = "\n".join(cli("replay", str(marked), "--tracker", "golf", "--export", str(traj_path), "--interpolate", "none", "--quiet"))
        notice = next((line.strip() for line in out.splitlines() if line.startswith("trackreplay: golf:")), "(no notice)")
        digest = next((line.split("digest ")[1].strip() for line in out.splitlines() if "digest " in line), "?")
        traj = pl.read_parquet(traj_path)
        j = compare(traj, ref)
        steps, lut_names = step_through(marked, ref)
        same = all(steps[int(f)]["status"] == s for f, s in zip(traj["frame"], traj["status"]))
        if not same:
            raise SystemExit("the step-through differs from the CLI replay")
        variants = []
        for label, reinit, lost in CONFIGS:
            res = replay(ReplayRequest(log=marked, tracker="golf", config=GolfConfig(reinit=ReinitConfig(landing=reinit, lost=lost))))
            variants.append((label, compare(res.trajectory, ref), res.digest))
        sheet = contact_sheet(steps, j, HERE / "golf_real_frames.png")
        one_mark = one_mark_runs(tmp)
    error_plot(j, HERE / "golf_real_error.png")
    write_report(j, steps, variants, notice, digest, said_record, said_annotate, sheet, lut_names, one_mark)
    return 0


def one_mark_runs(tmp: Path) -> list[dict]:
    """Record, mark and replay each clip of ONE_MARK with the CLI (default configuration, seed 0)."""
    out = []
    for key, label, video, reference, marks, gone in ONE_MARK:
        if not video.is_file():
            continue
        (tmp / f"{key}.csv").write_text(marks)
        log, marked, traj_path = tmp / f"{key}.mcap", tmp / f"{key}-marked.mcap", tmp / f"{key}.parquet"
        if key in TURNED:
            reference = turn_clip(video, reference, tmp / key)
            cli("record", str(log), "--images", str(tmp / key), "--fps", str(cv2.VideoCapture(str(video)).get(cv2.CAP_PROP_FPS)))
        elif not log.is_file():
            cli("record", str(log), "--video", str(video), "--encoding", "jpeg")
        cli("annotate", str(log), "--from-csv", str(tmp / f"{key}.csv"), "--label", "ball", "--out", str(marked))
        said = "\n".join(cli("replay", str(marked), "--tracker", "golf", "--export", str(traj_path), "--interpolate", "none", "--quiet"))
        traj = pl.read_parquet(traj_path)
        jj = compare(traj, pl.read_csv(reference, comment_prefix="#"))
        d = jj["dist"].fill_null(np.inf).to_numpy()
        m = (jj["status"] == "measured").fill_null(False).to_numpy()
        after = traj.filter(pl.col("frame") >= gone)
        out.append({"key": key, "label": label, "n": len(d), "measured": m.mean(), "d5": float((d[m] <= 5).mean()) if m.any() else 0.0,
                    "d10": float((d[m] <= 10).mean()) if m.any() else 0.0, "hit5": float((m & (d <= 5)).mean()),
                    "wrong": int((d[m] > 25).sum()), "gone": f"{int((after['status'] == 'measured').sum())} of {after.height}",
                    "gone_from": gone, "missed": jj.filter(~pl.Series(m & (d <= 5)))["frame"].to_list(),
                    "first_mark": min(int(line.split(",")[0]) for line in marks.splitlines()[1:]),
                    "digest": next((ln.split("digest ")[1].strip() for ln in said.splitlines() if "digest " in ln), "?")})
    return out


def turn_clip(video: Path, reference: Path, folder: Path) -> Path:
    """The clip's frames turned 90° clockwise as JPEG files (quality 95) in ``folder``; returns the
    reference turned with them (x' = height - 1 - y, y' = x) as a CSV beside the folder."""
    folder.mkdir(parents=True, exist_ok=True)
    capture, k, height = cv2.VideoCapture(str(video)), 0, 0
    while True:
        ok, image = capture.read()
        if not ok:
            break
        height = image.shape[0]
        cv2.imwrite(str(folder / f"{k:05d}.jpg"), cv2.rotate(image, cv2.ROTATE_90_CLOCKWISE), [cv2.IMWRITE_JPEG_QUALITY, 95])
        k += 1
    turned = folder.parent / f"{folder.name}_reference.csv"
    ref = pl.read_csv(reference, comment_prefix="#")
    ref.select("frame", (height - 1 - pl.col("y")).alias("x"), pl.col("x").alias("y")).write_csv(turned)
    return turned


def fmt_range(j: pl.DataFrame, a: int, b: int) -> str:
    d = j.filter((pl.col("frame") >= a) & (pl.col("frame") <= b))["dist"].drop_nulls().to_numpy()
    if not d.size:
        return "-"
    return f"{d.min():.1f}" if d.max() - d.min() < 0.05 else f"{d.min():.1f}-{d.max():.1f}"


def shares(j: pl.DataFrame) -> tuple[float, float, float, float]:
    n = j.height
    meas = (j["status"] == "measured").fill_null(False).to_numpy()
    d = j["dist"].fill_null(np.inf).to_numpy()
    return (meas & (d <= 5)).sum() / n, (meas & (d <= 10)).sum() / n, meas.sum() / n, (d <= 10).sum() / n


def write_report(j, steps, variants, notice, digest, said_record, said_annotate, sheet, lut_names, one_mark) -> None:
    frames = j["frame"].to_numpy()
    d = j["dist"].fill_null(np.inf).to_numpy()
    meas = (j["status"] == "measured").fill_null(False).to_numpy()
    d5, d10, measured, pos10 = shares(j)
    held5, held10 = held_from(meas & (d <= 5), frames, 12), held_from(meas & (d <= 10), frames, 12)
    any5, any10 = held_from(d <= 5, frames, 12), held_from(d <= 10, frames, 12)
    landing = (frames >= 25) & (frames <= 40)
    roll = (frames >= 41) & (frames <= 206)
    reinits = [(k, s["reinit"]) for k, s in sorted(steps.items()) if s["reinit"] not in ("", "start")]
    L = [
        "# Golf tracker on real clips (broadcast approach shot; iron shot into the sky; no encoders)",
        "",
        "Generated by `python docs/golf_real.py` (from the repository root; about a minute). Main input:",
        "`../shared/data/real/golf_broadcast_approach/demo.mp4` (760×388, 30 fps, 236 frames, TV broadcast:",
        "an approach shot comes down onto the green around frame 25, hops, rolls while the camera zooms in,",
        f"rolls over the cup's liner from frame 208 and drops into the hole on frame {HOLED - 1}). What the script runs, in a temporary folder:",
        "",
        "```",
        "trackreplay record clip.mcap --video demo.mp4 --encoding jpeg",
        "trackreplay annotate clip.mcap --from-csv marks.csv --label ball --out marked.mcap",
        "trackreplay replay marked.mcap --tracker golf --export traj.parquet --interpolate none --quiet",
        "```",
        "",
        f"`record`: {said_record.replace(str(ROOT.parent), '..')}; `annotate`: {said_annotate.split(': ', 1)[-1]}",
        "(`marks.csv`: boxes of 6×6 px at top-left (343,177) on frame 12, (329,179) on 16, (313,201) on 20,",
        "(296,251) on 30). The tracker starts from the first mark (frame 12); all four marks feed the colour",
        f"LUTs (built: {', '.join(lut_names)}; all four boxes are over grass). The log has no encoders and the",
        f"tracker says so once: `{notice}`. Replay digest `{digest}` (seed 0).",
        "",
        "Reference: `docs/data/golf_broadcast_reference.csv`, the ball centre on frames 12-206 from a",
        "nearest-bright-blob follower started by hand and checked by eye every 12th frame (not a",
        "broadcaster's ground truth; on the zoomed-in frames it is the centre of the whole white ball).",
        "",
        "## Numbers (default configuration)",
        "",
        "| measure | value |",
        "|---|---|",
        f"| reference frames | {len(frames)} (12-206) |",
        f"| detection rate: `measured` within 5 px / 10 px of the reference | {100 * d5:.1f} % / {100 * d10:.1f} % |",
        f"| reported `measured` at all | {100 * measured:.1f} % |",
        f"| any position (measured or predicted) within 10 px | {100 * pos10:.1f} % |",
        f"| held from the first mark (frame 12), consecutive frames `measured` within 5 px / 10 px | {held5} / {held10} (frames 12-{12 + held5 - 1}) |",
        f"| ... counting `predicted` positions too | {any5} / {any10} |",
        f"| landing and first hop, frames 25-40: `measured` within 5 px | {(meas & (d <= 5))[landing].sum()} of {landing.sum()} |",
        f"| roll and zoom, frames 41-206: `measured` within 5 px / 10 px | {(meas & (d <= 5))[roll].sum()} / {(meas & (d <= 10))[roll].sum()} of {roll.sum()} |",
        f"| median distance, measured frames | {np.median(d[meas]):.2f} px |",
        f"| re-initialisations after the start | {', '.join(f'frame {k}: {r}' for k, r in reinits) or 'none'} |",
        "",
        "Frame by frame (runs of consecutive reference frames in the same state; distance range in px):",
        "",
        "| frames | state | distance |",
        "|---|---|---|",
    ]
    for a, b, c, lo, hi in segments(j):
        rng = "-" if not np.isfinite(lo) else (f"{lo:.1f}" if abs(hi - lo) < 0.05 else f"{lo:.1f}-{hi:.1f}")
        L.append(f"| {a}{'' if a == b else f'-{b}'} | {c} | {rng} |")
    L += [
        "",
        "![distance to the reference per frame](golf_real_error.png)",
        "",
        f"Contact sheet ({sheet[0]}×{sheet[1]}, {sheet[2] // 1000} KB): crops around the reference (green circle, its",
        "blob size), enlarged by the factor in the corner; red cross = `measured` estimate, orange =",
        "`predicted` (an arrow when it is off the crop); magenta = the pixels the colour LUT (or, where it",
        "found nothing near the prediction, the contrast fallback) passed inside",
        "the search region (the silhouette `I_c`).",
        "",
        "![contact sheet](golf_real_frames.png)",
        "",
        "## Landing re-initialisation and lost search on this clip",
        "",
        "Without encoders the landing re-initialisation is the image-space parabola (`image_parabola`):",
        "after two misses while the ball descends, the particles are re-spread around the parabola's",
        "continuation.",
        "",
        "| config | `measured` ≤5 px | ≤10 px | frames 22-40 `measured` ≤5 px | first `measured` ≤5 px after frame 21 | digest |",
        "|---|---|---|---|---|---|",
    ]
    for label, jj, dig in variants:
        a5, a10, _, _ = shares(jj)
        dd = jj["dist"].fill_null(np.inf).to_numpy()
        mm = (jj["status"] == "measured").fill_null(False).to_numpy()
        win = (frames >= 22) & (frames <= 40)
        after = frames[(frames > 21) & mm & (dd <= 5)]
        L.append(f"| {label} | {100 * a5:.1f} % | {100 * a10:.1f} % | {(mm & (dd <= 5))[win].sum()} of {win.sum()} | "
                 f"{after.min() if after.size else 'never'} | `{dig[:16]}` |")
    L += [
        "",
        "## Issue 10: one mark per clip, as a user would",
        "",
        "Each clip recorded, marked with `annotate --from-csv` and replayed with the CLI (default",
        "configuration, seed 0). *measured* = share of the reference frames reported `measured`; *≤5 / ≤10 px*",
        "= share of those `measured` rows within 5 / 10 px of the reference; *≤5 px of all* = reference frames",
        "`measured` within 5 px (the iron shot's floor: ≥ 95 %); *confident wrong* = `measured` rows more than",
        f"25 px off; *gone* = `measured` rows while the ball is not in view (approach: from frame {HOLED}, ball in",
        "the hole; earlier versions' rows below counted from 208, when the ball was still rolling over the cup;",
        "iron shot: from frame 612, ball above the picture). The iron shot's reference is",
        "`../shared/data/real/golf_iron_shot_sky/reference.csv` (21 frames, 458-606, checked by eye); *turned*:",
        "the same clip's frames turned 90° clockwise (1280x720, JPEG 95) and the reference turned with them, a",
        "ball 19 px across in a 720-line frame (`GolfConfig.reference_ball_px`: the pixel settings scale with",
        "the marked ball when it is larger than the frame's height makes it).",
        "",
        "| clip, marks | version | measured | ≤5 px | ≤10 px | ≤5 px of all | confident wrong | `measured` while gone | reference frames not measured within 5 px |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in one_mark:
        for version, mea, d5, d10, wrong, gone in PREVIOUS.get(r["key"], []):
            L.append(f"| {r['label']} | {version} | {100 * mea:.1f} % | {100 * d5:.1f} % | {100 * d10:.1f} % | – | {wrong} | {gone} | |")
        before = [f for f in r["missed"] if f < r["first_mark"]]
        missed = [f for f in r["missed"] if f >= r["first_mark"]]
        shown = ", ".join(str(f) for f in missed[:12]) + (f" … ({len(missed)} in all)" if len(missed) > 12 else "")
        if before:
            shown = f"{before[0]}-{before[-1]} (before the mark); " + (shown or "none after it")
        L.append(f"| {r['label']} | **this page** (`{r['digest'][:16]}`) | {100 * r['measured']:.1f} % | {100 * r['d5']:.1f} % | "
                 f"{100 * r['d10']:.1f} % | {100 * r['hit5']:.1f} % | {r['wrong']} | {r['gone']} | {shown or 'none'} |")
    det = {}
    for k, st in steps.items():
        if st["status"] == "measured" and 12 <= k <= 206:
            det[st["detector"]] = det.get(st["detector"], 0) + 1
    after = [st["status"] for k, st in steps.items() if k >= HOLED]
    after_measured = [k for k, st in steps.items() if k >= HOLED and st["status"] == "measured"]
    over_cup = [st["status"] for k, st in steps.items() if 207 <= k < HOLED]
    over_cup_measured = [(k, st["x"], st["y"]) for k, st in steps.items() if 207 <= k < HOLED and st["status"] == "measured"]
    L += [
        "",
        "## How it holds the ball, and what is still wrong",
        "",
        f"- **Detectors** (four marks, frames 12-206, `measured` frames by the silhouette that found the ball): "
        + ", ".join(f"{n or '-'} {c}" for n, c in sorted(det.items())) + ". The LUT learned from the marks and,",
        "  through confident measurements, from the track itself (a zooming camera makes the ball several",
        "  times larger than the marked specks); where neither LUT finds the ball near the prediction the",
        "  local-contrast fallback (white top-hat of the luminance) is tried, through the same motion gate",
        "  and confidence.",
        "- **Iron shot into the sky:** at the strike the ball leaves the search region of a cloud that sat",
        "  on a ball at rest; that frame is `predicted` (not measured elsewhere), and since a ball seen lying",
        "  still and then missed was struck, the samples' velocities open up (`particles.launch_velocity_px`)",
        "  and it is measured again on the next frame; from the tree line on, the fading ball against the sky is found by the contrast",
        "  fallback when the sky LUT no longer passes it; once the prediction leaves the top of the picture",
        "  the track goes `predicted`, then `lost`, and with a fixed camera a new track may only start near",
        "  the picture's edge (the golfer's white cap mid-picture is not taken for the ball).",
        f"- **Frames 207-{HOLED - 1} of the approach:** the ball rolls over the cup's white liner (not in the reference);"
        f" the tracker reports {over_cup.count('measured')} of {len(over_cup)} `measured`, {over_cup.count('predicted')}"
        f" `predicted`, {over_cup.count('lost')} `lost` (four marks): ball and liner touch there"
        + (f"; `measured` at {', '.join(f'{k} ({x:.0f}, {y:.0f})' for k, x, y in over_cup_measured)}" if over_cup_measured else "")
        + ". Until 2026-11-27 frame 208 was `measured` at (373, 235), the liner's left part beside the ball"
        " (ball centre about (393, 246) by eye, 23 px away: a wrong row the 25 px threshold does not count);"
        " the ball and the liner, one blob refused for its shape, lay nearer the prediction with the ball's area,"
        " and such a blob now keeps a poorer one from being `measured` (`validate._merged_nearer`).",
        f"- **From frame {HOLED} on the approach** the ball is in the hole; the tracker reports"
        f" {after.count('measured')} of {len(after)} frames `measured` (four marks; with one mark see the table above)"
        + (f": frame(s) {', '.join(map(str, after_measured))}, a round-enough piece of the cup's white liner next to where"
           " the ball was predicted after a few misses (a confident wrong row that this page counts; not solved)." if after_measured else "."),
        "  Before the blob shape was checked against the motion (`blobs.streak_excess`), it followed the ball",
        "  onto the cup's white liner and reported all 28 frames `measured` (confidence up to 0.999): the liner",
        "  is an oval twice as wide as tall, and the roundness gate, which must let motion streaks through,",
        "  passed it. A slow ball cannot smear into an oval 50 px long, so that blob is now `elongated`; the",
        "  frames where the ball touches the liner (one blob of ball and liner) are `predicted`, then `lost`.",
        "",
    ]
    (HERE / "golf_real.md").write_text("\n".join(L))
    print("\n".join(L[26:38]))
    print(f"wrote {HERE / 'golf_real.md'}")


if __name__ == "__main__":
    sys.exit(main())
