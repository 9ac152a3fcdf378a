"""`flight --rescan` on the synthetic tee shots: what looking again along the fitted flight adds to
the golf tracker's causal trajectory, and how often it would claim a ball that is not there.

    python docs/golf_rescan.py [--workdir DIR]     (the logs of docs/golf_synthetic.py; reused from DIR)

For every shot of docs/golf_synthetic.py: the causal replay (default configuration, seed 0), then
:func:`trackreplay.replay.analysis.flight_rescan.rescan` on its trajectory, both scored against the scene's
ground truth with the same metrics as docs/golf_synthetic.md. Then the detector itself, on every
visible frame of every shot, with the fit's expected image of the ball but placed (a) on the true
ball and (b) 15, 25 and 40 px beside it, across its path, where there is no ball: how many of (b)
"find a ball" (false sightings per search) and how many of the frames the tracker missed (a)
finds, for the top-hat test alone and with the world-behind-the-ball test. Writes
docs/golf_rescan.md and docs/golf_rescan.json. Deterministic; ~6 minutes on 2 cores.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # the fit is many small solves
HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import numpy as np  # noqa: E402
import polars as pl  # noqa: E402

import golf_synthetic as G  # noqa: E402
from trackreplay.replay.core.engine import ReplayRequest, replay  # noqa: E402
from trackreplay.replay.analysis.flight import FlightConfig, fit_flight, observations  # noqa: E402
from trackreplay.replay.analysis.flight_rescan import RescanConfig, _look_all, expected_balls, rescan  # noqa: E402
from trackreplay.replay.log.groundtruth import read_groundtruth  # noqa: E402
from trackreplay.replay.log.reader import LogReader  # noqa: E402
from trackreplay.replay.analysis.smooth import log_context  # noqa: E402
from trackreplay.schemas import topics as T  # noqa: E402
from trackreplay.schemas.records import LensTable  # noqa: E402

DECOY_PX = (15.0, 25.0, 40.0)
THRESHOLDS = ((6.0, None), (6.0, 2.0), (6.0, 3.0), (6.0, 4.0), (6.0, 5.0), (8.0, 4.0))  # (min_snr, min_new_snr or top-hat only)


def fps_of(times: dict[int, int]) -> float:
    return (len(times) - 1) / ((max(times.values()) - min(times.values())) * 1e-9) if len(times) > 1 else 30.0


def found_rows(traj: pl.DataFrame, gt: pl.DataFrame) -> dict:
    """The rescan's own rows against the truth: how many, how far off, any where the ball is not visible."""
    rows = traj.filter(pl.col("fill") == "rescan").join(
        gt.select("frame", pl.col("x").alias("tx"), pl.col("y").alias("ty"), "visible"), on="frame", how="left")
    err = ((rows["x"] - rows["tx"]) ** 2 + (rows["y"] - rows["ty"]) ** 2).sqrt().drop_nulls().to_numpy()
    return {"found": rows.height, "invisible": int((~rows["visible"].fill_null(False)).sum()),
            "within5": int((err <= G.DETECT_PX).sum()), "max_px": float(err.max()) if err.size else None,
            "median_px": float(np.median(err)) if err.size else None}


