"""Multi-object metrics: CLEAR MOT (MOTA, MOTP, ID switches, FP, FN) and IDF1, on image boxes
(distance 1 − IoU, match below ``1 − min_iou``) or on 3-D positions (Euclidean metres, match below
``max_distance``).

Written here because ``motmetrics`` 1.4.0 (the latest release) calls ``np.asfarray``, gone in
numpy 2. The frame-by-frame matching follows motmetrics' ``MOTAccumulator.update`` exactly:
correspondences of the previous frame are kept while still within the threshold, the rest are
matched by the Hungarian method (scipy), a ground-truth object matched to a different hypothesis
than its last match is an ID switch. IDF1 is the global one-to-one id assignment maximising
identity true positives (motmetrics' ``id_global_assignment``). ``tests/replay/test_mot_parity.py``
runs motmetrics 1.4.0 (numpy 1.26, its own venv) on the same sequences and matches to 1e-6.
HOTA is not implemented.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import asdict, dataclass

import numpy as np
import polars as pl
from scipy.optimize import linear_sum_assignment


@dataclass(frozen=True)
class MotSummary:
    mota: float
    motp: float  # mean matched distance (1 − IoU for boxes, metres for 3-D), as motmetrics reports it
    idf1: float
    id_switches: int
    false_positives: int
    misses: int
    matches: int  # matched pairs, switches included (motmetrics' num_detections; its num_matches = matches − id_switches)
    objects: int  # ground-truth detections
    hypotheses: int  # tracker detections
    idtp: int

    def as_dict(self) -> dict:
        return asdict(self)


Frame = tuple[np.ndarray, np.ndarray, np.ndarray]  # gt ids (n,), hyp ids (m,), distances (n, m) with NaN = no match


def iou_distance(gt_boxes: np.ndarray, hyp_boxes: np.ndarray, max_distance: float = 0.5) -> np.ndarray:
    """``1 − IoU`` of ``x0 y0 w h`` boxes (n, m); NaN where above ``max_distance`` (motmetrics' iou_matrix)."""
    a, b = np.asarray(gt_boxes, np.float64).reshape(-1, 4), np.asarray(hyp_boxes, np.float64).reshape(-1, 4)
    if len(a) == 0 or len(b) == 0:
        return np.zeros((len(a), len(b)))
    lo = np.maximum(a[:, None, :2], b[None, :, :2])
    hi = np.minimum(a[:, None, :2] + a[:, None, 2:], b[None, :, :2] + b[None, :, 2:])
    inter = np.prod(np.clip(hi - lo, 0.0, None), axis=2)
    union = np.prod(a[:, 2:], axis=1)[:, None] + np.prod(b[:, 2:], axis=1)[None, :] - inter
    d = 1.0 - inter / np.where(union > 0, union, 1.0)
    return np.where(d > max_distance, np.nan, d)


def euclidean_distance(gt: np.ndarray, hyp: np.ndarray, max_distance: float) -> np.ndarray:
    """Euclidean distances (n, m); NaN beyond ``max_distance``."""
    a, b = np.asarray(gt, np.float64), np.asarray(hyp, np.float64)
    if len(a) == 0 or len(b) == 0:
        return np.zeros((len(a), len(b)))
    d = np.linalg.norm(a[:, None, :] - b[None, :, :], axis=2)
    return np.where(d > max_distance, np.nan, d)


def clear_mot(frames: Iterable[Frame]) -> MotSummary:
    """CLEAR MOT and IDF1 over a sequence of frames (gt ids, hyp ids, distance matrix)."""
    last: dict[int, int] = {}
    switches = fp = miss = matches = objects = hypotheses = 0
    dist_sum = 0.0
    pair_counts: dict[tuple[int, int], int] = {}
    gt_count: dict[int, int] = {}
    hyp_count: dict[int, int] = {}
    for oids, hids, dists in frames:
        oids, hids = [int(v) for v in oids], [int(v) for v in hids]
        dists = np.asarray(dists, np.float64).reshape(len(oids), len(hids))
        objects += len(oids)
        hypotheses += len(hids)
        for o in oids:
            gt_count[o] = gt_count.get(o, 0) + 1
        for h in hids:
            hyp_count[h] = hyp_count.get(h, 0) + 1
        for i, o in enumerate(oids):
            for j, h in enumerate(hids):
                if np.isfinite(dists[i, j]):
                    pair_counts[(o, h)] = pair_counts.get((o, h), 0) + 1
        free_o, free_h = set(range(len(oids))), set(range(len(hids)))
        pairs: list[tuple[int, int]] = []
        col = {h: j for j, h in enumerate(hids)}
        for i, o in enumerate(oids):  # keep last frame's correspondences that still hold
            h = last.get(o)
            if h is not None and h in col and np.isfinite(dists[i, col[h]]) and col[h] in free_h:
                pairs.append((i, col[h]))
                free_o.discard(i)
                free_h.discard(col[h])
        ro, rh = sorted(free_o), sorted(free_h)
        if ro and rh:
            sub = dists[np.ix_(ro, rh)]
            if np.isfinite(sub).any():
                big = np.nanmax(sub) * 2.0 + 1.0 if np.isfinite(sub).any() else 1.0
                cost = np.where(np.isfinite(sub), sub, 1e9 + big)
                r, c = linear_sum_assignment(cost)
                for a, b in zip(r.tolist(), c.tolist()):
                    if np.isfinite(sub[a, b]):
                        i, j = ro[a], rh[b]
                        if oids[i] in last and last[oids[i]] != hids[j]:
                            switches += 1
                        pairs.append((i, j))
                        free_o.discard(i)
                        free_h.discard(j)
        for i, j in pairs:
            last[oids[i]] = hids[j]
            dist_sum += float(dists[i, j])
        matches += len(pairs)
        miss += len(free_o)
        fp += len(free_h)
    idtp = _idtp(pair_counts, sorted(gt_count), sorted(hyp_count))
    mota = 1.0 - (miss + fp + switches) / objects if objects else float("nan")
    motp = dist_sum / matches if matches else float("nan")
    idf1 = 2.0 * idtp / (objects + hypotheses) if objects + hypotheses else float("nan")
    return MotSummary(mota, motp, idf1, switches, fp, miss, matches, objects, hypotheses, idtp)


def _idtp(pair_counts: dict[tuple[int, int], int], gts: list[int], hyps: list[int]) -> int:
    if not gts or not hyps:
        return 0
    gi, hi = {o: k for k, o in enumerate(gts)}, {h: k for k, h in enumerate(hyps)}
    w = np.zeros((len(gts), len(hyps)))
    for (o, h), n in pair_counts.items():
        w[gi[o], hi[h]] = n
    r, c = linear_sum_assignment(-w)
    return int(w[r, c].sum())


def frames_from_tables(traj: pl.DataFrame, gt: pl.DataFrame, *, space: str = "image", min_iou: float = 0.5,
                       max_distance_m: float = 1.0) -> list[Frame]:
    """Per ground-truth frame: visible truth vs the tracker's rows with a position (``lost`` rows and
    frames before the truth starts are left out). ``space`` is "image" (boxes) or "3d" (X Y Z)."""
    traj = traj.filter(pl.col("x").is_not_null() & (pl.col("status") != "lost"))
    gt = gt.filter(pl.col("visible").fill_null(True))
    out = []
    tr_by = {k[0]: df for k, df in traj.partition_by("frame", as_dict=True).items()} if traj.height else {}
    for (frame,), g in sorted(gt.partition_by("frame", as_dict=True).items()):
        t = tr_by.get(frame, traj.clear())
        if space == "image":
            gb = g.select((pl.col("x") - pl.col("w") / 2), (pl.col("y") - pl.col("h") / 2), "w", "h").to_numpy()
            tb = t.select((pl.col("x") - pl.col("w") / 2), (pl.col("y") - pl.col("h") / 2), "w", "h").to_numpy()
            d = iou_distance(gb, tb, 1.0 - min_iou)
        else:
            d = euclidean_distance(g.select("X", "Y", "Z").to_numpy(), t.select("X", "Y", "Z").to_numpy(), max_distance_m)
        out.append((g["id"].to_numpy(), t["track_id"].to_numpy(), d))
    return out


def mot_metrics(traj: pl.DataFrame, gt: pl.DataFrame, *, space: str = "image", min_iou: float = 0.5,
                max_distance_m: float = 1.0) -> MotSummary:
    return clear_mot(frames_from_tables(traj, gt, space=space, min_iou=min_iou, max_distance_m=max_distance_m))


def format_mot(s: MotSummary, label: str) -> str:
    return (f"{label}: MOTA {s.mota:.3f}  MOTP {s.motp:.3f}  IDF1 {s.idf1:.3f}  IDSW {s.id_switches}  "
            f"FP {s.false_positives}  FN {s.misses}  ({s.objects} truth, {s.hypotheses} tracked)")
