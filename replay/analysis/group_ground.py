"""Groups of people scored on the ground, in metres: group truth derived from people's world tracks,
and a group tracker's rows measured against the people and those groups.

**Group truth** (:class:`GroupRule`, :func:`derive_groups`). Each person's ground velocity is the
least-squares slope of their positions over ``velocity_window_s`` around the frame. Two people are
*linked* on a frame where both are placed, at most ``distance_m`` apart, with velocities differing
by at most ``speed_m_s``; link gaps of at most ``gap_s`` are closed (a one-frame flicker does not
split a group), and a pair is *together* on the frames of a linked run lasting at least
``min_duration_s``. A frame's groups are the connected components of the together-pairs (a person
with no partner is a group of one). A group's identity is its member set, its position the mean of
its members'. A **merge** is a group on frame f whose members were in two or more groups on frame
f-1; a **split** is a group of f-1 whose members are in two or more groups on f (only members
present on both frames count).

**Scores** (:func:`group_ground_scores`), with ``radius_m`` (1.5 m) as the match distance, on the
tracker's rows inside the *labelled area*: the convex hull of every ground position the truth
gives. Truth labels people in an area (PETS 2009 marks those beyond it ``conf = 0``, "ignore", and
``record`` leaves such rows out); a row outside it has nobody to match and is not scored either way
(``outside_rows`` counts them), as MOTChallenge ignores hypotheses on ignored objects.

- person coverage: the share of person-frames with a ``measured`` row (inside the area or not) within ``radius_m``
  (pooled; per person the least, and how many people reach ``coverage_goal`` of their frames);
- wrong rate: the share of ``measured`` rows (on annotated frames) with no person within ``radius_m``;
- group MOTA, MOTP (m), IDF1 and ID switches against the derived groups (positioned rows, i.e.
  measured and predicted, as hypotheses), by :func:`trackreplay.replay.analysis.mot.clear_mot`;
- merges/splits found: a truth merge is found when, on some frame within ``event_window_s`` of it,
  every member present is covered and their nearest ``measured`` rows are one track; a split when
  the members' nearest rows are two tracks or more (each member covered).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import asdict, dataclass

import numpy as np
import polars as pl
from scipy.sparse import coo_matrix
from scipy.spatial import Delaunay
from scipy.sparse.csgraph import connected_components

from trackreplay.replay.analysis.mot import clear_mot, euclidean_distance


@dataclass(frozen=True)
class GroupRule:
    """When people walk together (module docstring)."""

    distance_m: float = 1.5
    speed_m_s: float = 0.5
    min_duration_s: float = 1.0
    gap_s: float = 0.5
    velocity_window_s: float = 1.0


@dataclass(frozen=True)
class GroupGroundScores:
    person_coverage: float
    person_coverage_min: float
    people: int
    people_at_goal: int
    wrong_rate: float
    measured_rows: int  # measured rows inside the labelled area (the wrong rate's denominator)
    outside_rows: int  # positioned rows outside it (not scored)
    group_mota: float
    group_motp: float
    group_idf1: float
    group_id_switches: int
    truth_groups: int  # distinct member sets of two people or more
    merges: int
    merges_found: int
    splits: int
    splits_found: int

    def row(self, prefix: str = "ground_") -> dict:
        return {prefix + k: (None if isinstance(v, float) and not np.isfinite(v) else v) for k, v in asdict(self).items()}


GROUND_SCHEMA = {f"ground_{k}": (pl.Int64 if t == "int" else pl.Float64)
                 for k, t in GroupGroundScores.__annotations__.items()}


def frame_rate(truth: pl.DataFrame) -> float:
    """Frames per second from the truth's frame times (median step), 1.0 when they are missing."""
    f = truth.select("frame", "t_ns").unique().sort("frame").drop_nulls()
    if f.height < 2:
        return 1.0
    df, dt = np.diff(f["frame"].to_numpy()), np.diff(f["t_ns"].to_numpy())
    ok = df > 0
    return float(1e9 / np.median(dt[ok] / df[ok])) if ok.any() else 1.0


