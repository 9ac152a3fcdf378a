"""The group tracker on PETS09 S2L1 with config changes, and who is covered when: the tables behind
docs/groups_pets.md ("Who was below 80 %, and why": the per-person table and the before/after rows).

    trackreplay evaluate benchmarks/corpora/pets.toml --out runs/pets --seeds 0-2      # records runs/pets/logs/*.mcap
    python docs/groups_pets_configs.py runs/pets/logs/pets09_s2l1-*.mcap \\
        --config '{}' '{"grouping": {"near_gate": "start"}}' [--people]

Each ``--config`` (JSON, the tracker's TOML tables; ``{}`` the defaults) is one replay (seed 0: the
tracker draws no random number) of the log ``evaluate`` recorded, scored exactly as ``evaluate``
scores it (:func:`trackreplay.replay.runs.evaluate.score`: the ``ground_*`` columns). ``--people``
adds, per person below 80 % of their frames, where and when they are missed: their frames, the share
covered, their median distance from the camera's ground point, how many of their missed frames they
spend within 1.5 m of another person (a group the truth may or may not call one), on how many a
``predicted`` row (a group coasting without points) is within 1.5 m and a ``measured`` one within
1.5-3 m (placed too far off) and that row's median offset away from the camera (m; + farther),
their truth box's median height and foot row on the missed frames, and the missed frames' span.
``--foreground ID ...`` adds, per such person and 40 frames, the share of their truth box that the
tracker's foreground covers (from a second replay, stepped) and the share of their frames under 10 %.
``--causes`` adds, from a second replay (stepped), every person's missed frames split by the first
cause that applies (:data:`CAUSES`); ``--frames ID ...`` with it, one row per missed frame of those
people (what the frame showed: :func:`missed_causes`).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
import polars as pl

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from trackreplay.replay.analysis.group_ground import _nearest, derive_groups, group_ground_scores  # noqa: E402
from trackreplay.replay.core.engine import ReplayRequest, iter_steps, replay  # noqa: E402
from trackreplay.replay.log.groundtruth import groundtruth_with_frames  # noqa: E402
from trackreplay.replay.log.reader import LogReader  # noqa: E402
from trackreplay.replay.runs.batch import multi_object_metrics  # noqa: E402

COLUMNS = ("person_coverage", "person_coverage_min", "people_at_goal", "people", "wrong_rate", "group_mota",
           "group_idf1", "group_id_switches", "merges_found", "splits_found")


def people_below(traj: pl.DataFrame, gt: pl.DataFrame, frames: list[int], camera_xy: np.ndarray | None,
                 goal: float = 0.8, radius_m: float = 1.5) -> list[dict]:
    """Per person under ``goal``: frames, covered share, median distance from the camera (m), missed
    frames spent within ``radius_m`` of another person, and the missed frames' first and last."""
    groups = derive_groups(gt).filter(pl.col("frame").is_in(frames))
    near = _nearest(groups, traj.filter((pl.col("status") == "measured") & pl.col("X").is_not_null()
                                        & pl.col("frame").is_in(frames)), radius_m)
    out = []
    for (pid,), p in near.group_by(["id"], maintain_order=True):
        share = float(p["track"].is_not_null().mean())
        if share >= goal:
            continue
        missed = p.filter(pl.col("track").is_null())["frame"].to_list()
        me = groups.filter(pl.col("id") == pid)
        dist = (float(np.median(np.linalg.norm(me.select("X", "Y").to_numpy() - camera_xy, axis=1)))
                if camera_xy is not None else float("nan"))
        crowded = coasting = off = 0
        radial: list[float] = []
        for f in missed:
            here = groups.filter(pl.col("frame") == f)
            xy = here.filter(pl.col("id") == pid).select("X", "Y").to_numpy()
            others = here.filter(pl.col("id") != pid).select("X", "Y").to_numpy()
            crowded += int(len(others) > 0 and np.linalg.norm(others - xy, axis=1).min() <= radius_m)
            rows = traj.filter((pl.col("frame") == f) & pl.col("X").is_not_null())
            d = np.linalg.norm(rows.select("X", "Y").to_numpy() - xy, axis=1) if rows.height else np.zeros(0)
            status = rows["status"].to_list()
            coasting += int(any(s == "predicted" and dd <= radius_m for s, dd in zip(status, d)))
            off += int(any(s == "measured" and radius_m < dd <= 2 * radius_m for s, dd in zip(status, d)))
            m = [k for k, (s, dd) in enumerate(zip(status, d)) if s == "measured" and radius_m < dd <= 2 * radius_m]
            if m and camera_xy is not None:  # the nearest such row: farther from the camera (+) or nearer (-)
                k = min(m, key=lambda k: d[k])
                xy_row = rows.select("X", "Y").to_numpy()[k]
                radial.append(float(np.linalg.norm(xy_row - camera_xy) - np.linalg.norm(xy[0] - camera_xy)))
        box = gt.filter((pl.col("id") == pid) & pl.col("frame").is_in(missed))
        out.append({"id": int(pid), "frames": p.height, "covered": round(share, 3), "camera_m": round(dist, 1),
                    "missed": len(missed), "missed_near_another": crowded,
                    "missed_predicted_within": coasting, "missed_measured_1_2x": off,
                    "off_radial_m": round(float(np.median(radial)), 2) if radial else None,
                    "missed_box_h_px": round(float(box["h"].median()), 0) if box.height else None,
                    "missed_foot_row": round(float((box["y"] + box["h"] / 2).median()), 0) if box.height else None,
                    "missed_span": f"{min(missed)}-{max(missed)}" if missed else "-"})
    return sorted(out, key=lambda r: r["covered"])


