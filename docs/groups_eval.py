"""The group tracker (seed 003) on every synthetic stereo-crowd scene: the figures behind docs/groups.md.

    python docs/groups_eval.py [--fps 24] [--duration 4.0] [--seeds 0]   # -> docs/groups_results.json, docs/groups_tracks.png

Per scene (``trackreplay synth groups-…``, rendered at ``--fps``, VGA, JPEG 95, the paper's rig):
CLEAR MOT and IDF1 of the group tracks against the per-group truth (/groundtruth/groups) on image
boxes (IoU >= 0.5 and >= 0.3) and on 3-D positions (within 1 m, world frame: the scenes carry the
rig's pose on /stereo/pose, so tracker and truth are both in X Y Z with Z up), HOTA / DetA /
AssA / LocA (mean over alpha 0.05..0.95; similarity IoU, and max(0, 1 - d/1 m) in 3-D), 3-D position
RMSE per true group (per frame a Hungarian match within 1 m; with the share of the group's frames
matched), the tracker's merge events against the true merge frame (groups-merging) and whether any
two groups merged in groups-passing, with the margin by which they did not: per frame the merge
gate's position and velocity distances of every pair of groups over their thresholds
(d2p/gamma_position, d2v/gamma_velocity of the EKF velocities, and the same for the member points'
measured mean velocities, merge.measured_velocity; a pair overlaps on a frame when all are below 1,
and merges after merge.frames such frames in a row). Ground truth is the mean of the group's torso centres and the
union of its members' boxes; the tracker's position is the EKF mean of its KLT observation points.

The paper runs at 48 fps and so does this script by default (4 scenes x 202 frames, ~1 min of CPU).
``--fps 24 --out docs/groups_results_24fps.json --plot ''`` runs the same defaults at 24 fps: the
tracker rescales its per-frame parameters to the log's frame rate (GroupsConfig.at_rate).
The stairs scene gets 32 SGBM disparities (SCENE_CONFIG: its rig sees the group nearer than 5 m).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import polars as pl
from scipy.optimize import linear_sum_assignment

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from trackreplay.recorder.synth.groups.scene import (  # noqa: E402
    GROUNDTRUTH_GROUPS, SCENES, GroupSceneConfig, write_group_scene)
from trackreplay.replay.core.engine import ReplayRequest, iter_steps  # noqa: E402
from trackreplay.replay.core.group_table import group_rows, group_table  # noqa: E402
from trackreplay.replay.log.groundtruth import read_groundtruth  # noqa: E402
from trackreplay.replay.analysis.mot import hota_metrics, mot_metrics  # noqa: E402
from trackreplay.replay.log.reader import LogReader  # noqa: E402
from trackreplay.replay.core.trajectory import state_row, trajectory_table  # noqa: E402
from trackreplay.trackers.groups.merging import measured_velocities, merge_overlap  # noqa: E402

MERGE_EVENTS = ("merged into", "absorbed by")
# The stairs rig (2.1 m high, 15° down) sees the group at 3-6 m: disparities up to 18 px, beyond the
# default 16-disparity SGBM range (made for the 5.1 m rig, d <= 12 px beyond 5 m); with 16 the near
# points get wrong depths and splinter groups start metres away (measured: 3-D MOTA -0.17, 2 switches).
SCENE_CONFIG = {"groups-stairs": {"stereo": {"sgbm": {"num_disparities": 32}}}}


def _deep_merge(a: dict, b: dict) -> dict:
    out = dict(a)
    for k, v in b.items():
        out[k] = _deep_merge(out[k], v) if isinstance(v, dict) and isinstance(out.get(k), dict) else v
    return out


def position_errors(traj: pl.DataFrame, gt: pl.DataFrame, gate_m: float = 1.0) -> dict[int, dict]:
    """Per true group: 3-D RMSE (m) over the frames it is matched (Hungarian per frame, within ``gate_m``)."""
    live = traj.filter((pl.col("status") != "lost") & pl.col("X").is_not_null())
    by_frame = {k[0]: df for k, df in live.partition_by("frame", as_dict=True).items()} if live.height else {}
    err: dict[int, list[float]] = {}
    frames: dict[int, int] = {}
    for (frame,), g in gt.filter(pl.col("visible")).partition_by("frame", as_dict=True).items():
        for gid in g["id"].to_list():
            frames[gid] = frames.get(gid, 0) + 1
        t = by_frame.get(frame)
        if t is None:
            continue
        d = np.linalg.norm(g.select("X", "Y", "Z").to_numpy()[:, None] - t.select("X", "Y", "Z").to_numpy()[None], axis=2)
        r, c = linear_sum_assignment(np.where(d <= gate_m, d, 1e6))
        for i, j in zip(r.tolist(), c.tolist()):
            if d[i, j] <= gate_m:
                err.setdefault(int(g["id"][i]), []).append(float(d[i, j]))
    return {gid: {"rmse_m": float(np.sqrt(np.mean(np.square(err[gid])))) if gid in err else None,
                  "matched": round(len(err.get(gid, [])) / n, 3)} for gid, n in sorted(frames.items())}


def replay_with_gates(req: ReplayRequest) -> tuple[pl.DataFrame, pl.DataFrame, list, list[dict], dict]:
    """Trajectory, second table, events, and per frame and pair of live groups the merge gate's
    d2p/gamma_position and d2v/gamma_velocity (computed as the tracker's _merge does, from the
    frame's group snapshot), plus the tracker's rate-scaled config."""
    rows, extra, events, gates = [], [], [], []
    steps = iter_steps(req)
    try:
        for step in steps:
            rows.extend(state_row(req.tracker, step.frame.index, step.frame.t_ns, s) for s in step.states)
            extra.extend(group_rows(req.tracker, step))
            events.extend((step.frame.index, e) for e in getattr(step.intermediates, "events", ()))
            cfg = steps.tracker.config
            it = step.intermediates
            g = it.groups
            if len(g.ids) < 2:
                continue
            floor = np.eye(3) * cfg.association.min_extent_m**2
            spread = 1.0 if cfg.merge.velocity_spread_in_gate else 0.0
            vcov = np.array([g.P[k][np.ix_([1, 3, 5], [1, 3, 5])] + spread * g.velocity_spread[k] / max(int(g.members[k]), 1)
                             + np.eye(3) * 1e-8 for k in range(len(g.ids))])
            # the point labels are group ids: as indices into the snapshot's groups for the measured velocities
            index = {int(gid): k for k, gid in enumerate(g.ids.tolist())}
            labels = np.array([index.get(int(gid), -1) for gid in it.labels.tolist()], np.int64)
            measured = measured_velocities(it.points.velocity, labels, len(g.ids), cfg.association.min_points,
                                           steps.tracker.contested)
            gate = merge_overlap(g.x[:, [0, 2, 4]], g.extent + floor, g.x[:, [1, 3, 5]], vcov, measured, cfg.merge,
                                 steps.tracker.pose)  # as the tracker's _merge
            for i, j in zip(*np.triu_indices(len(g.ids), 1)):
                m = float(gate.measured[i, j])
                gates.append({"frame": step.frame.index, "pair": f"{g.ids[i]},{g.ids[j]}", "p": float(gate.position[i, j]),
                              "v": float(gate.velocity[i, j]), "m": m if np.isfinite(m) else None,
                              "counts": bool(gate.overlap[i, j])})
        scaled = steps.tracker.config
    finally:
        steps.close()
    info = {"fps": round(steps.tracker.fps, 3), "klt_window": scaled.klt.window, "merge_frames": scaled.merge.frames,
            "max_empty_frames": scaled.tracks.max_empty_frames, "accel_sigma_m_per_frame2": scaled.ekf.accel_sigma,
            "alpha_s": round(scaled.association.alpha_s, 4)}
    return trajectory_table(rows), group_table(extra), events, gates, info


def gate_margin(gates: list[dict], merge_frames: int) -> dict:
    """How far the pairs of groups stayed from merging: the least EKF velocity ratio on frames where
    the positions overlapped, the least max(p, v) ratio (both < 1 and the measured velocities too =
    a frame counted towards a merge), the least measured (member-point) velocity ratio on frames
    where position and EKF velocity both overlapped, the longest run of frames with position and EKF
    velocity overlapping (what counted before merge.measured_velocity) and of counted frames per
    pair against ``merge_frames``."""
    if not gates:
        return {"pairs": 0}
    df = pl.DataFrame(gates, schema={"frame": pl.Int64, "pair": pl.Utf8, "p": pl.Float64, "v": pl.Float64,
                                     "m": pl.Float64, "counts": pl.Boolean}).sort("pair", "frame")
    close = df.filter(pl.col("p") < 1.0)
    both_ekf = df.filter((pl.col("p") < 1.0) & (pl.col("v") < 1.0))
    runs, runs_ekf = {}, {}
    for (pair,), part in df.partition_by("pair", as_dict=True).items():
        runs_ekf[pair] = _longest_run(((part["p"] < 1.0) & (part["v"] < 1.0)).to_numpy(), part["frame"].to_numpy())
        runs[pair] = _longest_run(part["counts"].to_numpy(), part["frame"].to_numpy())
    worst = df.with_columns(pl.max_horizontal("p", "v").alias("mx")).sort("mx").row(0, named=True)
    measured = both_ekf["m"].drop_nulls()
    return {"pairs": df["pair"].n_unique(), "position_overlap_frames": close.height,
            "min_velocity_ratio_while_positions_overlap": None if close.is_empty() else round(float(close["v"].min()), 3),
            "min_max_ratio": round(float(worst["mx"]), 3), "at_frame": worst["frame"], "pair": worst["pair"],
            "position_and_ekf_velocity_overlap_frames": both_ekf.height,
            "min_measured_velocity_ratio_while_both_overlap": None if measured.is_empty() else round(float(measured.min()), 3),
            "longest_position_and_ekf_velocity_run": runs_ekf,
            "longest_overlap_run": runs, "merge_frames": merge_frames}


def _longest_run(flags: np.ndarray, frames: np.ndarray) -> int:
    """The longest run of consecutive frames with ``flags`` set."""
    best = run = 0
    for k in range(len(flags)):  # per frame of one pair (a few hundred), not per pixel
        run = run + 1 if flags[k] and (k == 0 or frames[k] == frames[k - 1] + 1) else int(flags[k])
        best = max(best, run)
    return best


def _hota(s) -> dict:
    return {k: v for k, v in s.as_dict().items() if k != "hota_alpha"}


def evaluate_scene(scene: str, fps: float, duration: float, seed: int, tmp: Path, config: dict | None = None) -> dict:
    cfg = GroupSceneConfig(scene=scene, seed=seed, fps=fps, duration=duration, encoding="jpeg")
    log = tmp / f"{scene}-{seed}.mcap"
    write_group_scene(log, cfg)
    started = time.perf_counter()
    config = _deep_merge(SCENE_CONFIG.get(scene, {}), config or {})
    traj, table, events, gates, rate = replay_with_gates(ReplayRequest(log=log, tracker="groups", seed=0, config=config or None))
    seconds = time.perf_counter() - started
    gt = read_groundtruth(LogReader(log), GROUNDTRUTH_GROUPS)
    out = {
        "scene": scene, "seed": seed, "config": config, "frames": cfg.lead_in + int(round(duration * fps)), "replay_s": round(seconds, 1),
        "rate_scaled": rate, "position_frame": "world" if LogReader(log).topics().get("/stereo/pose") else "camera",
        "image_iou50": mot_metrics(traj, gt, space="image", min_iou=0.5).as_dict(),
        "image_iou30": mot_metrics(traj, gt, space="image", min_iou=0.3).as_dict(),
        "ground_3d_1m": mot_metrics(traj, gt, space="3d", max_distance_m=1.0).as_dict(),
        "hota_image": _hota(hota_metrics(traj, gt, space="image")),
        "hota_3d_1m": _hota(hota_metrics(traj, gt, space="3d", max_distance_m=1.0)),
        "rmse_per_group": position_errors(traj, gt),
        "track_ids": sorted(set(traj["track_id"].to_list())),
        "events": [f"{f}: {e}" for f, e in events],
        "second_table_rows": table.height,
        "merge_gate": gate_margin(gates, rate["merge_frames"]),
    }
    merges = [f for f, e in events if any(k in e for k in MERGE_EVENTS)]
    out["merge_frames"] = merges
    if scene == "groups-merging":
        true_frame = cfg.lead_in + int(np.ceil(cfg.merge_s * fps))  # first frame with t >= merge_s
        out["true_merge_frame"] = true_frame
        out["merge_delay_frames"] = None if not merges else merges[0] - true_frame
        out["merge_delay_s"] = None if not merges else round((merges[0] - true_frame) / fps, 3)
        last = traj.filter(pl.col("frame") == traj["frame"].max())
        out["groups_at_end"] = last.filter(pl.col("status") != "lost").height
    if scene == "groups-passing":
        out["false_merge"] = bool(merges)
    return out, traj, gt


def plot(runs: list[tuple[dict, pl.DataFrame, pl.DataFrame]], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(runs), figsize=(4.2 * len(runs), 4.2))
    for ax, (res, traj, gt) in zip(np.atleast_1d(axes), runs):
        for gid, g in sorted(gt.partition_by("id", as_dict=True).items()):
            ax.plot(g["X"], g["Y"], "k--", lw=1)
            ax.annotate(f"truth {gid[0]}", (g["X"][0], g["Y"][0]), fontsize=7)
        live = traj.filter((pl.col("status") != "lost") & pl.col("X").is_not_null())
        for (tid,), t in sorted(live.partition_by("track_id", as_dict=True).items()):
            ax.plot(t["X"], t["Y"], "-", lw=1.5, label=f"group {tid}")
        ax.set_title(res["scene"], fontsize=9)
        ax.set_xlabel("X (m, world)")
        ax.set_ylabel("Y (m, world; the rig looks along +Y)")
        ax.legend(fontsize=6)
        ax.set_aspect("equal", adjustable="datalim")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--fps", type=float, default=48.0)
    ap.add_argument("--duration", type=float, default=4.0)
    ap.add_argument("--seeds", type=int, nargs="+", default=[0])
    ap.add_argument("--scenes", nargs="+", default=list(SCENES))
    ap.add_argument("--config", type=json.loads, default=None,
                    help='tracker config overrides as JSON, e.g. \'{"merge": {"frames": 10}}\' (per-frame values at rate_hz, 48)')
    ap.add_argument("--out", type=Path, default=HERE / "groups_results.json")
    ap.add_argument("--plot", default=str(HERE / "groups_tracks.png"), help="'' for no plot")
    args = ap.parse_args()
    results, runs = [], []
    with tempfile.TemporaryDirectory() as tmp:
        for scene in args.scenes:
            for seed in args.seeds:
                res, traj, gt = evaluate_scene(scene, args.fps, args.duration, seed, Path(tmp), args.config)
                results.append(res)
                if seed == args.seeds[0]:
                    runs.append((res, traj, gt))
                i50, i30, g3 = res["image_iou50"], res["image_iou30"], res["ground_3d_1m"]
                rmse = ", ".join(f"{k}: {v['rmse_m']:.2f} m ({v['matched']:.0%})" if v["rmse_m"] is not None else f"{k}: -"
                                 for k, v in res["rmse_per_group"].items())
                extra = ""
                if "merge_delay_frames" in res:
                    extra = f"; merge at {res['merge_frames'][:1]} vs truth {res['true_merge_frame']}"
                if "false_merge" in res:
                    extra = f"; false merge: {res['false_merge']}; gate margin {res['merge_gate']}"
                print(f"{scene} seed {seed} ({res['frames']} frames, {res['replay_s']} s): "
                      f"image@0.5 MOTA {i50['mota']:.3f} MOTP {i50['motp']:.3f} IDF1 {i50['idf1']:.3f} IDSW {i50['id_switches']} | "
                      f"image@0.3 MOTA {i30['mota']:.3f} IDF1 {i30['idf1']:.3f} IDSW {i30['id_switches']} | "
                      f"3-D MOTA {g3['mota']:.3f} MOTP {g3['motp']:.3f} m IDF1 {g3['idf1']:.3f} IDSW {g3['id_switches']} | "
                      f"HOTA image {res['hota_image']['hota']:.3f} (DetA {res['hota_image']['deta']:.3f} AssA {res['hota_image']['assa']:.3f}) "
                      f"3-D {res['hota_3d_1m']['hota']:.3f} (DetA {res['hota_3d_1m']['deta']:.3f} AssA {res['hota_3d_1m']['assa']:.3f}) | "
                      f"RMSE {rmse}{extra}")
    args.out.write_text(json.dumps({"fps": args.fps, "duration_s": args.duration, "config": args.config,
                                    "results": results}, indent=1) + "\n")
    if args.plot:
        plot(runs, Path(args.plot))
    print(f"wrote {args.out} and {args.plot}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
