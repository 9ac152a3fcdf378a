"""Golf tracker (seed 000) on a real broadcast approach shot, with no encoders and no ground truth.

    python docs/golf_real.py        (needs matplotlib: pip install -e '.[docs]')

Records ../shared/data/real/golf_broadcast_approach/demo.mp4 to MCAP, marks the ball on four early
frames with `annotate` (what a user would click), replays the golf tracker (image coordinates
only) and compares with the hand-checked positions in docs/data/golf_broadcast_reference.csv.
Writes docs/golf_real.md, docs/golf_real_error.png and docs/golf_real_frames.jpg.
"""

from __future__ import annotations

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

from replay.frames import FrameTopics, iter_frames  # noqa: E402
from replay.reader import LogReader  # noqa: E402

VIDEO = ROOT.parent / "shared" / "data" / "real" / "golf_broadcast_approach" / "demo.mp4"
REFERENCE = HERE / "data" / "golf_broadcast_reference.csv"
MARKS = "frame,x,y,w,h\n12,343,177,6,6\n16,329,179,6,6\n20,313,201,6,6\n30,296,251,6,6\n"
SHEET_FRAMES = (12, 24, 32, 40, 60, 90, 120, 150, 170, 190, 200, 206)


def cli(*args: str) -> str:
    proc = subprocess.run([sys.executable, "-m", "replay.cli", *args], cwd=ROOT, capture_output=True, text=True)
    if proc.returncode != 0:
        raise SystemExit(f"trackreplay {' '.join(args)} failed: {proc.stderr.strip()}")
    return proc.stdout + proc.stderr


def longest_run(ok: np.ndarray, frames: np.ndarray, start: int) -> int:
    """Consecutive reference frames from ``start`` on which ``ok`` holds."""
    run = 0
    for f, good in zip(frames, ok):
        if f < start:
            continue
        if not good:
            break
        run += 1
    return run