def detector_trials(log: Path, traj: pl.DataFrame, gt: pl.DataFrame, times: dict, cameras: dict) -> list[dict]:
    """Every visible frame: the detector's answer (top-hat and world responses, in sigmas) with the
    fitted image of the ball placed on the true ball and beside it (no ball there)."""
    fit = fit_flight(observations(traj, cameras, track_id=1), FlightConfig(jackknife_blocks=0), fps_of(times))
    vis = gt.filter(pl.col("visible") & pl.col("x").is_not_null())
    truth = {f: np.array([x, y]) for f, x, y in vis.select("frame", "x", "y").rows()}
    measured = set(traj.filter(pl.col("status") == "measured")["frame"].to_list())
    cfg = RescanConfig(min_snr=1e-9, min_new_snr=-1e9, sigma_factor=0.0)  # every answer, thresholds applied below
    balls = {b.frame: b for b in expected_balls(fit, sorted(truth), times, cameras, world_frames=cfg.world_frames)}
    out = []
    for offset in (0.0,) + tuple(s * d for d in DECOY_PX for s in (1.0, -1.0)):
        placed = {}
        for i, b in balls.items():
            along = b.path[-1] - b.path[0]
            n = float(np.hypot(*along))
            across = np.array([-along[1], along[0]]) / n if n > 1e-6 else np.array([1.0, 0.0])
            placed[i] = dataclasses.replace(b, centre=truth[i] + offset * across, sigma=0.0)
        seen = {s.frame: s for s in _look_all(log, placed, cameras, cfg)}
        for i in sorted(placed):
            s = seen.get(i)
            out.append({"frame": i, "offset": offset, "missed": i not in measured,
                        "snr": None if s is None else s.snr, "new": None if s is None else s.new_snr,
                        "error": None if s is None else float(np.hypot(*(s.point - truth[i])))})
    return out


def trial_table(trials: list[dict]) -> list[dict]:
    ball = [t for t in trials if t["offset"] == 0.0 and t["missed"]]
    decoys = [t for t in trials if t["offset"] != 0.0 and t["snr"] is not None]
    rows = []
    for hat, new in THRESHOLDS:
        def hit(t, hat=hat, new=new):
            return t["snr"] is not None and t["snr"] >= hat and (new is None or t["new"] >= new)
        rows.append({"min_snr": hat, "min_new_snr": new, "searches": len(decoys), "false": sum(hit(t) for t in decoys),
                     "missed": len(ball), "found": sum(hit(t) for t in ball),
                     "found_within5": sum(hit(t) and t["error"] <= G.DETECT_PX for t in ball)})
    return rows


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workdir", type=Path, help="keep (and reuse) the synthesised logs here")
    args = ap.parse_args()
    tmp = tempfile.TemporaryDirectory() if args.workdir is None else None
    workdir = Path(tmp.name) if tmp is not None else args.workdir
    workdir.mkdir(parents=True, exist_ok=True)
    results, trials = {}, []
    try:
        for key, desc, scene in G.RUNS:
            log, info = G.synthesise(key, scene, workdir)
            reader = LogReader(log)
            gt = read_groundtruth(reader).filter(pl.col("id") == 1)
            camera = np.array(LensTable.from_pb(reader.first(T.PTZ_LENS_TABLE)).camera_position, float)
            causal = replay(ReplayRequest(log=log, tracker="golf")).trajectory
            times, cameras = log_context(log)
            t0 = time.process_time()
            found = rescan(causal, log, times, cameras, track_id=1, fps=fps_of(times))
            cpu = time.process_time() - t0
            before, frames_before = G.run_metrics(causal, gt, camera, info["landing_frame"])
            after, frames_after = G.run_metrics(found.trajectory, gt, camera, info["landing_frame"])
            results[key] = {
                "desc": desc, "before": before, "after": after, "rows": found_rows(found.trajectory, gt),
                "rounds": list(found.rounds), "dropped": list(found.dropped), "cpu_s": cpu,
                "misses": G.miss_causes(frames_after, gt, after["start"], scene.shutter),
            }
            trials += [dict(t, run=key) for t in detector_trials(log, causal, gt, times, cameras)]
            r = results[key]
            print(f"{key:9s} detected {G.pct(before['detected'])} -> {G.pct(after['detected'])}  found {r['rows']['found']} "
                  f"(max {G.fmt(r['rows']['max_px'], '.1f')} px, invisible {r['rows']['invisible']})  rounds {r['rounds']}  "
                  f"{cpu:.1f} s", flush=True)
        table = trial_table(trials)
        (HERE / "golf_rescan.json").write_text(json.dumps({"runs": results, "detector": table},
                                                          indent=1, default=float) + "\n")
        write_report(results, table)
    finally:
        if tmp is not None:
            tmp.cleanup()
    print(f"wrote {HERE / 'golf_rescan.md'}")
    return 0


