"""Where and why the group tracker's 3-D ID switches happen: the table behind docs/groups.md
("Stable over scene seeds?" → "The switches, one by one").

    python docs/groups_switches.py                                   # groups-merging 0 2, groups-stairs 1 4
    python docs/groups_switches.py --runs groups-merging:0-9 groups-stairs:0-9

Each run is replayed exactly as docs/groups_eval.py does (:func:`groups_eval.evaluate_scene`: 48 fps,
4 s, the scene's SCENE_CONFIG), then the CLEAR-MOT matching of
:func:`trackreplay.replay.analysis.mot.clear_mot` (3-D positions within 1 m) is run again here with
the switches written down: frame, true group, the tracker id it was last matched to (``before``) and
the one it is matched to now (``after``). The count is checked against ``mot_metrics``' ID switches.

Each switch gets the facts the tracker's events and the tables give — when the true group appeared,
what became of ``before`` (deleted after ``tracks.max_empty_frames`` without an update, merged,
absorbed, still alive and where), where ``after`` came from (started, or a merge of which ids) — and
a cause from these rules, first that applies:

- ``at the merge``: the true group was formed by a merge in the truth (it appears after the first
  truth frame; groups-merging's group 3), ``before`` is one of the parts the tracker merged into
  ``after``, and this is the true group's first switch: the truth relabels at the true merge frame,
  the tracker at its merge event, so between the two the merged group is matched to a part's id.
- ``splinter merged back under a new id``: ``after`` is a merge of ``before`` and a track that started
  while the true group already existed (the tracker split the group, then merged the pieces).
- ``splinter absorbed the track``: ``before`` was absorbed by ``after``, a track that started while
  the true group already existed (the piece outlived the original and kept its own id).
- ``track starved, splinter took over``: ``before`` had no update on the frame before the switch
  (it coasts on its prediction; the tracker deletes it after ``tracks.max_empty_frames`` such
  frames) or was deleted by then, and ``after`` started while the true group already existed.
- ``swap``: ``before`` is still alive and matched to another true group.
- ``track drifted off`` (``, splinter nearer`` when ``after`` started while the true group already
  existed): ``before`` is still alive and updated but more than 1 m from the true group.
- ``other``: none of these.

A "splinter" is only a track that started after the true group appeared; the merge and deletion
rules look only at events up to the switch's frame. Counts ``by cause`` at the end; a switch of a
group that stays a group is any switch but ``at the merge``.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import polars as pl
from scipy.optimize import linear_sum_assignment

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))

from groups_eval import evaluate_scene  # noqa: E402
from trackreplay.replay.analysis.mot import frames_from_tables, mot_metrics  # noqa: E402

GATE_M = 1.0  # the 3-D match distance of docs/groups_eval.py's ground_3d_1m
STARTED = re.compile(r"group (\d+) started")
DELETED = re.compile(r"group (\d+) deleted: (.*)")
MERGED = re.compile(r"groups ([\d,]+) (merged into|absorbed by) group (\d+)")


@dataclass(frozen=True)
class Switch:
    frame: int
    truth: int
    before: int
    after: int
    last_matched: int  # the last frame the truth was matched to ``before``


def switches(traj: pl.DataFrame, gt: pl.DataFrame) -> tuple[list[Switch], dict[int, dict[int, int]]]:
    """The ID switches of ``clear_mot`` on 3-D positions within GATE_M (its matching, step for step),
    and per frame the truth → tracker id matches."""
    frame_ids = sorted({int(f) for f in gt["frame"]})
    frames = frames_from_tables(traj, gt, space="3d", max_distance_m=GATE_M)
    last: dict[int, tuple[int, int]] = {}
    found: list[Switch] = []
    matched: dict[int, dict[int, int]] = {}
    for frame, (oids, hids, dists) in zip(frame_ids, frames):
        oids, hids = [int(v) for v in oids], [int(v) for v in hids]
        dists = np.asarray(dists, np.float64).reshape(len(oids), len(hids))
        free_o, free_h, pairs = set(range(len(oids))), set(range(len(hids))), []
        col = {h: j for j, h in enumerate(hids)}
        for i, o in enumerate(oids):  # last frame's correspondences that still hold are kept
            h = last.get(o, (None, 0))[0]
            if h in col and np.isfinite(dists[i, col[h]]) and col[h] in free_h:
                pairs.append((i, col[h]))
                free_o.discard(i)
                free_h.discard(col[h])
        ro, rh = sorted(free_o), sorted(free_h)
        if ro and rh and np.isfinite(sub := dists[np.ix_(ro, rh)]).any():
            r, c = linear_sum_assignment(np.where(np.isfinite(sub), sub, 1e9 + np.nanmax(sub) * 2.0 + 1.0))
            for a, b in zip(r.tolist(), c.tolist()):
                if np.isfinite(sub[a, b]):
                    o, h = oids[ro[a]], hids[rh[b]]
                    if o in last and last[o][0] != h:
                        found.append(Switch(frame, o, last[o][0], h, last[o][1]))
                    pairs.append((ro[a], rh[b]))
        for i, j in pairs:
            last[oids[i]] = (hids[j], frame)
        matched[frame] = {oids[i]: hids[j] for i, j in pairs}
    return found, matched


def parse_events(events: list[str]) -> tuple[dict[int, int], dict[int, tuple[int, str]], dict[int, list[tuple[int, list[int], str]]]]:
    """From the tracker's ``"frame: text"`` events: start frame per id; end (frame, reason) per id
    that was deleted or merged away; per merge product its merges (frame, parts, verb), in order."""
    started, ended, merges = {}, {}, {}
    for line in events:
        frame_s, text = line.split(": ", 1)
        frame = int(frame_s)
        if m := STARTED.match(text):
            started[int(m[1])] = frame
        elif m := DELETED.match(text):
            ended[int(m[1])] = (frame, f"deleted at {frame} ({m[2]})")
        elif m := MERGED.match(text):
            parts, product = [int(p) for p in m[1].split(",")], int(m[3])
            merges.setdefault(product, []).append((frame, parts, m[2]))
            for p in parts:
                if p != product:
                    ended[p] = (frame, f"{m[2]} {product} at {frame}")
    return started, ended, merges


def distance_at(traj: pl.DataFrame, gt: pl.DataFrame, track: int, truth: int, frame: int) -> float | None:
    """3-D distance (m) of ``track`` from ``truth`` at ``frame``; None when either has no position."""
    t = traj.filter((pl.col("frame") == frame) & (pl.col("track_id") == track) & (pl.col("status") != "lost")
                    & pl.col("X").is_not_null())
    g = gt.filter((pl.col("frame") == frame) & (pl.col("id") == truth) & pl.col("visible"))
    if t.is_empty() or g.is_empty():
        return None
    return float(np.linalg.norm(t.select("X", "Y", "Z").to_numpy()[0] - g.select("X", "Y", "Z").to_numpy()[0]))


def facts(s: Switch, traj: pl.DataFrame, gt: pl.DataFrame, matched: dict[int, dict[int, int]], events: list[str]) -> dict:
    """What the tracker's events and the tables say around one switch."""
    started, ended, merges = parse_events(events)
    truth_from = int(gt.filter(pl.col("id") == s.truth)["frame"].min())
    fate = ended.get(s.before, (None, ""))
    before_gone = fate[0] is not None and fate[0] <= s.frame
    measured = traj.filter((pl.col("track_id") == s.before) & (pl.col("status") == "measured") & (pl.col("frame") <= s.frame))
    # the latest merge into ``after`` by the switch (what had happened by then)
    merge = next((m for m in reversed(merges.get(s.after, [])) if m[0] <= s.frame), None)
    origin = []
    if s.after in started:
        origin.append(f"started at {started[s.after]} ({s.frame - started[s.after]} frames before)")
    origin += [f"{m[2]} {s.after} from {','.join(map(str, m[1]))} at {m[0]}" for m in merges.get(s.after, [])]
    return {"frame": s.frame, "truth": s.truth, "truth_from": truth_from,
            "formed_by_merge": truth_from > int(gt["frame"].min()), "before": s.before, "after": s.after,
            "last_matched": s.last_matched, "before_gone": before_gone,
            "before_fate": fate[1] if fate[0] is not None else "alive to the end",
            "before_last_measured": int(measured["frame"].max()) if measured.height else None,
            "before_distance_m": None if before_gone else distance_at(traj, gt, s.before, s.truth, s.frame),
            "before_matched_to": next((o for o, h in matched.get(s.frame, {}).items() if h == s.before and o != s.truth), None),
            "merge": merge, "after_origin": "; ".join(origin) or "-",
            # the pieces the tracker made of a true group: tracks started after the true group appeared
            "splinters": {p for p in (merge[1] if merge else []) + [s.after] if started.get(p, -1) > truth_from}}