def main() -> int:
    if not VIDEO.is_file():
        print(f"{VIDEO} is absent; nothing to do")
        return 0
    ref = pl.read_csv(REFERENCE, comment_prefix="#")
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        (tmp / "marks.csv").write_text(MARKS)
        cli("record", str(tmp / "clip.mcap"), "--video", str(VIDEO), "--quiet")
        cli("annotate", str(tmp / "clip.mcap"), "--from-csv", str(tmp / "marks.csv"), "--label", "ball", "--out", str(tmp / "marked.mcap"))
        out = cli("replay", str(tmp / "marked.mcap"), "--tracker", "golf", "--export", str(tmp / "traj.parquet"),
                  "--interpolate", "none", "--quiet")
        notice = next((line for line in out.splitlines() if line.startswith("trackreplay: golf:")), "")
        traj = pl.read_parquet(tmp / "traj.parquet")
        j = ref.join(traj.select("frame", pl.col("x").alias("ex"), pl.col("y").alias("ey"), "status"), on="frame", how="left")
        frames = j["frame"].to_numpy()
        err = np.hypot(j["ex"].to_numpy() - j["x"].to_numpy(), j["ey"].to_numpy() - j["y"].to_numpy())
        measured = (j["status"] == "measured").fill_null(False).to_numpy()
        ok5, ok10 = measured & (err <= 5), measured & (err <= 10)
        # contact sheet: crops around the reference position, estimate in red, reference in green
        reader = LogReader(tmp / "marked.mcap")
        tiles = []
        by_frame = {int(r["frame"]): r for r in j.iter_rows(named=True)}
        for frame in iter_frames(reader, FrameTopics.detect(reader)):
            if frame.index not in SHEET_FRAMES:
                continue
            r = by_frame[frame.index]
            image = frame.image.copy()
            cx, cy = int(r["x"]), int(r["y"])
            cv2.circle(image, (cx, cy), 9, (0, 220, 0), 1, cv2.LINE_AA)
            if r["ex"] is not None and np.isfinite(r["ex"]):
                colour = (0, 0, 255) if r["status"] == "measured" else (0, 165, 255)
                cv2.drawMarker(image, (int(round(r["ex"])), int(round(r["ey"]))), colour, cv2.MARKER_CROSS, 14, 1, cv2.LINE_AA)
            y0, x0 = max(0, cy - 50), max(0, cx - 75)
            tile = cv2.resize(image[y0 : y0 + 100, x0 : x0 + 150], (300, 200), interpolation=cv2.INTER_NEAREST)
            cv2.putText(tile, f"{frame.index} {r['status'] or '-'}", (6, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.55, (255, 255, 255), 1, cv2.LINE_AA)
            tiles.append(tile)
        grid = np.vstack([np.hstack(tiles[k : k + 4]) for k in range(0, len(tiles), 4)])
        cv2.imwrite(str(HERE / "golf_real_frames.jpg"), grid, [cv2.IMWRITE_JPEG_QUALITY, 85])
    fig, ax = plt.subplots(figsize=(10, 3.6))
    ax.plot(frames[measured], err[measured], ".", ms=3, label="measured")
    other = ~measured & np.isfinite(err)
    ax.plot(frames[other], err[other], "x", ms=3, label="predicted")
    ax.axvspan(25, 40, color="0.85", label="landing and first bounce (by eye)")
    ax.set_yscale("log")
    ax.set_xlabel("frame")
    ax.set_ylabel("distance to reference [px]")
    ax.set_title("Golf tracker on a real broadcast approach shot (no encoders)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(HERE / "golf_real_error.png", dpi=100)
    first_fail = next((int(f) for f, good in zip(frames, ok10) if f >= 12 and not good), None)
    lines = [
        "# Golf tracker on a real broadcast clip",
        "",
        "Generated by `python docs/golf_real.py`. Input: `golf_broadcast_approach/demo.mp4` (760×388, 30 fps,",
        "236 frames, TV broadcast: an approach shot comes down onto the green around frames 25–40, rolls,",
        "and drops into the hole around frame 207) recorded with `trackreplay record`, the ball marked with",
        "`trackreplay annotate --from-csv` on frames 12, 16, 20 and 30 (6×6 boxes), replayed with",
        "`--tracker golf` (defaults). The log has no encoders, so the tracker works in image coordinates only",
        f"and says so: `{notice.strip()}`.",
        "",
        "Reference: `docs/data/golf_broadcast_reference.csv`, the ball centre on frames 12–206 from a",
        "nearest-bright-blob follower started by hand and checked by eye every 12th frame (not a ground truth",
        "from the broadcaster).",
        "",
        "| measure | value |",
        "|---|---|",
        f"| reference frames | {len(frames)} (12–206) |",
        f"| measured within 5 px / 10 px | {ok5.mean():.2f} / {ok10.mean():.2f} |",
        f"| median distance of measured estimates | {np.nanmedian(err[measured]):.2f} px |",
        f"| consecutive frames held within 10 px from frame 12 | {longest_run(ok10, frames, 12)} |",
        f"| first reference frame not held within 10 px | {first_fail if first_fail is not None else 'none'} |",
        f"| frames 25–40 (landing, bounce) held within 10 px | {ok10[(frames >= 25) & (frames <= 40)].sum()} of {((frames >= 25) & (frames <= 40)).sum()} |",
        f"| frames 100–206 (roll, zoom in) held within 10 px | {ok10[frames >= 100].sum()} of {(frames >= 100).sum()} |",
        "",
        "![distance to reference](golf_real_error.png)",
        "",
        "Crops around the reference (green circle); red cross = measured estimate, orange = predicted:",
        "",
        "![frames](golf_real_frames.jpg)",
        "",
        "What the frames show (read off the pictures of the run that wrote this page):",
        "",
        "- **Descent, landing and bounce (frames 12–40):** the ball is a 2–4 px speck over the green; apart",
        "  from two frames (22–23) where the motion-blurred ball drops out of the LUT and the track is",
        "  `predicted`, it is held to well under a pixel, through the ground contact around frame 25–30.",
        "- **Roll (40–110):** held within a pixel while the camera pans and zooms in.",
        "- **Around frames 111–133** the ball is lost as the camera pans faster; the particles are respread",
        "  over the picture centre (our `lost_search = centre` addition) and for a few frames a false speck",
        "  is `measured` about 55 px away, until the ball is re-acquired.",
        "- **Zoomed in (150–206):** the ball grows to 20–30 px; the silhouette keeps only its sunlit upper",
        "  side, so the estimate sits on the ball but 4–10 px up and right of the reference centroid (the",
        "  reference itself is a bright-blob centroid, biased the other way by the shadowed side). The",
        "  area gate follows the zoom (targets from past extractions), so the ball is never rejected.",
        "",
    ]
    (HERE / "golf_real.md").write_text("\n".join(lines))
    print("\n".join(lines[12:21]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