def people(truth: pl.DataFrame, fps: float, window_s: float) -> pl.DataFrame:
    """``frame, id, X, Y, VX, VY`` (m, m/s): every placed person, velocity the least-squares slope over the window."""
    rows = truth.filter(pl.col("X").is_not_null() & pl.col("Y").is_not_null() & pl.col("visible").fill_null(True))
    rows = rows.select("frame", "id", "X", "Y").sort("id", "frame")
    half = max(1, int(round(window_s * fps / 2)))
    parts = []
    for (pid,), p in rows.group_by(["id"], maintain_order=True):
        f = p["frame"].to_numpy()
        xy = p.select("X", "Y").to_numpy()
        v = np.zeros_like(xy)
        for k in range(len(f)):
            near = np.abs(f - f[k]) <= half
            t = (f[near] - f[near].mean()) / fps
            v[k] = (t @ (xy[near] - xy[near].mean(axis=0))) / (t @ t) if t @ t > 0 else 0.0
        parts.append(p.with_columns(pl.Series("VX", v[:, 0]), pl.Series("VY", v[:, 1])))
    schema = {"frame": pl.Int64, "id": pl.Int64, "X": pl.Float64, "Y": pl.Float64, "VX": pl.Float64, "VY": pl.Float64}
    return pl.concat(parts).cast(schema) if parts else pl.DataFrame(schema=schema)


def _runs(flags: np.ndarray) -> Iterator[tuple[int, int]]:
    """Half-open ``[a, b)`` runs of True."""
    d = np.diff(np.concatenate([[0], flags.astype(np.int8), [0]]))
    yield from zip(np.flatnonzero(d == 1).tolist(), np.flatnonzero(d == -1).tolist())


def together(link: np.ndarray, fps: float, rule: GroupRule) -> np.ndarray:
    """One pair's links over consecutive frames → its together frames (gaps closed, short runs dropped)."""
    closed = link.copy()
    gap = int(round(rule.gap_s * fps))
    runs = list(_runs(link))
    for (_, b), (a, _) in zip(runs, runs[1:]):
        if a - b <= gap:
            closed[b:a] = True
    out = np.zeros_like(link)
    need = max(1, int(round(rule.min_duration_s * fps)))
    for a, b in _runs(closed):
        if b - a >= need:
            out[a:b] = True
    return out


def derive_groups(truth: pl.DataFrame, rule: GroupRule = GroupRule(), fps: float | None = None) -> pl.DataFrame:
    """``frame, id, group, X, Y`` per person: ``group`` the id of the group holding them on that frame."""
    fps = fps or frame_rate(truth)
    ppl = people(truth, fps, rule.velocity_window_s)
    if ppl.is_empty():
        return ppl.select("frame", "id", "X", "Y").with_columns(pl.lit(0, pl.Int64).alias("group"))
    f0, f1 = int(ppl["frame"].min()), int(ppl["frame"].max())
    ids = sorted(ppl["id"].unique().to_list())
    col = {p: k for k, p in enumerate(ids)}
    n, T = len(ids), f1 - f0 + 1
    pos = np.full((T, n, 4), np.nan)
    pos[ppl["frame"].to_numpy() - f0, [col[p] for p in ppl["id"].to_list()]] = ppl.select("X", "Y", "VX", "VY").to_numpy()
    pairs: list[tuple[int, int, np.ndarray]] = []
    for i in range(n):
        for j in range(i + 1, n):
            d = np.hypot(*(pos[:, i, :2] - pos[:, j, :2]).T)
            dv = np.hypot(*(pos[:, i, 2:] - pos[:, j, 2:]).T)
            link = (d <= rule.distance_m) & (dv <= rule.speed_m_s)  # NaN (someone absent) is False
            if link.any():
                pairs.append((i, j, together(link, fps, rule)))
    present = np.isfinite(pos[:, :, 0])
    names: dict[frozenset, int] = {}
    rows = []
    for t in range(T):
        here = np.flatnonzero(present[t])
        edges = [(i, j) for i, j, tog in pairs if tog[t]]
        a = np.array([e[0] for e in edges], np.int64)
        b = np.array([e[1] for e in edges], np.int64)
        _, comp = connected_components(coo_matrix((np.ones(len(a)), (a, b)), shape=(n, n)), directed=False)
        for c in np.unique(comp[here]):
            members = frozenset(ids[k] for k in here[comp[here] == c])
            gid = names.setdefault(members, len(names) + 1)
            rows += [(t + f0, p, gid) for p in sorted(members)]
    groups = pl.DataFrame(rows, schema={"frame": pl.Int64, "id": pl.Int64, "group": pl.Int64}, orient="row")
    return groups.join(ppl.select("frame", "id", "X", "Y"), on=["frame", "id"])