def cause(f: dict, first_switch: bool) -> str:
    """The first rule of the module docstring that applies."""
    merge, before, after = f["merge"], f["before"], f["after"]
    from_before = merge is not None and before in merge[1]
    if f["formed_by_merge"] and first_switch and from_before:
        return "at the merge"
    if from_before and merge[2] == "merged into" and f["splinters"] - {before}:
        return "splinter merged back under a new id"
    if from_before and merge[2] == "absorbed by" and after in f["splinters"]:
        return "splinter absorbed the track"
    coasting = f["before_last_measured"] is not None and f["before_last_measured"] < f["frame"] - 1
    if (f["before_gone"] or coasting) and after in f["splinters"]:
        return f"track starved (no update since {f['before_last_measured']}), splinter took over"
    if f["before_matched_to"] is not None:
        return f"swap (before now matched to truth {f['before_matched_to']})"
    if f["before_distance_m"] is not None and f["before_distance_m"] > GATE_M:
        return "track drifted off, splinter nearer" if after in f["splinters"] else "track drifted off"
    return "other"


def explain(s: Switch, first_switch: bool, traj: pl.DataFrame, gt: pl.DataFrame, matched: dict[int, dict[int, int]],
            events: list[str]) -> dict:
    """The facts around one switch (JSON-friendly) and its cause."""
    f = facts(s, traj, gt, matched, events)
    c = cause(f, first_switch)
    f.pop("splinters")
    f.pop("merge")
    d = f["before_distance_m"]
    f["before_distance_m"] = None if d is None else round(d, 2)
    return {**f, "cause": c, "stays_a_group": c != "at the merge"}