def foreground_in_boxes(log: Path, cfg: dict, gt: pl.DataFrame, ids: list[int], span: int = 40) -> list[dict]:
    """Per person of ``ids`` and per ``span`` frames: the mean share of their truth box that the tracker's
    foreground covers, and the share of their frames with under 10 % of it (a second replay, stepped)."""
    boxes = {(f, i): (x, y, w, h) for f, i, x, y, w, h in
             gt.filter(pl.col("id").is_in(ids)).select("frame", "id", "x", "y", "w", "h").iter_rows()}
    seen: dict[int, list[tuple[int, float]]] = {i: [] for i in ids}
    steps = iter_steps(ReplayRequest(log=log, tracker="groups", seed=0, config=cfg or None))
    for step in steps:
        fg = step.intermediates.fg_left
        for i in ids:
            box = boxes.get((step.frame.index, i))
            if box is None:
                continue
            x, y, w, h = box  # (x, y) the box's centre
            x0, y0 = max(int(x - w / 2), 0), max(int(y - h / 2), 0)
            inside = fg[y0:int(y + h / 2), x0:int(x + w / 2)]
            seen[i].append((step.frame.index, float(inside.mean()) if inside.size else 0.0))
    out = []
    for i in ids:
        a = np.array(seen[i]).reshape(-1, 2)
        for lo in range(0, int(a[:, 0].max()) + 1 if len(a) else 0, span):
            part = a[(a[:, 0] >= lo) & (a[:, 0] < lo + span), 1]
            if len(part):
                out.append({"id": i, "frames": f"{lo}-{lo + span - 1}", "foreground": round(float(part.mean()), 2),
                            "under_10pct": round(float((part < 0.1).mean()), 2)})
    return out


CAUSES = ("learning", "no foreground", "placed too far", "placed too near", "coasting", "points unassigned", "other")


