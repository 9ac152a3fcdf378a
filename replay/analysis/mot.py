"""Multi-object metrics: CLEAR MOT (MOTA, MOTP, ID switches, FP, FN) and IDF1, on image boxes
(distance 1 − IoU, match below ``1 − min_iou``) or on 3-D positions (Euclidean metres, match below
``max_distance``).

Written here because ``motmetrics`` 1.4.0 (the latest release) calls ``np.asfarray``, gone in
numpy 2. The frame-by-frame matching follows motmetrics' ``MOTAccumulator.update`` exactly:
correspondences of the previous frame are kept while still within the threshold, the rest are
matched by the Hungarian method (scipy), a ground-truth object matched to a different hypothesis
than its last match is an ID switch. IDF1 is the global one-to-one id assignment maximising
identity true positives (motmetrics' ``id_global_assignment``). ``tests/replay/analysis/test_mot_parity.py``
runs motmetrics 1.4.0 (numpy 1.26, its own venv) on the same sequences and matches to 1e-6.

HOTA (Luiten et al. 2020, IJCV): for each α in 0.05, 0.10 … 0.95, DetA_α = TP/(TP+FN+FP),
AssA_α = mean over TP pairs of the pair's track-level Jaccard |TPA|/(|TPA|+|FNA|+|FPA|),
HOTA_α = sqrt(DetA_α·AssA_α), LocA_α = mean similarity of the TP pairs; each reported figure is the
mean over the 19 α. It needs a similarity in [0, 1] rather than a thresholded distance: IoU for image
boxes, ``max(0, 1 − d/max_distance)`` for 3-D positions. Per frame the pairs are chosen by one
Hungarian assignment maximising similarity × the global alignment score of the two ids (the soft
track-level Jaccard over the whole sequence), as TrackEval does, then kept at each α where the
similarity is ≥ α. ``tests/replay/analysis/test_hota_parity.py`` matches TrackEval 1.3.0 to 1e-6.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator
from dataclasses import asdict, dataclass

import numpy as np
import polars as pl
from scipy.optimize import linear_sum_assignment

from trackreplay.trackers.geometry.box import iou


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
    d = 1.0 - iou(a[:, None], b[None])
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


@dataclass(frozen=True)
class HotaSummary:
    hota: float  # each field is the mean over α = 0.05 … 0.95
    deta: float
    assa: float
    loca: float
    detre: float
    detpr: float
    assre: float
    asspr: float
    hota_alpha: tuple[float, ...]  # HOTA_α per α (ALPHAS)

    def as_dict(self) -> dict:
        return asdict(self)


ALPHAS = np.arange(0.05, 0.99, 0.05)  # 0.05 … 0.95, the same floats as TrackEval
_EPS = np.finfo(float).eps


def iou_similarity(gt_boxes: np.ndarray, hyp_boxes: np.ndarray) -> np.ndarray:
    """IoU of ``x0 y0 w h`` boxes (n, m), unthresholded."""
    d = iou_distance(gt_boxes, hyp_boxes, max_distance=np.inf)
    return 1.0 - d if d.size else d


def distance_similarity(gt: np.ndarray, hyp: np.ndarray, max_distance: float) -> np.ndarray:
    """``max(0, 1 − d / max_distance)`` of Euclidean distances (n, m)."""
    d = euclidean_distance(gt, hyp, np.inf)
    return np.clip(1.0 - d / max_distance, 0.0, None) if d.size else d


def hota(frames: Iterable[Frame] | Callable[[], Iterable[Frame]]) -> HotaSummary:
    """HOTA, DetA, AssA, LocA (and DetRe/DetPr/AssRe/AssPr) over frames of (gt ids, hyp ids,
    similarity (n, m) in [0, 1]; NaN counts as 0). ``frames`` may be a function giving the same frames
    afresh on each call: they are then gone through twice (the global alignment, then each frame's
    assignment) and never held together (issue 33: a long log)."""
    if not callable(frames):
        kept = list(frames)
        frames = lambda: kept  # noqa: E731
    # pass 1, global alignment: soft Jaccard per id pair, each frame's similarity shared out like an IoU
    potential: dict[tuple[int, int], float] = {}
    gt_counts: dict[int, int] = {}
    hyp_counts: dict[int, int] = {}
    n_gt = n_hyp = 0
    for oids, hids, sim in _hota_frames(frames()):
        n_gt += len(oids)
        n_hyp += len(hids)
        if sim.size:
            denom = sim.sum(axis=0, keepdims=True) + sim.sum(axis=1, keepdims=True) - sim
            share = np.where(denom > _EPS, sim / np.where(denom > _EPS, denom, 1.0), 0.0)
            for i, j in zip(*np.nonzero(share)):  # row by row, as np.add.at adds them (a zero adds nothing)
                key = (int(oids[i]), int(hids[j]))
                potential[key] = potential.get(key, 0.0) + float(share[i, j])
        for o in oids.tolist():
            gt_counts[o] = gt_counts.get(o, 0) + 1
        for h in hids.tolist():
            hyp_counts[h] = hyp_counts.get(h, 0) + 1
    gts, hyps = sorted(gt_counts), sorted(hyp_counts)
    gi, hi = {o: k for k, o in enumerate(gts)}, {h: k for k, h in enumerate(hyps)}
    n_alpha = len(ALPHAS)
    tp, fn, fp, loc = np.zeros(n_alpha), np.zeros(n_alpha), np.zeros(n_alpha), np.zeros(n_alpha)
    if n_gt == 0 or n_hyp == 0:  # nothing to match: DetA 0, LocA 1 by convention (as TrackEval)
        zero = np.zeros(n_alpha)
        return _hota_summary(zero, zero + n_gt, zero + n_hyp, np.ones(n_alpha), zero, zero, zero)
    pot = np.zeros((len(gts), len(hyps)))
    for (o, h), v in potential.items():
        pot[gi[o], hi[h]] = v
    gt_count = np.array([[gt_counts[o]] for o in gts], np.float64).reshape(len(gts), 1)
    hyp_count = np.array([hyp_counts[h] for h in hyps], np.float64).reshape(1, len(hyps))
    alignment = pot / (gt_count + hyp_count - pot)
    # pass 2: each frame's pairs, by one assignment maximising similarity x alignment
    pair_tp = np.zeros((n_alpha, len(gts), len(hyps)))
    for oids, hids, sim in _hota_frames(frames()):
        g = np.array([gi[int(o)] for o in oids], np.int64)
        h = np.array([hi[int(v)] for v in hids], np.int64)
        if len(g) == 0 or len(h) == 0:
            fn += len(g)
            fp += len(h)
            continue
        r, c = linear_sum_assignment(-(alignment[np.ix_(g, h)] * sim))
        s = sim[r, c]
        for a, alpha in enumerate(ALPHAS):
            keep = s >= alpha - _EPS
            k = int(keep.sum())
            tp[a] += k
            fn[a] += len(g) - k
            fp[a] += len(h) - k
            loc[a] += s[keep].sum()
            np.add.at(pair_tp[a], (g[r[keep]], h[c[keep]]), 1)
    ass_a, ass_re, ass_pr = np.zeros(n_alpha), np.zeros(n_alpha), np.zeros(n_alpha)
    for a in range(n_alpha):
        m = pair_tp[a]
        denom = max(1.0, tp[a])
        ass_a[a] = (m * m / np.maximum(1.0, gt_count + hyp_count - m)).sum() / denom
        ass_re[a] = (m * m / np.maximum(1.0, gt_count)).sum() / denom
        ass_pr[a] = (m * m / np.maximum(1.0, hyp_count)).sum() / denom
    loca = np.maximum(1e-10, loc) / np.maximum(1e-10, tp)
    return _hota_summary(tp, fn, fp, loca, ass_a, ass_re, ass_pr)


def _hota_frames(frames: Iterable[Frame]) -> Iterator[Frame]:
    for oids, hids, sim in frames:
        oids, hids = np.asarray(oids, np.int64).ravel(), np.asarray(hids, np.int64).ravel()
        yield oids, hids, np.nan_to_num(np.asarray(sim, np.float64).reshape(len(oids), len(hids)), nan=0.0)


def _hota_summary(tp, fn, fp, loca, ass_a, ass_re, ass_pr) -> HotaSummary:
    det_a = tp / np.maximum(1.0, tp + fn + fp)
    det_re = tp / np.maximum(1.0, tp + fn)
    det_pr = tp / np.maximum(1.0, tp + fp)
    h = np.sqrt(det_a * ass_a)
    return HotaSummary(float(h.mean()), float(det_a.mean()), float(ass_a.mean()), float(loca.mean()),
                       float(det_re.mean()), float(det_pr.mean()), float(ass_re.mean()), float(ass_pr.mean()),
                       tuple(float(v) for v in h))


def frames_from_tables(traj: pl.DataFrame, gt: pl.DataFrame, *, space: str = "image", min_iou: float = 0.5,
                       max_distance_m: float = 1.0, similarity: bool = False,
                       frames: Iterable[int] | None = None) -> list[Frame]:
    """Per annotated frame: visible truth vs the tracker's rows with a position (``lost`` rows left out).
    ``space`` is "image" (boxes) or "3d" (X Y Z). With ``similarity`` the matrices are HOTA
    similarities (IoU; ``max(0, 1 − d/max_distance_m)``) instead of thresholded distances.

    The annotated frames are ``frames`` (every ground-truth message's, from
    :func:`~trackreplay.replay.log.groundtruth.groundtruth_with_frames`), else those with a truth row.
    A frame the truth annotates with no visible object (hidden, out of the picture, or none listed)
    counts like any other: a box there is a false positive, an unmatched prediction in HOTA. Invisible
    truth is not an ignore region (MOTChallenge's zero-marked rows are dropped on import); frames the
    truth does not annotate (before it starts, after it ends) are left out."""
    traj = traj.filter(pl.col("x").is_not_null() & (pl.col("status") != "lost"))
    annotated = sorted({int(f) for f in (gt["frame"] if frames is None else frames)})
    visible = gt.filter(pl.col("visible").fill_null(True))
    gt_by = {k[0]: df for k, df in visible.partition_by("frame", as_dict=True).items()} if visible.height else {}
    tr_by = {k[0]: df for k, df in traj.partition_by("frame", as_dict=True).items()} if traj.height else {}
    out = []
    for frame in annotated:
        g, t = gt_by.get(frame, visible.clear()), tr_by.get(frame, traj.clear())
        if space == "image":
            gb = g.select((pl.col("x") - pl.col("w") / 2), (pl.col("y") - pl.col("h") / 2), "w", "h").to_numpy()
            tb = t.select((pl.col("x") - pl.col("w") / 2), (pl.col("y") - pl.col("h") / 2), "w", "h").to_numpy()
            d = iou_similarity(gb, tb) if similarity else iou_distance(gb, tb, 1.0 - min_iou)
        elif similarity:
            d = distance_similarity(g.select("X", "Y", "Z").to_numpy(), t.select("X", "Y", "Z").to_numpy(), max_distance_m)
        else:
            d = euclidean_distance(g.select("X", "Y", "Z").to_numpy(), t.select("X", "Y", "Z").to_numpy(), max_distance_m)
        out.append((g["id"].to_numpy(), t["track_id"].to_numpy(), d))
    return out


def three_d_missing(traj: pl.DataFrame, gt: pl.DataFrame) -> str | None:
    """Why the 3-D block does not apply (the trajectory's positioned rows, or the visible truth, have
    no ``X, Y, Z`` at all: a 2-D tracker or truth), or None when both have some."""
    def has(df: pl.DataFrame) -> bool:
        return df.select(pl.all_horizontal(pl.col(c).is_not_null() for c in "XYZ").any()).item() is True

    if not has(traj.filter(pl.col("x").is_not_null() & (pl.col("status") != "lost"))):
        return "the trajectory has no X, Y, Z"
    if not has(gt.filter(pl.col("visible").fill_null(True))):
        return "the ground truth has no X, Y, Z"
    return None


MAX_DISTANCE_M = 1.0  # the 3-D match distance (m) by default: `eval --mot`'s and `batch`'s


def mot_metrics(traj: pl.DataFrame, gt: pl.DataFrame, *, space: str = "image", min_iou: float = 0.5,
                max_distance_m: float = MAX_DISTANCE_M, frames: Iterable[int] | None = None) -> MotSummary:
    return clear_mot(frames_from_tables(traj, gt, space=space, min_iou=min_iou, max_distance_m=max_distance_m, frames=frames))


def hota_metrics(traj: pl.DataFrame, gt: pl.DataFrame, *, space: str = "image", max_distance_m: float = MAX_DISTANCE_M,
                 frames: Iterable[int] | None = None) -> HotaSummary:
    return hota(frames_from_tables(traj, gt, space=space, max_distance_m=max_distance_m, similarity=True, frames=frames))


def format_hota(s: HotaSummary, label: str) -> str:
    return f"{label}: HOTA {s.hota:.3f}  DetA {s.deta:.3f}  AssA {s.assa:.3f}  LocA {s.loca:.3f}"


def format_mot(s: MotSummary, label: str) -> str:
    return (f"{label}: MOTA {s.mota:.3f}  MOTP {s.motp:.3f}  IDF1 {s.idf1:.3f}  IDSW {s.id_switches}  "
            f"FP {s.false_positives}  FN {s.misses}  ({s.objects} truth, {s.hypotheses} tracked)")


# --- a long log a chunk of frames at a time (issue 33) ---------------------------------------------------
CHUNK_FRAMES = 4096  # annotated frames read, matched and scored at a time


def truth_chunks(reader, topic: str, chunk_frames: int | None = None):
    """``chunks()``: the log's truth ``chunk_frames`` (:data:`CHUNK_FRAMES`) messages at a time, each as (its
    annotated frames, their rows), the rows as
    :func:`~trackreplay.replay.log.groundtruth.groundtruth_with_frames` reads them (``GroundTruthFrame.from_pb``,
    its columns). For a log whose messages come in increasing frame order, an object at most once in each,
    and without a rig pose (whose world transform is applied to the whole table at once)."""
    from trackreplay.replay.log.groundtruth import GT_SCHEMA
    from trackreplay.schemas.records import GroundTruthFrame

    chunk_frames = chunk_frames or CHUNK_FRAMES

    def chunks():
        rows: list[tuple] = []
        frames: list[int] = []
        for item in reader.messages([topic]):
            gt = GroundTruthFrame.from_pb(item.decode())
            frames.append(gt.frame)
            for o in gt.objects:
                rows.append((gt.frame, gt.t_ns, o.id, o.x, o.y, o.w, o.h, o.X, o.Y, o.Z, o.vx, o.vy, o.visible, o.group))
            if len(frames) >= chunk_frames:
                yield np.array(frames, np.int64), pl.DataFrame(rows, schema=GT_SCHEMA, orient="row")
                rows, frames = [], []
        if frames:
            yield np.array(frames, np.int64), pl.DataFrame(rows, schema=GT_SCHEMA, orient="row")

    return chunks


class ChunkedTables:
    """The trajectory (a lazy Parquet scan: each chunk's frames read with the filter pushed down) and the
    truth (``truth()``: :func:`truth_chunks`) a chunk of frames at a time, for :func:`mot_metrics_chunked` and
    :func:`hota_metrics_chunked`; also notes whether the visible truth has X, Y, Z (:func:`three_d_missing`)."""

    def __init__(self, traj: pl.LazyFrame, truth) -> None:
        self.traj, self.truth = traj, truth
        self.truth_located: bool | None = None  # known once the truth has been gone through

    def chunks(self):
        located = False
        for annotated, gt in self.truth():
            lo, hi = int(annotated.min()), int(annotated.max())
            rows = self.traj.filter(pl.col("frame").is_between(lo, hi) & pl.col("x").is_not_null()
                                    & (pl.col("status") != "lost")).select(
                "tracker", "track_id", "frame", "x", "y", "w", "h", "X", "Y", "Z").collect()
            visible = gt.filter(pl.col("visible").fill_null(True))
            located = located or _has_xyz(visible)
            # the whole table's order within a frame: the truth by object, the trajectory by tracker and track
            yield (np.unique(annotated), visible.sort(["frame", "id"], maintain_order=True),
                   rows.sort(["frame", "tracker", "track_id"], maintain_order=True))
        self.truth_located = located

    def three_d_missing(self) -> str | None:
        """:func:`three_d_missing` of the whole tables."""
        if not self.traj.filter(pl.col("x").is_not_null() & (pl.col("status") != "lost")
                                & pl.all_horizontal(pl.col(c).is_not_null() for c in "XYZ")).select(pl.len()).collect().item():
            return "the trajectory has no X, Y, Z"
        if self.truth_located is None:
            for _ in self.chunks():
                pass
        return None if self.truth_located else "the ground truth has no X, Y, Z"


def _has_xyz(df: pl.DataFrame) -> bool:
    return df.select(pl.all_horizontal(pl.col(c).is_not_null() for c in "XYZ").any()).item() is True


def frames_from_chunks(chunks, *, space: str = "image", min_iou: float = 0.5, max_distance_m: float = 1.0,
                       similarity: bool = False) -> Iterator[Frame]:
    """:func:`frames_from_tables`' frames from ``chunks`` of (annotated frames (sorted, unique), the visible
    truth on them by frame and object, the trajectory's positioned rows on them (not lost) by frame,
    tracker and track): the same frames, with the same values, one chunk held at a time."""
    for annotated, g, t in chunks:
        gf, tf = g["frame"].to_numpy(), t["frame"].to_numpy()
        if space == "image":
            box = (pl.col("x") - pl.col("w") / 2), (pl.col("y") - pl.col("h") / 2), "w", "h"
            gv, tv = g.select(*box).to_numpy(), t.select(*box).to_numpy()
        else:
            gv, tv = g.select("X", "Y", "Z").to_numpy(), t.select("X", "Y", "Z").to_numpy()
        gid, tid = g["id"].to_numpy(), t["track_id"].to_numpy()
        ga, gb = np.searchsorted(gf, annotated, "left"), np.searchsorted(gf, annotated, "right")
        ta, tb = np.searchsorted(tf, annotated, "left"), np.searchsorted(tf, annotated, "right")
        for k in range(len(annotated)):
            a, b = np.ascontiguousarray(gv[ga[k]:gb[k]]), np.ascontiguousarray(tv[ta[k]:tb[k]])
            if space == "image":
                d = iou_similarity(a, b) if similarity else iou_distance(a, b, 1.0 - min_iou)
            elif similarity:
                d = distance_similarity(a, b, max_distance_m)
            else:
                d = euclidean_distance(a, b, max_distance_m)
            yield gid[ga[k]:gb[k]], tid[ta[k]:tb[k]], d


def mot_metrics_chunked(tables: ChunkedTables, *, space: str = "image", min_iou: float = 0.5,
                        max_distance_m: float = MAX_DISTANCE_M) -> MotSummary:
    """:func:`mot_metrics` a chunk of frames at a time (one pass)."""
    return clear_mot(frames_from_chunks(tables.chunks(), space=space, min_iou=min_iou, max_distance_m=max_distance_m))


def hota_metrics_chunked(tables: ChunkedTables, *, space: str = "image",
                         max_distance_m: float = MAX_DISTANCE_M) -> HotaSummary:
    """:func:`hota_metrics` a chunk of frames at a time (two passes)."""
    return hota(lambda: frames_from_chunks(tables.chunks(), space=space, max_distance_m=max_distance_m, similarity=True))