def group_events(groups: pl.DataFrame) -> list[tuple[str, int, tuple[tuple[int, ...], ...]]]:
    """``(kind, frame, parts)``: merges and splits between consecutive frames; ``parts`` the members
    (present on both frames) by their group on the side with several groups."""
    by_frame = {f: dict(zip(g["id"].to_list(), g["group"].to_list())) for (f,), g in groups.group_by(["frame"])}
    events = []
    for f in sorted(by_frame):
        prev, cur = by_frame.get(f - 1), by_frame[f]
        if prev is None:
            continue
        both = sorted(set(prev) & set(cur))
        for kind, now, before in (("merge", cur, prev), ("split", prev, cur)):
            for g in sorted({now[p] for p in both}):
                members = [p for p in both if now[p] == g]
                origin = sorted({before[p] for p in members})
                if len(origin) > 1:
                    events.append((kind, f, tuple(tuple(p for p in members if before[p] == o) for o in origin)))
    return events


def _nearest(ppl: pl.DataFrame, rows: pl.DataFrame, radius_m: float) -> pl.DataFrame:
    """``frame, id, track`` the nearest measured row's track within ``radius_m`` of each person (null: none)."""
    out = []
    rows_by = {f: g for (f,), g in rows.group_by(["frame"])}
    for (f,), p in ppl.group_by(["frame"], maintain_order=True):
        r = rows_by.get(f)
        track = [None] * p.height
        if r is not None:
            d = np.linalg.norm(p.select("X", "Y").to_numpy()[:, None] - r.select("X", "Y").to_numpy()[None], axis=2)
            k = np.argmin(d, axis=1)
            ids = r["track_id"].to_list()
            track = [ids[kk] if d[i, kk] <= radius_m else None for i, kk in enumerate(k.tolist())]
        out.append(pl.DataFrame({"frame": [f] * p.height, "id": p["id"], "track": track},
                                schema={"frame": pl.Int64, "id": pl.Int64, "track": pl.Int64}))
    return pl.concat(out) if out else pl.DataFrame(schema={"frame": pl.Int64, "id": pl.Int64, "track": pl.Int64})


def _found(kind: str, f: int, parts: tuple[tuple[int, ...], ...], nearest: dict, window: int) -> bool:
    for g in range(f - window, f + window + 1):
        tracks = [nearest.get((g, p)) for part in parts for p in part]
        if not tracks or any(t is None for t in tracks):
            continue
        if (kind == "merge") == (len(set(tracks)) == 1):
            return True
    return False


def _group_mot(groups: pl.DataFrame, hyps: pl.DataFrame, frames: list[int], radius_m: float):
    centres = groups.group_by("frame", "group").agg(pl.col("X").mean(), pl.col("Y").mean())
    gt_by = {f: g.sort("group") for (f,), g in centres.group_by(["frame"])}
    hyp_by = {f: h.sort("track_id") for (f,), h in hyps.group_by(["frame"])}
    empty_g = pl.DataFrame(schema={"group": pl.Int64, "X": pl.Float64, "Y": pl.Float64})
    empty_h = pl.DataFrame(schema={"track_id": pl.Int64, "X": pl.Float64, "Y": pl.Float64})

    def seq():
        for f in frames:
            g, h = gt_by.get(f, empty_g), hyp_by.get(f, empty_h)
            yield (g["group"].to_numpy(), h["track_id"].to_numpy(),
                   euclidean_distance(g.select("X", "Y").to_numpy(), h.select("X", "Y").to_numpy(), radius_m))
    return clear_mot(seq())