def run(scene: str, seed: int, tmp: Path, config: dict | None = None) -> tuple[dict, list[dict]]:
    res, traj, gt = evaluate_scene(scene, 48.0, 4.0, seed, tmp, config)
    found, matched = switches(traj, gt)
    expected = mot_metrics(traj, gt, space="3d", max_distance_m=GATE_M).id_switches
    if len(found) != expected:
        raise AssertionError(f"{scene} seed {seed}: {len(found)} switches found here, clear_mot counts {expected}")
    seen: set[int] = set()
    rows = []
    for s in found:
        rows.append(explain(s, s.truth not in seen, traj, gt, matched, res["events"]))
        seen.add(s.truth)
    return res, rows


def parse_run(text: str) -> tuple[str, list[int]]:
    """``scene:0,2`` or ``scene:0-9``."""
    scene, _, seeds = text.partition(":")
    out: list[int] = []
    for part in seeds.split(","):
        lo, _, hi = part.partition("-")
        out += list(range(int(lo), int(hi or lo) + 1))
    return scene, out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--runs", nargs="+", default=["groups-merging:0,2", "groups-stairs:1,4"],
                    help="scene:seeds, seeds as 0,2 or 0-9")
    ap.add_argument("--config", type=json.loads, default=None,
                    help='tracker config overrides as JSON, as groups_eval.py (e.g. \'{"grouping": {"near_gate": "start"}}\')')
    args = ap.parse_args()
    table, counts = [], {}
    with tempfile.TemporaryDirectory() as tmp:
        for scene, seeds in map(parse_run, args.runs):
            for seed in seeds:
                res, rows = run(scene, seed, Path(tmp), args.config)
                print(f"{scene} seed {seed}: {len(rows)} switches; tracker events: {'; '.join(res['events'])}"
                      + (f"; true merge frame {res['true_merge_frame']}" if "true_merge_frame" in res else ""))
                for r in rows:
                    table.append(f"| {scene} | {seed} | {r['frame']} | {r['truth']} (from {r['truth_from']}) | "
                                 f"{r['before']} → {r['after']} | {r['before_fate']}"
                                 + (f"; {r['before_distance_m']} m off at the switch" if r["before_distance_m"] is not None else "")
                                 + f"; last measured {r['before_last_measured']}"
                                 + f" | {r['after_origin']} | {r['cause']} |")
                    key = r["cause"].split(" (")[0]
                    counts[key] = counts.get(key, 0) + 1
    print("\n| scene | seed | frame | truth (visible from) | tracker id before → after | what became of before "
          "| where after came from | cause |\n|---|---|---|---|---|---|---|---|")
    print("\n".join(table))
    stays = sum(n for c, n in counts.items() if c != "at the merge")
    print(f"\nby cause: {counts}; of a group that stays a group: {stays} of {sum(counts.values())}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