def missed_causes(log: Path, cfg: dict, gt: pl.DataFrame, radius_m: float = 1.5,
                  detail: tuple[int, ...] = ()) -> tuple[pl.DataFrame, list[dict]]:
    """Per person and cause (:data:`CAUSES`), their frames with no ``measured`` row within ``radius_m``, each
    given the first cause that applies: the tracker was still learning its background; under 10 % of the
    truth box is foreground; the median ground point of the box's foreground pixels is over 1 m farther
    from the camera than the truth, or over 1 m nearer; a ``predicted`` row (a group coasting) is within
    ``radius_m``; observation points in the box were left unassigned; else other. Also ``frames``: theirs.
    Second, for the people in ``detail``, one row per missed frame: the cause, the share of the box in the
    foreground, the foreground's rows in the box's columns and the truth box's, the placement's offset
    from the camera (m, + farther), the points in the box and their group ids (-1 none), and the nearest
    measured and any row (group id, metres, status)."""
    truth = {f: g for (f,), g in gt.filter(pl.col("X").is_not_null()).group_by(["frame"])}
    counts: dict[tuple[int, str], int] = {}
    frames: dict[int, int] = {}
    rows_out: list[dict] = []
    for step in iter_steps(ReplayRequest(log=log, tracker="groups", seed=0, config=cfg or None)):
        people = truth.get(step.frame.index)
        if people is None:
            continue
        it = step.intermediates
        rows, camera = np.zeros((0, 2)), None
        if it.mode == "tracking":
            g = it.groups
            rows = it.world.to_world(g.x[:, [0, 2, 4]])[:, :2] if len(g.ids) else rows
            camera = it.rig.pose.t[:2]
        for pid, x, y, w, h, X, Y in people.select("id", "x", "y", "w", "h", "X", "Y").iter_rows():
            frames[pid] = frames.get(pid, 0) + 1
            xy = np.array([X, Y])
            d = np.linalg.norm(rows - xy, axis=1)
            status = np.array(it.groups.status if it.mode == "tracking" else (), dtype=object)
            if ((status == "measured") & (d <= radius_m)).any():
                continue
            cause = "learning" if it.mode != "tracking" else "other"
            box, inside, v, off = np.zeros((0, 0), bool), np.zeros(0, bool), np.zeros(0), 0.0
            x0, y0, x1, y1 = int(max(x - w / 2, 0)), int(max(y - h / 2, 0)), int(x + w / 2), int(y + h / 2)
            if it.mode == "tracking":
                box = it.fg_left[y0:y1, x0:x1]
                v, u = np.nonzero(box & np.isfinite(it.disparity[y0:y1, x0:x1]))
                off = 0.0
                if len(v):
                    uvd = np.stack([u + x0, v + y0, it.disparity[v + y0, u + x0]], axis=1).astype(np.float64)
                    placed = np.median(it.rig.pose.to_world(it.rig.to_points(uvd))[:, :2], axis=0)
                    off = float(np.linalg.norm(placed - camera) - np.linalg.norm(xy - camera))
                uv = it.points.uvd[:, :2]
                inside = (uv[:, 0] >= x0) & (uv[:, 0] < x1) & (uv[:, 1] >= y0) & (uv[:, 1] < y1)
                if not box.size or box.mean() < 0.1:
                    cause = "no foreground"
                elif off > 1.0:
                    cause = "placed too far"
                elif off < -1.0:
                    cause = "placed too near"
                elif ((status == "predicted") & (d <= radius_m)).any():
                    cause = "coasting"
                elif (it.labels[inside] < 0).any():
                    cause = "points unassigned"
            counts[(pid, cause)] = counts.get((pid, cause), 0) + 1
            if pid in detail and it.mode == "tracking":
                ids = it.groups.ids
                fg_rows = np.flatnonzero(it.fg_left[:, x0:x1].any(axis=1))
                fg_rows = fg_rows[(fg_rows >= y0 - 0.5 * h) & (fg_rows <= y1 + 0.5 * h)]
                meas = np.flatnonzero(status == "measured")
                m = meas[np.argmin(d[meas])] if len(meas) else None
                a = int(np.argmin(d)) if len(d) else None
                rows_out.append({
                    "id": pid, "frame": step.frame.index, "cause": cause, "foreground": round(float(box.mean()), 2),
                    "fg_rows": f"{fg_rows.min()}-{fg_rows.max()}" if len(fg_rows) else "-", "box_rows": f"{y0}-{y1}",
                    "placed_m": round(off, 2) if len(v) else None, "points": int(inside.sum()),
                    "labels": sorted(set(it.labels[inside].tolist())),
                    "measured": f"{ids[m]} at {d[m]:.2f} m" if m is not None else "-",
                    "nearest": f"{ids[a]} at {d[a]:.2f} m, {status[a]}" if a is not None else "-"})
    out = pl.DataFrame([{"id": pid, "frames": n, **{c: counts.get((pid, c), 0) for c in CAUSES}}
                        for pid, n in sorted(frames.items())])
    return out.with_columns(missed=pl.sum_horizontal(*CAUSES)), rows_out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("log", type=Path)
    ap.add_argument("--config", nargs="+", type=json.loads, default=[{}])
    ap.add_argument("--people", action="store_true")
    ap.add_argument("--foreground", type=int, nargs="+", default=None, metavar="ID",
                    help="per person ID and 40 frames, the share of their truth box in the foreground (a second replay)")
    ap.add_argument("--causes", action="store_true", help="every person's missed frames by cause (a second replay)")
    ap.add_argument("--frames", type=int, nargs="+", default=(), metavar="ID",
                    help="with --causes: each missed frame of these people, one row each")
    ap.add_argument("--save", type=Path, default=None, help="write each replay's trajectory here (config_<k>.parquet)")
    args = ap.parse_args()
    reader = LogReader(args.log)
    gt, annotated = groundtruth_with_frames(reader)
    frames = annotated["frame"].to_list()
    print("| config | " + " | ".join(COLUMNS) + " | image MOTA |\n|" + "---|" * (len(COLUMNS) + 2))
    for cfg in args.config:
        result = replay(ReplayRequest(log=args.log, tracker="groups", seed=0, config=cfg or None))
        traj = result.trajectory
        if args.save is not None:
            args.save.mkdir(parents=True, exist_ok=True)
            traj.write_parquet(args.save / f"config_{args.config.index(cfg)}.parquet")
        row = group_ground_scores(traj, gt, frames).row("")
        mot = multi_object_metrics(traj, gt, annotated["frame"])
        print(f"| `{json.dumps(cfg)}` | " + " | ".join(f"{row[c]:.3f}" if isinstance(row[c], float) else str(row[c])
                                                      for c in COLUMNS) + f" | {mot.get('mota', float('nan')):.3f} |")
        if args.people:
            plane = reader.first("/camera/ground_plane")
            camera = np.array([plane.camera_ground_x, plane.camera_ground_y]) if plane is not None else None
            for r in people_below(traj, gt, frames, camera):
                print("   ", r)
        if args.foreground:
            for r in foreground_in_boxes(args.log, cfg, gt, args.foreground):
                print("    foreground", r)
        if args.causes:
            table, detail = missed_causes(args.log, cfg, gt, detail=tuple(args.frames))
            print("    | id | frames | missed | covered | " + " | ".join(CAUSES) + " |\n    |" + "---|" * (len(CAUSES) + 4))
            for r in table.iter_rows(named=True):
                print(f"    | {r['id']} | {r['frames']} | {r['missed']} | {1 - r['missed'] / r['frames']:.3f} | "
                      + " | ".join(str(r[c]) for c in CAUSES) + " |")
            total = table.select(*CAUSES, "missed").sum().row(0, named=True)
            print("    | all | " + str(table["frames"].sum()) + f" | {total['missed']} | | "
                  + " | ".join(str(total[c]) for c in CAUSES) + " |")
            for r in detail:
                print("    frame", r)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