def inside_labelled_area(truth: pl.DataFrame, xy: np.ndarray) -> np.ndarray:
    """(N,) bool: ``xy`` inside the convex hull of the truth's ground positions (all inside when
    those span no area: fewer than 3, or on one line)."""
    placed = truth.filter(pl.col("X").is_not_null() & pl.col("Y").is_not_null()).select("X", "Y").unique().to_numpy()
    try:
        return Delaunay(placed).find_simplex(np.asarray(xy, np.float64).reshape(-1, 2), tol=1e-9) >= 0
    except Exception:  # noqa: BLE001 - scipy's QhullError: a degenerate set bounds nothing
        return np.ones(len(xy), bool)


def group_ground_scores(traj: pl.DataFrame, truth: pl.DataFrame, frames: list[int] | None = None, *,
                        rule: GroupRule = GroupRule(), radius_m: float = 1.5, coverage_goal: float = 0.8,
                        event_window_s: float = 1.0) -> GroupGroundScores:
    """The module's scores of a group tracker's trajectory (``frame, track_id, status, X, Y``, ground
    metres) against the people of ``truth`` (``frame, t_ns, id, X, Y``) on the annotated ``frames``."""
    fps = frame_rate(truth)
    frames = sorted(set(truth["frame"].to_list()) if frames is None else frames)
    groups = derive_groups(truth, rule, fps).filter(pl.col("frame").is_in(frames))
    every = traj.filter(pl.col("X").is_not_null() & pl.col("Y").is_not_null() & pl.col("frame").is_in(frames))
    inside = inside_labelled_area(truth, every.select("X", "Y").to_numpy()) if every.height else np.zeros(0, bool)
    outside = int((~inside).sum())
    placed = every.filter(pl.Series(inside, dtype=pl.Boolean))
    measured = placed.filter(pl.col("status") == "measured")
    near = _nearest(groups, every.filter(pl.col("status") == "measured"), radius_m)  # a row just outside still covers
    per_person = near.group_by("id").agg(pl.col("track").is_not_null().mean().alias("c")).sort("id")
    covered = float(near["track"].is_not_null().mean()) if near.height else float("nan")
    wrong = _nearest(measured.rename({"track_id": "id"}).select("frame", "id", "X", "Y"),
                     groups.with_columns(pl.col("id").alias("track_id")), radius_m)
    mot = _group_mot(groups, placed, frames, radius_m)
    events = group_events(groups)
    lookup = {(f, p): t for f, p, t in near.iter_rows()}
    window = int(round(event_window_s * fps))
    found = {k: sum(_found(k, f, parts, lookup, window) for kind, f, parts in events if kind == k) for k in ("merge", "split")}
    sizes = groups.group_by("group").agg(pl.col("id").n_unique().alias("n"))
    return GroupGroundScores(
        person_coverage=covered,
        person_coverage_min=float(per_person["c"].min()) if per_person.height else float("nan"),
        people=per_person.height, people_at_goal=int((per_person["c"] >= coverage_goal).sum()),
        wrong_rate=float(wrong["track"].is_null().mean()) if wrong.height else float("nan"),
        measured_rows=measured.height, outside_rows=outside,
        group_mota=mot.mota, group_motp=mot.motp, group_idf1=mot.idf1, group_id_switches=mot.id_switches,
        truth_groups=int((sizes["n"] >= 2).sum()),
        merges=sum(1 for e in events if e[0] == "merge"), merges_found=found["merge"],
        splits=sum(1 for e in events if e[0] == "split"), splits_found=found["split"],
    )
