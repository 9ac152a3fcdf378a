"""Golf tracker (seed 000) on the two real clips played back differently: does it generalise?

    python docs/golf_robustness.py      (about 5 minutes; skips a clip that is absent)

The tracker is measured on other real clips than ours, so each of our two clips (the iron shot into
the sky, ../shared/data/real/golf_iron_shot_sky; the broadcast approach,
../shared/data/real/golf_broadcast_approach) is turned into the kinds of clip a user brings: half the
resolution, half the frame rate, mirrored (a left-handed golfer, a camera on the other side), darker,
harder JPEG, and marks drawn the way people draw them (3 px off, 1.6x or 0.6x the ball, 3 frames
later). Each variant is recorded with `trackreplay record --images`, marked once with
`trackreplay annotate --from-csv` (the clip's one mark, moved with the variant), replayed with
`trackreplay replay --tracker golf` (default configuration, seed 0) and compared with the clip's
reference positions moved the same way (tolerances scaled with the resolution). Writes
docs/golf_robustness.md and docs/golf_robustness.json. Deterministic.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))

import cv2  # noqa: E402
import numpy as np  # noqa: E402
import polars as pl  # noqa: E402

REPO_ENV = dict(os.environ, PYTHONPATH=str(ROOT))
# The approach's ball rolls over the cup's liner from frame 208 and is in the hole from 217 on
# (checked by eye on 2x crops of frames 206-221; docs/golf_real.md).
HOLED = 217


def cli(*args: str) -> tuple[str, str]:
    """Run ``trackreplay ARGS``; (stdout, stderr)."""
    proc = subprocess.run([sys.executable, "-m", "trackreplay", *args], cwd=ROOT, capture_output=True, text=True,
                          env=REPO_ENV)
    if proc.returncode != 0:
        raise SystemExit(f"trackreplay {' '.join(args[:1])} failed: {proc.stderr.strip()}")
    return proc.stdout, proc.stderr


def compare(traj: pl.DataFrame, ref: pl.DataFrame) -> pl.DataFrame:
    """The reference joined with track 1's estimate on each of its frames, and the distance (px)."""
    est = traj.filter(pl.col("track_id") == 1).select("frame", pl.col("x").alias("ex"), pl.col("y").alias("ey"), "status")
    j = ref.join(est, on="frame", how="left").sort("frame")
    return j.with_columns((((pl.col("ex") - pl.col("x")) ** 2 + (pl.col("ey") - pl.col("y")) ** 2).sqrt()).alias("dist"))


REAL = ROOT.parent / "shared" / "data" / "real"
# key: (video, reference csv, the one mark (frame, x, y, w, h: top-left box), first frame the ball is gone)
CLIPS = {
    "iron": (REAL / "golf_iron_shot_sky" / "vid1.mp4", REAL / "golf_iron_shot_sky" / "reference.csv", (458, 593, 1016, 22, 22), 612),
    "approach": (REAL / "golf_broadcast_approach" / "demo.mp4", HERE / "data" / "golf_broadcast_reference.csv", (20, 312, 200, 8, 8), HOLED),
}
VARIANTS = {  # key: (what it is, how it is made)
    "as recorded": ("the clip as it is", {}),
    "half resolution": ("every frame resized to half (INTER_AREA)", {"resize": 0.5}),
    "half frame rate": ("every other frame (30 fps iron, 15 fps approach)", {"every": 2}),
    "mirrored": ("left and right swapped", {"flip": True}),
    "darker": ("luminance x0.75", {"gain": 0.75}),
    "brighter": ("luminance x1.3 (highlights clip: a white ball and bright sky both saturate)", {"gain": 1.3}),
    "sensor noise": ("Gaussian noise of 4 levels per channel (seeded), then JPEG", {"noise": 4.0}),
    "soft focus": ("a Gaussian blur of 1.2 px", {"blur": 1.2}),
    "1.5x resolution": ("every frame enlarged 1.5x (INTER_CUBIC): a larger ball", {"resize": 1.5}),
    "JPEG q50": ("re-encoded at quality 50", {"quality": 50}),
    "shaky camera": ("each frame shifted by up to 2 px each way (seeded)", {"shake": 2.0}),
    "mark 3 px off": ("the box moved 3 px right and 3 px up", {"shift": (3, -3)}),
    "mark 1.6x": ("the box 1.6x the ball's, same centre", {"box_scale": 1.6}),
    "mark 0.6x": ("the box 0.6x the ball's, same centre", {"box_scale": 0.6}),
    "mark 3 frames late": ("the ball marked 3 frames later (in flight)", {"late": 3}),
    # added 2026-11-28 (ninth session), from a review that built them by hand
    "3/4 resolution": ("every frame resized to 0.75 (INTER_AREA)", {"resize": 0.75}),
    "turned 180°": ("the picture upside down (both axes flipped)", {"flip": True, "flip_v": True}),
    "frames repeated": ("retimed to 5/3 the frame rate by showing frames again (30 -> 50 fps approach, 60 -> 100 iron)",
                        {"retime": 5 / 3}),
    "broadcast overlay": ("a white box with a red disc top right (80x40 px) and a running timestamp bottom left",
                          {"overlay": True}),
}
# The same script run on the code before this change (commit 8ba91d0, in its own worktree and venv);
# its rows, as written then: docs/golf_robustness_before.json.
BEFORE_FILE = HERE / "golf_robustness_before.json"