def write_report(results: dict, table: list[dict]) -> None:
    cfg = RescanConfig()
    lines = [
        "# Golf: looking again along the fitted flight (`flight --rescan`)",
        "",
        "> Stays a script, not a `trackreplay evaluate` manifest (docs/README.md): `golf_rescan.py`: it scores `flight --rescan`, an offline analysis of a trajectory after the replay, and the detector's false sightings on searches placed beside the ball; neither is a tracker replay that `evaluate` scores.",
        "",
        "Generated by `python docs/golf_rescan.py` (the logs of docs/golf_synthetic.py; replay seed 0; deterministic).",
        "The causal golf tracker sees one frame at a time with only the past; after the event, `trackreplay flight",
        "TRAJ LOG --rescan OUT` fits the ball's physical flight to what it measured, then looks again in every frame",
        "it did not measure, where the flight puts the ball (replay/analysis/flight_rescan.py): a matched filter of the ball's",
        "fitted image — its size and its path across the sensor during the exposure — in a gate of",
        f"max({cfg.gate_px:g} px, one diameter) round the fitted place, over the luminance's top-hat (≥ {cfg.min_snr:g} robust σ)",
        f"*and* over what stands above the world behind the ball (≥ {cfg.min_new_snr:g} σ; the median of the frames up to",
        f"{cfg.world_frames} either side in which the ball is elsewhere, each brought into this pose). It starts next to",
        f"measured frames (within {cfg.reach}), looks only where {cfg.sigma_factor:g}× the fit's 1-σ in the picture fits",
        "in the gate, refits with what it found and looks again, until a round finds nothing. A frame found is",
        "`measured` with `fill` = `rescan`; the tracker's own rows are not changed.",
        "",
        "Metrics as in docs/golf_synthetic.md (*detected*: `measured` within 5 px, over the visible frames; *re-acquire*:",
        "frames from the landing to the first detected frame, in brackets from the ball's return into view).",
        "",
        "## 1. Causal tracker vs after the rescan",
        "",
        "| run | visible | detected ≤5 px causal → rescan | measured causal → rescan | precision ≤5 px → | RMSE px → | "
        "re-acquire → | `measured` while not visible → | frames found | of them ≤5 px / max px / not visible | rounds (found per round) | CPU s |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for key, r in results.items():
        b, a, f = r["before"], r["after"], r["rows"]
        lines.append(
            f"| {r['desc']} | {a['visible']} | {G.pct(b['detected'])} → **{G.pct(a['detected'])}** | "
            f"{G.pct(b['measured_share'])} → {G.pct(a['measured_share'])} | {G.pct(b['precision'])} → {G.pct(a['precision'])} | "
            f"{G.fmt(b['rmse'], '.1f')} → {G.fmt(a['rmse'], '.1f')} | "
            f"{G.reac(b['reacquire'])} ({G.reac(b['reacquire_in_view'])}) → {G.reac(a['reacquire'])} ({G.reac(a['reacquire_in_view'])}) | "
            f"{b['false_measured']} → {a['false_measured']} of {a['hidden']} | {f['found']} | "
            f"{f['within5']} / {G.fmt(f['max_px'], '.1f')} / {f['invisible']} | {', '.join(map(str, r['rounds']))} | {r['cpu_s']:.1f} |")
    lines += [
        "",
        "Visible frames still missed after the rescan, by cause (as in docs/golf_synthetic.md):",
        "",
        "| run | missed | " + " | ".join(G.MISS_CAUSES) + " |",
        "|---|---|" + "---|" * len(G.MISS_CAUSES),
    ]
    for key, r in results.items():
        m = r["misses"]
        lines.append(f"| {r['desc']} | {sum(m.values())} | " + " | ".join(str(m[c]) for c in G.MISS_CAUSES) + " |")
    lines += [
        "",
        "## 2. The detector: a ball where there is none?",
        "",
        "On every visible frame of the ten shots, the fitted image of the ball (from the causal trajectory's fit) placed",
        "on the true ball, and 15, 25 and 40 px beside it across its path, on both sides (no ball there; cloud puffs,",
        "turf, tee markers, spare balls and the bird are). *False*: searches beside the ball that found one; *found*:",
        "of the visible frames the causal tracker did not measure, those where the search on the true ball found it",
        "(and within 5 px). The defaults are marked.",
        "",
        "| top-hat ≥ σ | world ≥ σ | searches beside the ball | false sightings | missed frames | found | found ≤5 px |",
        "|---|---|---|---|---|---|---|",
    ]
    for row in table:
        default = row["min_snr"] == cfg.min_snr and row["min_new_snr"] == cfg.min_new_snr
        new = "top-hat alone" if row["min_new_snr"] is None else f"{row['min_new_snr']:g}"
        mark = " **(default)**" if default else ""
        lines.append(f"| {row['min_snr']:g}{mark} | {new} | {row['searches']} | {row['false']} ({100 * row['false'] / max(row['searches'], 1):.2f} %) | "
                     f"{row['missed']} | {row['found']} | {row['found_within5']} |")
    lines += ["", "## What this shows", "", FINDINGS.strip(), ""]
    (HERE / "golf_rescan.md").write_text("\n".join(lines) + "\n")


FINDINGS = """
(Written from the numbers above on the commit that added this page; re-read them after a change.)

- **What it adds.** On the nine shots filmed from behind the tee, the share of visible frames measured
  within 5 px goes from 83.6-90.0 % to 88.9-95.3 % (+2.3 to +9.5 points; the default shot 90.0 → 95.3 %);
  183 frames found in all, 175 of them within 5 px of the true ball, the worst 6.5 px (the gate is
  a ball diameter where that is more than 5 px: 6-8 px near the landing, 1080p), none on a frame
  where the ball cannot be seen (`measured` while not visible stays 0 on every shot, the tree's 55
  hidden frames included: the search reaches their edges and finds nothing behind the crown). RMSE
  of all measured frames 0.7-1.1 px. The frames found are the 2-3 px specks after the launch as the
  ball climbs back into the camera's view, the top of the hops and the return from the first hop:
  counted from the ball's return into the picture, re-acquired after 0 frames on five shots, 1 and 2
  on two more (4 causally); `bounce=False` stays at 4, and the encoder dropout at 9 (no poses around
  the landing: nothing to project the flight with).
- **What it does not.** The launch streak (the first ~10 frames in the air: +2 to +5 grey levels above
  the sky spread over 60-120 px) and the first hop's streak at 110 px a frame stay missed: the matched
  filter's response on the true streak is 0-3 sigma there, below anything that could be told from the
  sky's noise; and on the default shot the fit's launch (a launch time known to ~0.1 s) puts the
  ball 15-40 px off on frames 16-17, where the 1-sigma guard refuses to look. The floor of issue 10
  (98 % within 5 px) is not reached: 95.3 % on the default shot, 88.9-95.3 % on the others.
- **The camera beside the tee.** Its fit misses its own observations by 5.2 px RMS (docs/golf_flight.md:
  the launch is guessed, the least squares stops at its evaluation limit); the fitted ball is 23-323 px
  off the true one in the frames the tracker missed, and its 1-sigma in the picture (8-238 px) says so:
  nothing is searched, nothing is found. Looking again is only as good as the flight it follows, and
  it asks the fit's own uncertainty before it looks.
- **Why the world test.** With the top-hat alone, a place 15-40 px beside the ball "found a ball" on
  14.6 % of the searches (cloud puffs the ball's size, turf, the bird): the prior from the flight is
  tight, but not tight enough to make that chance of a puff in the gate harmless. Requiring the same
  template over what also stands above the world behind the ball cuts it to 0.84 % (37 of 4399) while
  finding 233 of the 432 frames the causal tracker missed when placed on the true ball (286 with the
  top-hat alone). Most of the false sightings left are in the seed-0 scene (rendered in six of the
  variants) on frames 29-45, as the ball climbs back into view past cloud puffs while the operator
  whips the camera up: the puffs' motion blur changes from frame to frame there, so the neighbours
  do not show quite the same world. Only places seen by at least two such frames are searched (a
  place off a neighbour's picture has no world behind it to compare with).
"""


if __name__ == "__main__":
    raise SystemExit(main())