def decoded(video: Path) -> tuple[list[np.ndarray], float]:
    cap = cv2.VideoCapture(str(video))
    fps = cap.get(cv2.CAP_PROP_FPS)
    frames = []
    while True:
        ok, frame = cap.read()
        if not ok:
            return frames, fps
        frames.append(frame)


def overlay(img: np.ndarray, k: int) -> np.ndarray:
    """What a broadcast puts over the picture: a running timestamp bottom left, a white box with a
    red disc top right (a channel logo; the review's clip)."""
    img = img.copy()
    height, width = img.shape[:2]
    cv2.putText(img, f"00:{k // 60:02d}:{k % 60:02d}.{k % 10}", (10, height - 15), cv2.FONT_HERSHEY_SIMPLEX,
                0.8 * height / 720, (255, 255, 255), 2, cv2.LINE_AA)
    cv2.rectangle(img, (width - 90, 10), (width - 10, 50), (255, 255, 255), -1)
    cv2.circle(img, (width - 50, 30), 12, (0, 0, 200), -1)
    return img


def run(clip: str, variant: str, frames: list[np.ndarray], fps: float, tmp: Path) -> dict:
    video, reference, (mark_frame, bx, by, bw, bh), gone = CLIPS[clip]
    how = VARIANTS[variant][1]
    height, width = frames[0].shape[:2]
    every, s, retime = how.get("every", 1), how.get("resize", 1.0), how.get("retime", 1.0)
    flip, flip_v = how.get("flip", False), how.get("flip_v", False)
    # the source frame shown on each frame of the variant
    sel = [min(round(k / retime), len(frames) - 1) for k in range(int(len(frames) * retime))] if retime != 1.0 \
        else list(range(0, len(frames), every))
    first_at = {}  # source frame -> the variant's first frame showing it
    for k, i in enumerate(sel):
        first_at.setdefault(i, k)
    # A shaky camera: frame i's picture moved by shake[i] (the world stays; the picture moves)
    shake = np.random.default_rng(7).uniform(-1.0, 1.0, (len(frames), 2)) * how.get("shake", 0.0)

    def point(x: float, y: float, i: int = 0) -> tuple[float, float]:
        """A reference position (pixel centres) of frame ``i`` in the variant's pixels."""
        x = width - 1 - x if flip else x
        y = height - 1 - y if flip_v else y
        return ((x + shake[i, 0] + 0.5) * s - 0.5, (y + shake[i, 1] + 0.5) * s - 0.5)

    noise_rng = np.random.default_rng(11)
    folder = tmp / f"{clip}-{list(VARIANTS).index(variant)}"
    folder.mkdir(parents=True, exist_ok=True)
    for k, i in enumerate(sel):
        img = frames[i]
        if flip or flip_v:
            img = np.ascontiguousarray(img[::-1 if flip_v else 1, ::-1 if flip else 1])
        if s != 1.0:
            img = cv2.resize(img, (round(width * s), round(height * s)), interpolation=cv2.INTER_AREA if s < 1 else cv2.INTER_CUBIC)
        if "shake" in how:
            move = np.float32([[1, 0, shake[i, 0]], [0, 1, shake[i, 1]]])
            img = cv2.warpAffine(img, move, (img.shape[1], img.shape[0]), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        if "blur" in how:
            img = cv2.GaussianBlur(img, (0, 0), how["blur"])
        if "noise" in how:
            img = np.clip(img + noise_rng.normal(0.0, how["noise"], img.shape), 0, 255).astype(np.uint8)
        if "gain" in how:
            img = np.clip(img.astype(np.float32) * how["gain"], 0, 255).astype(np.uint8)
        if how.get("overlay"):
            img = overlay(img, k)
        cv2.imwrite(str(folder / f"{k:05d}.jpg"), img, [cv2.IMWRITE_JPEG_QUALITY, how.get("quality", 95)])
    log = tmp / f"{folder.name}.mcap"
    cli("record", str(log), "--images", str(folder), "--fps", str(fps / every * retime), "--quiet")

    ref = pl.read_csv(reference, comment_prefix="#")
    marked_at = mark_frame + how.get("late", 0)
    cx = float(np.interp(marked_at, ref["frame"], ref["x"])) if "late" in how else bx + bw / 2 - 0.5
    cy = float(np.interp(marked_at, ref["frame"], ref["y"])) if "late" in how else by + bh / 2 - 0.5
    dx, dy = how.get("shift", (0, 0))
    side_w, side_h = bw * how.get("box_scale", 1.0), bh * how.get("box_scale", 1.0)
    mx, my = point(cx + dx, cy + dy, marked_at)
    box = (round(mx - side_w * s / 2 + 0.5), round(my - side_h * s / 2 + 0.5), max(2, round(side_w * s)), max(2, round(side_h * s)))
    marks = tmp / f"{folder.name}.csv"
    mark_k = first_at[marked_at]
    marks.write_text(f"frame,x,y,w,h\n{mark_k},{box[0]},{box[1]},{box[2]},{box[3]}\n")
    marked, traj_path = tmp / f"{folder.name}-marked.mcap", tmp / f"{folder.name}.parquet"
    cli("annotate", str(log), "--from-csv", str(marks), "--label", "ball", "--out", str(marked))
    said = cli("replay", str(marked), "--tracker", "golf", "--export", str(traj_path), "--interpolate", "none", "--quiet")[0]

    ref = ref.filter(pl.col("frame").is_in(list(first_at)))
    moved = [point(x, y, f) for f, x, y in zip(ref["frame"], ref["x"], ref["y"])]
    ref = pl.DataFrame({"frame": [first_at[f] for f in ref["frame"]], "x": [p[0] for p in moved], "y": [p[1] for p in moved]})
    traj = pl.read_parquet(traj_path)
    j = compare(traj, ref).filter(pl.col("frame") >= mark_k)
    d = j["dist"].fill_null(np.inf).to_numpy()
    m = (j["status"] == "measured").fill_null(False).to_numpy()
    gone_k = next(k for k, i in enumerate(sel) if i >= gone)  # the variant's first frame with the ball gone
    after = traj.filter(pl.col("frame") >= gone_k)
    return {"clip": clip, "variant": variant, "reference_frames": int(len(d)), "measured": float(m.mean()),
            "within_5px": float((m & (d <= 5 * s)).mean()), "confident_wrong": int((d[m] > 25 * s).sum()),
            "measured_while_gone": f"{int((after['status'] == 'measured').sum())}/{after.height}",
            "digest": next((ln.split("digest ")[1].strip() for ln in said.splitlines() if "digest " in ln), "?")}


def main() -> int:
    rows = []
    with tempfile.TemporaryDirectory() as td:
        for clip, (video, *_rest) in CLIPS.items():
            if not video.is_file():
                print(f"golf_robustness: {video} is absent; skipping {clip}")
                continue
            frames, fps = decoded(video)
            for variant in VARIANTS:
                rows.append(run(clip, variant, frames, fps, Path(td)))
                print(json.dumps(rows[-1]), flush=True)
    if not rows:
        return 0
    (HERE / "golf_robustness.json").write_text(json.dumps(rows, indent=1) + "\n")
    write_report(rows)
    return 0


def pct(v: float) -> str:
    return f"{100 * v:.1f} %"


def write_report(rows: list[dict]) -> None:
    lines = [
        "# Golf tracker on the real clips played back differently",
        "",
        "> Stays a script, not a `trackreplay evaluate` manifest (docs/README.md): `golf_robustness.py`: it makes the "
        "variants it scores from the two real clips (resolution, frame rate, mirrored, darker, JPEG) and draws the marks "
        "badly on purpose (off-centre, loose, tight, late), with tolerances scaled to each variant; `evaluate` scores "
        "clips as they are, marked from their truth.",
        "",
        "Generated by `python docs/golf_robustness.py` (about 11 minutes). Each real clip, turned into",
        "the kinds of clip a user brings, recorded, marked once and replayed with the CLI (default",
        "configuration, seed 0); scored on the clip's reference frames from the mark on (positions and",
        "tolerances moved and scaled with the variant). *Measured*: share of those frames `measured`;",
        "*within 5 px*: `measured` and within 5 px (scaled: 2.5 px at half resolution, 7.5 px at 1.5x); *confident wrong*:",
        "`measured` more than 25 px off; *measured while gone*: `measured` rows after the ball left",
        "the picture (iron, from frame 612) or dropped into the hole (approach, from frame 217).",
        "*Before*: this script run on the code at commit 8ba91d0, before the changes below",
        "(`golf_robustness_before.json`; `-`: a variant added later, brighter to 1.5x resolution and 3/4 resolution to",
        "broadcast overlay, 2026-11-28).",
        "",
        "| clip | variant | reference frames | measured | within 5 px | confident wrong | measured while gone | before: within 5 px / wrong / while gone |",
        "|---|---|---|---|---|---|---|---|",
    ]
    before_rows = json.loads(BEFORE_FILE.read_text()) if BEFORE_FILE.is_file() else []
    earlier = {(b["clip"], b["variant"]): b for b in before_rows}
    for r in rows:
        b = earlier.get((r["clip"], r["variant"]))
        before = f"{pct(b['within_5px'])} / {b['confident_wrong']} / {b['measured_while_gone']}" if b else "-"
        lines.append(f"| {r['clip']} | {r['variant']} ({VARIANTS[r['variant']][0]}) | {r['reference_frames']} | {pct(r['measured'])} "
                     f"| {pct(r['within_5px'])} | {r['confident_wrong']} | {r['measured_while_gone']} | {before} |")
    lines += ["", FINDINGS]
    (HERE / "golf_robustness.md").write_text("\n".join(lines) + "\n")


FINDINGS = """## Re-run 2026-12-07 (fifteenth session)

After the world behind the ball (`trackers/golf/world_behind.py`, fourteenth session) and the path from
the mark (`Validator.seed_at`, fifteenth; docs/ball_corpus.md): **no confident wrong row and nothing
`measured` after the ball has gone, in any variant.** What they cost, in `measured` rows (`predicted` or
`lost` instead, never wrong):

- the approach's frames right after its mark on the moving ball, and those where it rolls at under a
  pixel a frame in a still view: as recorded 100 → 96.3 %, most variants 2–4 points lower than before;
- three variants fell far: the iron shot marked 3 frames late (in flight) 100 → 5.0 %, the approach in
  soft focus 97.9 → 11.2 %, with sensor noise 100 → 87.7 %. The same with the path from the mark
  switched off (`python docs/golf_robustness_ab.py`: 5.0 %, 12.8 %, 87.2 % with `Validator.seed_at` a no-op), so
  they come from the fourteenth session's world behind the ball, whose doc run did not include this
  script; not examined further this session;
- the half-resolution approach: 98.4 → 95.7 %. While this run was made, the path from the mark let
  another tentative track (a thing on the green moving with the zoom) be confirmed there, 69 rows wrong;
  fixed before committing (while the ball's speed is unknown only a path from the mark is confirmed).

## What this found, and what changed

Three failures that the clips as recorded never showed (each now has a unit test that fails
without its fix, in tests/trackers/golf/):

- **Mirrored iron shot: 14 confident wrong rows and `measured` on all 44 frames after the ball
  had gone.** Faint in front of the trees (frame 493), the ball was missed once; the nearest
  look-alike in the gate was a flower 32 px behind its path, seen in the same place on the frames
  before while the ball was measured elsewhere. It was measured, and the track settled on the
  flower bed. Now a look-alike blob that sat still while the ball was measured more than a diameter away is
  *still scenery*, refused by the gate (reason `still`, shown in the Rerun view) for as long as it
  stays (`trackers/golf/scenery.py`, `[golf.validate] still_px`).
- **Marks drawn loosely: the iron shot never measured at all** (box 3 px off, or 1.6x the ball).
  The LUTs learn the ball's colours from the ellipse inscribed in the box: a loose box gave them
  turf, the ball merged with it in the silhouette and its size was read as 415-2690 px instead of
  ~280. Each mark is now placed on the bright blob it was drawn round before anything learns from
  it (`trackers/golf/snap.py`, `[golf.snap]`): moved to the blob's centroid when more than a pixel
  off, and given the blob's size when the box's sample ellipse is larger than the blob plus a pixel
  of blurred rim each side (a tight box, as the synthetic annotator draws them, is kept as drawn:
  a ball's dim, shaded side is still the ball).
- **Iron shot at 30 fps: 1 of 18 reference frames measured.** The one mark is on the launch frame;
  at 30 fps the ball is 40-70 px away on the next. A ball seen lying still and then missed is
  taken to be struck (the samples' velocities open up), but "lying still" needed two sightings.
  Now one sighting does when the ball is round on it (no motion blur: `rest_roundness`); a streak
  marked in flight is not taken for a ball at rest (tried without that condition: the iron shot
  marked 3 frames late measured a wrong blob 85 px off in the opened gate, 14 rows).

Left as found: the approach at 15 fps (every other frame of a 30 fps broadcast) is now followed
(95.7 % within 5 px; before 1.1 % and 12 wrong rows), but after the ball dropped into the hole the
right half of the cup's white liner (split by the flagstick, about as large and round as the zoomed-in
ball, where the ball was last seen as one blob with it) is measured on 4 of the 9 frames to the end
(5 before 2026-11-29's `target_shrink_rate`).
At 15 fps the ball goes from rolling over the liner to gone in one step: the last blob holding it is
ball and liner together (2.8x the ball's area, inside the area tolerance), and the size the tracker
expects grows towards it. Not solved. After the ball left the picture, the iron shot at JPEG q50 and
the shaky iron shot measured 2 rows (as before) until 2026-11-27: the ball's last blobs at the top
edge, cut by it and smeared, taught the size and colour tables, which then took a speck for the ball.
A blob within one ball diameter of the picture's edge now teaches neither (`GolfTracker._at_border`):
0 of 44 on both, the other rows unchanged.

"Gone" on the approach counts from frame 217 (2026-11-27; before: 208). Checked by eye on 2x crops of
frames 206-221: the ball rolls over the cup's liner from 208 and drops on 216, so frames 207-216
(after the reference's last frame, 206) count neither way. A blob refused for its shape that lies
nearer the prediction and nearer the ball's area than the candidate (the ball merged with the liner)
now keeps a poorer candidate from being `measured` (`validate._merged_nearer`; at 30 fps the piece of
liner measured on frame 208 in docs/golf_real.md's four-mark run; here 15 fps: 9 -> 5 of 9 rows).

Added 2026-11-28 (the code of commit c7c7867 on): brighter (x1.3, highlights clip), sensor noise (4
levels a channel before the JPEG), soft focus (1.2 px blur) and 1.5x resolution (a larger ball, upscaled).
Nothing to fix: every one of these 8 rows within 97.9-100 % and none `measured` after the ball is gone.

Added 2026-11-28 (ninth session), the variants a black-box review built by hand: 3/4 resolution, the
picture turned 180°, frames repeated (5/3 the rate by showing frames again) and a broadcast overlay. What
the review found there and is fixed (tests in tests/trackers/golf/): with repeated frames a tentative
track was confirmed from two pictures of ball and cup liner, then liner pieces `measured` after the drop
(approach, 8 of 32): a frame whose search region repeats the picture before it exactly now adds no
sighting (`validate._fit`), 0 of 32; with each frame shown three times a streak grown sideways into a
bunker moved a measurement 20 px (`golf.streak` now grows only along the predicted motion). The overlay
on the iron shot (fixed 2026-11-29, 44 -> 0 of 44): the ball climbs slowly out through the top (its
samples' mean 1.4 px above the picture on the next frame, less than the diameter that made the
prediction "outside"), and the contrast fallback took the white box's corner 11 px below the edge, 14 px
from the prediction and inside the gate (confidence 0.32), `measured` on all 44 frames after. Once the
predicted centre is beyond an edge by any amount, only a blob the edge cuts (reaching within half a
diameter of it: what is left of a ball leaving) can be taken directly (`validate.cut_by_edge`); anything
wholly inside is a jump that needs confirming. Every other row of this table is unchanged (digests
equal), as are docs/golf_real.md and docs/golf_synthetic.md. Tried before that: a higher confidence
(0.5) for the contrast fallback (44 -> 40 of 44, and 3 correct frames lost on the 1080p synthetic shot),
dropped. The approach turned 180° (fixed 2026-11-29, 7 -> 0 of 19): after the drop a tentative track of
11x4 px liner pieces (area ~24 px, the ball's ~290) was confirmed on frame 226, 20 px from where the ball
was last measured, and so passed as "the ball found again where it was" (`seen_before` exempts that
place). That exemption now needs a blob about as large as the ball was (within the area tolerance): a
much smaller one there is checked like any other, and a blob (ball and liner) covered that point on the
ball's last frame. (A limit on the confirmed size alone would not do: a ball lost at launch is found
again 20x smaller on the synthetic tee shots; there the encoders carry the point into the sky of the last
picture, where nothing covered it.) Every other row unchanged. **Was failing until 2026-11-29 (eleventh session)**: the approach at 3/4 resolution — specks beside the
cup on 15 of 19, and from frame ~148 rows 5-10 px off on 1-2 px blobs near a ball of 10-26 px (80.2 %
within 5 px; the expected size followed the specks down from ~14 px to 1.5 px while the broadcast
zoomed in). Why, found 2026-11-29: from frame ~140 the ground LUT marks only the rim of the larger, sharper
ball (its blended edge colours), not its white interior; the LUT had spent its `learn_max` = 6 boxes
learned from the track on frames 24-109, on a blob swinging between part of the ball and all of it
(2 <-> 5 <-> 14 px: each swing a "zoom change" of 2x), so nothing was left for the zoom that follows. At
full resolution the same clip relearns at frames 105, 106 and 170, each time where the LUT had lost the
ball's core (29-50 % of it still marked). Tried and dropped: learning only at sizes outside the range
already learned (3/4 resolution unchanged, the clip as recorded lost the ball from frame 136); an area
slack of 4 px on the trigger (still 6 boxes spent by frame 127); no box with fewer than 9 core pixels
(`learn_min_core_px`: 3/4 resolution 80.2 -> 100 %, 15 -> 0 of 19 after the drop, the approach at 15 fps 5 -> 0
of 9, synthetic seed 2 82.2 -> 87.2 %, but the approach at half resolution 98.4 -> 71.7 % and 0 -> 17 of 19 rows
`measured` after the drop: there the old code spent its 6 boxes on 1-4 px specks at frames 26-35 and never
learned again, which served; the new one learned from an 8 px box at frame 93 whose core held turf, and the
LUT marked less of the ball afterwards (36 -> 30 %): learning from the track can make the LUT worse.
Reverted); keeping a learned box only if the LUT then marks more of that box's ball (else the LUT restored:
the approach at 15 fps 5 -> 0 of 9 after the drop, encoder-dropout shot 85.5 -> 88.3 %, but 3/4 resolution
still 15 of 19 and the approach with one mark at frame 12 then measured the empty cup's liner, a real-data
test: reverted; with both, half and 3/4 resolution fell to 73 and 57 %).
What fixed it (2026-11-29, eleventh session): the expected size no longer follows pieces of the ball
down at the rate it follows a growing ball. A smaller blob moves the target area at half the rate
(`[golf.blobs] target_shrink_rate` 0.15, `target_rate` 0.3 for the rest): a silhouette loses part of the
ball (its shaded side, its rim, all but a highlight) far more often than a ball's image shrinks that fast,
and a target that follows such pieces lets smaller pieces through on the next frame. **3/4 resolution:
80.2 -> 98.4 % within 5 px, 15 -> 0 of 19 `measured` after the drop** (a real-data test); the approach at
15 fps 5 -> 4 of 9 after the drop, with sensor noise 97.9 -> 100 %, at JPEG q50 99.5 -> 97.9 % (four frames
`predicted`, none wrong); the other 34 rows as before; on the synthetic shots (docs/golf_synthetic.md) detected within 5 px level or +0.9 to +1.4
points on four shots, -0.3 on two. Rates tried on the 8 rows (both clips as recorded, at half and 3/4
resolution and at half frame rate): 0.2 leaves 3/4 resolution failing (17 of 19), 0.1 and 0.15 fix it,
0.05 costs the iron shot at 3/4 resolution a frame; half the growth rate, the middle of what works, kept.

Measured and changed on the way (this table): a first form of the mark placement also shrank a
box whose sample ellipse was only a pixel wider than the ball's blob. The approach's 8x8 px mark
then became the 5x5 px ball's core; frames 204-206 (ball and cup liner one blob) went `predicted`,
and the mirrored and shaky approach measured the cup's liner on 3 of the 28 frames after the ball
dropped in (shaky: 94.1 % within 5 px, before 98.9 %). A box now counts as loose only when its
ellipse exceeds the blob by more than a pixel of blurred rim on each side (`slack_px` 2).
"""


if __name__ == "__main__":
    raise SystemExit(main())
