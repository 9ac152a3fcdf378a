"""Offline fixed-interval smoothing of every track over the whole log (issue 13).

The trackers are causal: a frame's estimate uses only the past. After the event the whole log is
in hand, so every estimate may use the future as well. :func:`smooth_trajectory` runs, per track,
a Rauch–Tung–Striebel smoother (Kalman filter forward, RTS backward) over the tracker's motion
model, and fills the frames the tracker did not measure from the smoothed state, with a standard
deviation. All tracks and all noise grid points are filtered at once (issue 33): the image model
splits into axes (:mod:`.rts`, elementwise numpy over grid × axis × track, the backward pass a
parallel prefix scan), a 3-D model with a full ``R`` uses stacked matrices (:mod:`.rts_space`).
filterpy's ``batch_filter`` / ``rts_smoother``, one track and grid point at a time, gave the same
numbers (positions within 10⁻¹¹ px, the same fits; ``benchmarks/bench_smooth.py`` keeps it as the
reference) at ~100× the cost.

**Model.** Each tracker declares its own in its spec (``TrackerSpec.smoothing``,
:mod:`trackreplay.trackers.smoothing`); a tracker that declares none, or a name no spec declares,
gets the first. Constant velocity in the image (:class:`ImageSmoothing`), per track: state
``(x, vx, y, vy)`` in px and px/frame, white-acceleration process noise of spectral density ``q``
(px²/frame³), one step per frame (``F = [[1, 1], [0, 1]]`` per axis, ``Q = q [[1/3, 1/2], [1/2,
1]]``). This is the motion model of the flow tracker's image-plane position (seed 004 §4.3, whose
third state, a Gauss–Markov acceleration, is the white acceleration here) and of the colour
particle filter (seed 002: ``x ← x + ω``). The golf tracker's image position follows a ball the
operator keeps near the centre, so the same model is used for it; its 3-D flight has its own
offline fit (:mod:`trackreplay.replay.analysis.flight`). Constant velocity in 3-D
(:class:`SpaceSmoothing`): group tracks, with the group EKF's own transition and process noise at
the config the replay used (``trackers/groups/smoothing.py``, seed 003 §3.2): state ``[X Ẋ Y Ẏ Z
Ż]``, columns ``VX, VY, VZ`` (m/s) and ``X_std, Y_std, Z_std`` (m) added.

**Raw observations.** A tracker's output is already filtered; smoothing it again gains little
(flow-sim1 got slightly worse). Where the replay kept the trackers' raw measurements
(``ReplayRequest(observations=True)``, :func:`observation_rows`: the flow tracker's centroid of the
moving set, eq. 11; a group's mean ``[u v d]`` carried to 3-D with its covariance), those are the
observations instead.

**Observations.** ``measured`` rows are observations of ``(x, y)``; their noise is
``σ₀ / √confidence`` (the tracker's own confidence, floored at ``min_confidence``; ``σ₀`` when the
tracker gives none). ``predicted``, ``lost`` and absent frames between a track's first and last
position are not observations: the smoother fills them (status ``interpolated``). ``q`` and
``σ₀`` are chosen per track by maximum likelihood (the filter's innovations) over a fixed grid, so
the smoother adapts to a slow square in a simulation and to a golf ball alike, with no tuning
and no randomness. Measurements more than ``outlier_sigma`` standard deviations from the
smoothed track (a wrong blob) are then dropped and the track smoothed again.

**Output.** The trajectory table (★ columns, same rows plus the absent frames of each track's
span) with smoothed ``x, y, vx, vy`` on every positioned row, and extra columns:

- ``x_std``, ``y_std`` (px), ``vx_std``, ``vy_std`` (px/frame): the smoother's standard deviations;
- ``fill``: how the row's image position was obtained — ``rts`` (an observation, smoothed),
  ``rts_outlier`` (a measurement the smoother rejected; the row shows the smoothed track),
  ``rts_gap`` (no observation: filled by the smoother, status ``interpolated``), or null for a
  row left ``lost`` (a gap longer than ``max_gap`` frames, or before/after the track).
  ``linear`` / ``cubic`` appear for rows filled by :func:`trackreplay.replay.core.export.fill_gaps`,
  which the smoother replaces wherever a model exists (every tracker of the project has one).

Box size ``w, h`` and the world position ``X, Y, Z`` of filled rows are linear interpolations of
the tracker's neighbouring values (the image model says nothing about them). With a camera pose in
the log (PTZ encoders and lens table) the lines of sight ``dx, dy, dz`` are recomputed from the
smoothed ``x, y`` through the frame's camera; without one they are interpolated and renormalised.

Measured against ground truth in ``docs/smoothing.md`` (``python docs/smoothing.py``).
"""

from __future__ import annotations

import math
from array import array
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import polars as pl

from trackreplay.replay.analysis import rts, rts_space, segments
from trackreplay.replay.core import registry
from trackreplay.replay.core.observations import OBS_SCHEMA, observation_rows, observations_table  # noqa: F401 (re-exported)
from trackreplay.replay.core.trajectory import COLUMNS, SCHEMA
from trackreplay.schemas.errors import TrackreplayError
from trackreplay.schemas.records import PtzReading
from trackreplay.trackers.geometry.ptz import PtzCamera
from trackreplay.trackers.smoothing import DEFAULT_SMOOTHING, SmoothingModel, SpaceSmoothing

EXTRA_SCHEMA: dict[str, pl.DataType] = {
    "x_std": pl.Float64, "y_std": pl.Float64, "vx_std": pl.Float64, "vy_std": pl.Float64, "fill": pl.String,
    # 3-D models (groups): smoothed velocity (m/s, the log's frame rate) and position std (m)
    "VX": pl.Float64, "VY": pl.Float64, "VZ": pl.Float64, "X_std": pl.Float64, "Y_std": pl.Float64, "Z_std": pl.Float64,
}
SMOOTH_COLUMNS = (*COLUMNS, *EXTRA_SCHEMA)
FILLS = ("rts", "rts_outlier", "rts_gap", "linear", "cubic")


@dataclass(frozen=True)
class SmoothConfig:
    """Smoother settings (defaults used everywhere in the docs)."""

    max_gap: int = 15  # longest run of frames without a position that is filled; longer stays lost
    q_grid: tuple[float, ...] = (1e-4, 1e-3, 1e-2, 0.1, 1.0, 10.0, 100.0)  # px²/frame³
    sigma_grid: tuple[float, ...] = (0.1, 0.3, 1.0, 3.0, 10.0)  # px, measurement std at confidence 1
    sigma_v_grid: tuple[float, ...] = (0.1, 0.3, 1.0, 3.0)  # px/frame, velocity observations (where used)
    min_confidence: float = 0.05
    outlier_sigma: float = 5.0


def smoothing_model(tracker: str, config: Any = None) -> SmoothingModel:
    """The model ``tracker``'s tracks are smoothed with: its spec's (``TrackerSpec.smoothing``, at
    ``config``, the config it was replayed with; None: the defaults), image constant velocity for a
    tracker no spec declares."""
    spec = registry.find(tracker)
    return DEFAULT_SMOOTHING if spec is None else spec.smoothing_model(config)


@dataclass(frozen=True)
class TrackFit:
    """What the smoother chose for one track (for reports and tests)."""

    tracker: str
    track_id: int
    q: float
    sigma: float
    sigma_v: float
    log_likelihood: float
    observations: int
    outliers: int
    filled: int
    noise: str = ""  # the chosen noise in words (the model's units)


def _noise_grid(cfg: SmoothConfig, velocity: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(q, σ₀, σ_v)`` of every grid point, q outermost (the order ties are broken in: first wins);
    one σ_v when no track observes a velocity (it then changes nothing)."""
    sv = cfg.sigma_v_grid if velocity else cfg.sigma_v_grid[:1]
    q, s, v = np.meshgrid(np.array(cfg.q_grid, float), np.array(cfg.sigma_grid, float), np.array(sv, float), indexing="ij")
    return q.ravel(), s.ravel(), v.ravel()


LANE_ELEMENTS = 1 << 14  # grid points × tracks filtered together: the working set (~20 arrays of this size)


def _lanes(lengths: list[int], width: int) -> list[list[int]]:
    """Tracks filtered together, longest first, at most ``width`` of them; a lane's tracks are at
    least half as long as its first (padding at most doubles the work)."""
    order = sorted(range(len(lengths)), key=lambda i: -lengths[i])
    lanes: list[list[int]] = []
    for i in order:
        if lanes and 2 * lengths[i] >= lengths[lanes[-1][0]] and len(lanes[-1]) < width:
            lanes[-1].append(i)
        else:
            lanes.append([i])
    return lanes


def _select(zs: list[np.ndarray], rs: list[np.ndarray], cfg: SmoothConfig) -> list[tuple[float, float, float, float]]:
    """Per track, ``(q, σ₀, σ_v, log-likelihood)`` of the grid point with the highest likelihood
    (first on ties; a NaN likelihood never wins); σ_v from its grid only for a track that observes
    a velocity."""
    best: list = [None] * len(zs)
    velocity = [bool(np.isfinite(z[:, 2:]).any()) for z in zs]
    for with_velocity in (False, True):
        part = [i for i in range(len(zs)) if velocity[i] == with_velocity]
        q, s, sv = _noise_grid(cfg, with_velocity)
        for lane in _lanes([len(zs[i]) for i in part], max(1, LANE_ELEMENTS // len(q))):
            tracks = [part[j] for j in lane]
            # (packed inside: a long lane's columns are not kept while its pieces are filtered)
            ll = rts.grid_loglik(lambda lane=tracks: rts.Columns.pack([zs[i] for i in lane], [rs[i] for i in lane]),
                                 rts.axis_noise(DEFAULT_SMOOTHING.Q, q), s * s, sv * sv, LANE_ELEMENTS)
            ll = np.where(np.isnan(ll), -math.inf, ll)
            for j, i in enumerate(tracks):
                g = int(np.argmax(ll[:, j]))
                best[i] = (float(q[g]), float(s[g]), float(sv[g]), float(ll[g, j]))
    return best


def _smooth_at(zs: list[np.ndarray], rs: list[np.ndarray], fits: list) -> list[tuple[np.ndarray, np.ndarray]]:
    """Per track, the smoothed state ``(x, vx, y, vy)`` (n, 4) and its variances (n, 4) at its noise."""
    out: list = [None] * len(zs)
    for lane in _lanes([len(z) for z in zs], LANE_ELEMENTS):
        q, s, sv = (np.array([fits[i][k] for i in lane]) for k in range(3))
        for i in lane:
            out[i] = (np.empty((len(zs[i]), 4)), np.empty((len(zs[i]), 4)))
        # a piece of frames at a time, the last first, straight into each track's rows (issue 33: a long track's
        # filtered states wait in a temporary file, its columns go after the forward pass, and its whole-track
        # arrays are only these two)
        pieces = rts.smooth_pieces(rts.Columns.pack([zs[i] for i in lane], [rs[i] for i in lane]),
                                   rts.axis_noise(DEFAULT_SMOOTHING.Q, q), s * s, sv * sv)
        for lo, (p, v, a, _, c) in pieces:
            last = a.shape[1] - 1  # the y axis' covariance: its own, or shared with x
            for j, i in enumerate(lane):
                m = min(len(zs[i]) - lo, len(p))
                if m > 0:
                    out[i][0][lo:lo + m] = np.stack([p[:m, 0, j], v[:m, 0, j], p[:m, 1, j], v[:m, 1, j]], axis=1)
                    out[i][1][lo:lo + m] = np.stack([a[:m, 0, j], c[:m, 0, j], a[:m, last, j], c[:m, last, j]], axis=1)
    return out


def smooth_tracks(zs: list[np.ndarray], confidences: list[np.ndarray], cfg: SmoothConfig = SmoothConfig(),
                  copy: bool = True) -> list[tuple]:
    """Smooth image tracks over consecutive frames, all at once (:mod:`.rts`).

    ``zs[i]`` (n, 2) or (n, 4): observed image positions (and velocities), NaN where a frame or a
    component is not an observation; ``confidences[i]`` (n,): the tracker's confidence (NaN: none).
    Per track ``(x, var, outliers, fit)``: ``x`` (n, 4) = (x, vx, y, vy), their variances (n, 4),
    ``outliers`` (n,) bool and ``fit = (q, σ₀, σ_v, log-likelihood)``. Without ``copy``, a float64
    ``zs[i]`` of 4 columns is used as it is (its outliers set to NaN: the caller's array changes).
    """
    rs, obs = [], []
    zs = [np.array(z, dtype=np.float64) if copy else np.asarray(z, dtype=np.float64) for z in zs]
    for i, (z, confidence) in enumerate(zip(zs, confidences)):
        conf = np.where(np.isfinite(confidence), np.maximum(confidence, cfg.min_confidence), 1.0)
        rs.append(1.0 / conf)
        if z.shape[1] == 2:
            zs[i] = z = np.concatenate([z, np.full_like(z, np.nan)], axis=1)
        obs.append(np.isfinite(z[:, :2]).all(axis=1))
        z[~obs[-1]] = np.nan
    fits = _select(zs, rs, cfg)
    smoothed = _smooth_at(zs, rs, fits)
    outliers = [np.zeros(len(z), bool) for z in zs]
    again = []
    for i, (z, ok) in enumerate(zip(zs, obs)):
        if ok.sum() > 4:
            resid = z[:, :2] - smoothed[i][0][:, [0, 2]]
            var = fits[i][1] ** 2 * rs[i]  # the measurement's own variance: a sound observation lies well inside it
            bad = ok & (np.sqrt((resid**2).sum(axis=1) / (2.0 * var)) > cfg.outlier_sigma)
            if bad.any() and (ok & ~bad).sum() >= 2:
                outliers[i], z[bad] = bad, np.nan
                again.append(i)
                smoothed[i] = None  # (smoothed again below: not held through the second grid search)
    if again:
        refits = _select([zs[i] for i in again], [rs[i] for i in again], cfg)
        for i, fit, sm in zip(again, refits, _smooth_at([zs[i] for i in again], [rs[i] for i in again], refits)):
            fits[i], smoothed[i] = fit, sm
    return [(x, var, out, fit) for (x, var), out, fit in zip(smoothed, outliers, fits)]


KEYS = ["tracker", "track_id", "frame"]
_interp, _interp_rate = segments.interp, segments.interp_rate  # per track when given ``starts``


@dataclass(frozen=True)
class _Plan:
    """Which frames of each track's span the smoother sets, and how (the image and 3-D models alike).

    Runs of frames without an observation (predicted, lost, absent, or rejected as an outlier) are
    filled by the smoother when at most max_gap long and bracketed by observations: the smoother
    interpolates there. Elsewhere (a run that ends the track or is too long) it would extrapolate,
    so those rows keep the tracker's own values (predicted) or stay lost.
    """

    smoothed: np.ndarray  # bool (n,): the smoother's value (an observation, or a filled gap)
    keep: np.ndarray  # bool (n,): the row keeps a position
    filled: np.ndarray  # bool (n,): predicted and gap rows taken from the smoother: status interpolated
    fill: np.ndarray  # object (n,): the fill column
    status: np.ndarray  # object (n,): the new status column


def _plan(observed: np.ndarray, measured: np.ndarray, has_pos: np.ndarray, status: np.ndarray, starts: np.ndarray,
          max_gap: int) -> _Plan:
    """The plan of every track at once (``starts``: each track's first row, :mod:`.segments`)."""
    fill_gap = segments.short_gaps(~observed, starts, max_gap)
    smoothed = observed | fill_gap
    keep = smoothed | has_pos
    filled = fill_gap & ~measured
    fill = np.full(len(observed), None, dtype=object)
    fill[observed] = "rts"
    fill[fill_gap & measured] = "rts_outlier"
    fill[filled] = "rts_gap"
    new_status = np.where(filled, "interpolated", np.where(keep, status, "lost")).astype(object)
    return _Plan(smoothed, keep, filled, fill, new_status)


@dataclass(frozen=True)
class _Spans:
    """A table's tracks split at their positioned span ``lo .. hi`` (all tracks at once, canonical
    order, each row with its track's index ``_tid``)."""

    full: pl.DataFrame  # each positioned track on every frame of its span (absent frames: nulls but the keys)
    starts: np.ndarray  # (T + 1,) each track's first row in ``full``, and the end
    outside: pl.DataFrame  # those tracks' rows before and after their span
    bare: pl.DataFrame  # the tracks without a positioned row


def _spans(table: pl.DataFrame, positioned: pl.Expr) -> _Spans:
    """The spans from numpy offsets and one gather of the table's rows (not a join of the frame grid
    with the table, which held both and their hash tables); the joins where a track repeats a frame."""
    t = table.with_columns(pl.struct("tracker", "track_id").rle_id().alias("_tid"))
    tid = t["_tid"].to_numpy().astype(np.int64)
    frame = t["frame"].to_numpy().astype(np.int64)
    pos = t.select(positioned.fill_null(False)).to_series().to_numpy()
    tracks = int(tid.max()) + 1 if len(tid) else 0
    lo, hi = np.full(tracks, np.iinfo(np.int64).max), np.full(tracks, np.iinfo(np.int64).min)
    np.minimum.at(lo, tid[pos], frame[pos])
    np.maximum.at(hi, tid[pos], frame[pos])
    has = np.zeros(tracks, bool)
    has[tid[pos]] = True
    ids = np.flatnonzero(has)
    row_has = has[tid]
    inside = row_has & (frame >= lo[tid]) & (frame <= hi[tid])
    length = hi[ids] - lo[ids] + 1
    begin = np.concatenate([[0], np.cumsum(length)])
    slot = np.full(tracks, -1)
    slot[ids] = np.arange(len(ids))
    k = slot[tid[inside]]
    at = begin[k] + frame[inside] - lo[ids][k]
    if (np.diff(at) <= 0).any():  # a frame twice in a track (rows sorted by track and frame otherwise)
        return _spans_join(t, positioned)
    src = np.zeros(int(begin[-1]), np.int64)
    src[at] = np.flatnonzero(inside)
    gap = np.ones(len(src), bool)
    gap[at] = False
    which = np.repeat(np.arange(len(ids)), length)
    heads = np.searchsorted(tid, ids)  # each track's first row (rle ids ascend)
    keys = t.select(pl.col("_tid", "tracker", "track_id").gather(heads[which]))
    rest = [c for c in t.columns if c not in ("_tid", "tracker", "track_id", "frame")]
    index = pl.select(pl.when(pl.Series(gap)).then(None).otherwise(pl.Series(src))).to_series()  # null: an absent frame
    body = t.select(pl.col(rest).gather(index))
    full = pl.concat([keys.with_columns(pl.Series("frame", lo[ids][which] - begin[which] + np.arange(len(which)),
                                                  dtype=pl.Int64)), body], how="horizontal")
    return _Spans(full, begin.astype(np.int64), t.filter(pl.Series(row_has & ~inside)), t.filter(pl.Series(~row_has)))


def _spans_join(t: pl.DataFrame, positioned: pl.Expr) -> _Spans:
    """:func:`_spans` by joins (``t`` with ``_tid``)."""
    span = (t.filter(positioned).group_by("_tid")
            .agg(pl.col("frame").min().alias("_lo"), pl.col("frame").max().alias("_hi"),
                 pl.col("tracker").first(), pl.col("track_id").first()).sort("_tid"))
    t = t.join(span.select("_tid", "_lo", "_hi"), on="_tid", how="left", maintain_order="left")
    bare = t.filter(pl.col("_lo").is_null()).drop("_lo", "_hi")
    outside = t.filter(pl.col("_lo").is_not_null() & ((pl.col("frame") < pl.col("_lo")) | (pl.col("frame") > pl.col("_hi"))))
    lo, hi = span["_lo"].to_numpy().astype(np.int64), span["_hi"].to_numpy().astype(np.int64)
    length = hi - lo + 1
    begin = np.concatenate([[0], np.cumsum(length)])[:-1]
    which = np.repeat(np.arange(span.height), length)
    grid = span.select(pl.col("_tid", "tracker", "track_id").gather(which)).with_columns(
        pl.Series("frame", lo[which] - begin[which] + np.arange(len(which)), dtype=pl.Int64))
    full = grid.join(t.drop("tracker", "track_id", "_lo", "_hi"), on=["_tid", "frame"], how="left", maintain_order="left")
    return _Spans(full, segments.offsets(full["_tid"].to_numpy()), outside.drop("_lo", "_hi"), bare)


def _rows(df: pl.DataFrame, mask: np.ndarray) -> tuple[pl.DataFrame, np.ndarray]:
    """The rows of ``df`` (grouped by ``_tid``) under ``mask``, and their track offsets."""
    part = df.filter(pl.Series(mask))
    return part, segments.offsets(part["_tid"].to_numpy())


def _assemble(full: pl.DataFrame, cols: dict[str, np.ndarray], confidence: np.ndarray, plan: _Plan) -> pl.DataFrame:
    return full.with_columns(
        *(pl.Series(k, v, dtype=pl.Float64, nan_to_null=True) for k, v in cols.items()),
        pl.Series("confidence", confidence, dtype=pl.Float64, nan_to_null=True),
        pl.Series("status", plan.status, dtype=pl.String),
        pl.Series("fill", plan.fill.tolist(), dtype=pl.String),
    )


def _no_extra(df: pl.DataFrame) -> pl.DataFrame:
    return df.with_columns(*(pl.lit(None, dtype=t).alias(c) for c, t in EXTRA_SCHEMA.items()))


def _has_raw(full: pl.DataFrame, starts: np.ndarray, raw: pl.DataFrame | None, column: str) -> np.ndarray:
    """Per track of ``full``, whether the replay kept a raw measurement ``column`` for it."""
    if raw is None:
        return np.zeros(len(starts) - 1, bool)
    have = raw.group_by(["tracker", "track_id"]).agg(pl.col(column).is_not_null().any().alias("_raw"))
    heads = full.select(pl.col("tracker", "track_id").gather(starts[:-1]))
    return heads.join(have, on=["tracker", "track_id"], how="left", maintain_order="left")["_raw"].fill_null(False).to_numpy()


def _raw_rows(full: pl.DataFrame, raw: pl.DataFrame) -> pl.DataFrame:
    """The raw measurements on ``full``'s rows (nulls where none)."""
    return full.select(KEYS).join(raw, on=KEYS, how="left", maintain_order="left")


def _smooth_image(table: pl.DataFrame, models: Mapping[str, SmoothingModel], cfg: SmoothConfig, raw: pl.DataFrame | None,
                  frame_times: Mapping[int, int] | None, cameras: Mapping[int, PtzCamera] | None,
                  given=None) -> tuple[list[pl.DataFrame], list[TrackFit]]:
    """Every image track's rows and fit: all tracks' columns at once (:mod:`.segments`), the
    smoother over all of them (:func:`smooth_tracks`; ``given(full, starts)``: its results, already
    computed: :func:`smooth_track_piece`)."""
    sp = _spans(table, pl.col("x").is_not_null() & pl.col("y").is_not_null() & (pl.col("status") != "lost"))
    parts = [_no_extra(sp.bare), _no_extra(sp.outside)]
    full, starts = sp.full, sp.starts
    status = full["status"].fill_null("lost").to_numpy().astype(object)
    x, y = full["x"].to_numpy().astype(float), full["y"].to_numpy().astype(float)
    has_pos = np.isfinite(x) & np.isfinite(y) & (status != "lost")
    z, measured = _image_observations(models, full, starts, raw, has_pos & (status == "measured"))
    rows = segments.per_row(segments.counts(np.isfinite(z[:, :2]).all(axis=1), starts) > 0, starts)
    if not rows.all():  # only predictions: nothing to smooth; keep the rows as they are
        idle, idle_starts = _rows(full, ~rows)
        parts.append(_finish(_no_extra(idle), idle_starts, frame_times))
    fits: list[TrackFit] = []
    if rows.size and rows.all():  # (every track: no copies)
        out, fits = _image_result(models, full, starts, z, measured, has_pos, status, cfg, cameras, given)
        parts.append(_finish(out, starts, frame_times))
    elif rows.any():
        full, starts = _rows(full, rows)
        out, fits = _image_result(models, full, starts, z[rows], measured[rows], has_pos[rows], status[rows], cfg,
                                  cameras, given)
        parts.append(_finish(out, starts, frame_times))
    return parts, fits


def _image_result(models: Mapping[str, SmoothingModel], full: pl.DataFrame, starts: np.ndarray, z: np.ndarray,
                  measured: np.ndarray, has_pos: np.ndarray, status: np.ndarray, cfg: SmoothConfig,
                  cameras: Mapping[int, PtzCamera] | None, given=None) -> tuple[pl.DataFrame, list[TrackFit]]:
    """The image tracks' rows: ``x, y, vx, vy`` smoothed, gaps filled, the other columns interpolated."""
    conf = full["confidence"].to_numpy().astype(float)
    bounds = list(zip(starts[:-1].tolist(), starts[1:].tolist()))
    smoothed = (smooth_tracks([z[a:b] for a, b in bounds], [conf[a:b] for a, b in bounds], cfg) if given is None
                else given(full, starts))
    xs, var, outliers = (smoothed[0][k] if len(smoothed) == 1 else np.concatenate([s[k] for s in smoothed])
                         for k in range(3))  # (one track: its own arrays)
    plan = _plan(measured & ~outliers, measured, has_pos, status, starts, cfg.max_gap)
    out = _assemble(full, _image_columns(full, starts, xs, var, plan, has_pos, cameras),
                    np.where(plan.filled, np.nan, conf), plan)
    heads = full.select(pl.col("tracker", "track_id").gather(starts[:-1]))
    counted = zip(*(segments.counts(m, starts).tolist() for m in (measured, outliers, plan.filled)))
    fits = [TrackFit(tracker, int(track_id), q, s, sv, ll, m, o, f, models[tracker].describe(q, s))
            for (tracker, track_id), (_, _, _, (q, s, sv, ll)), (m, o, f) in zip(heads.iter_rows(), smoothed, counted)]
    return out, fits


def _image_observations(models: Mapping[str, SmoothingModel], full: pl.DataFrame, starts: np.ndarray,
                        raw: pl.DataFrame | None, measured: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``z`` (n, 4) = (x, y, vx, vy), NaN where not observed, and the measured rows that observe.

    The tracker's raw measurements (before its own filter), where the replay kept them, replace its
    filtered output: the smoother then filters them once, with the future, instead of smoothing a
    filtered track."""
    n = full.height
    xy = np.stack([full["x"].to_numpy().astype(float), full["y"].to_numpy().astype(float)], axis=1)
    v = np.stack([full["vx"].to_numpy().astype(float), full["vy"].to_numpy().astype(float)], axis=1)
    z, measured = np.full((n, 4), np.nan), measured.copy()
    has_raw = segments.per_row(_has_raw(full, starts, raw, "zx"), starts)
    r = _raw_rows(full, raw) if has_raw.any() else None
    track_end = segments.per_row(starts[1:], starts)
    blocks = segments.offsets(full.select(pl.col("tracker").rle_id()).to_series().to_numpy())
    for a, b in zip(blocks[:-1].tolist(), blocks[1:].tolist()):  # one tracker (model) at a time
        model, sl = models[full["tracker"][a]], slice(a, b)
        vel = v[sl] if model.observe_velocity else np.full((b - a, 2), np.nan)
        z[sl] = np.where(measured[sl, None], np.concatenate([xy[sl], vel], axis=1), np.nan)
        hr = has_raw[sl]
        if r is None or not hr.any():
            continue
        zx, zy = r["zx"].to_numpy()[sl].astype(float), r["zy"].to_numpy()[sl].astype(float)
        zv = np.stack([r["zvx"].to_numpy().astype(float), r["zvy"].to_numpy().astype(float)], axis=1)
        if model.velocity_lag:  # each track's velocity from ``lag`` frames later
            ahead = np.arange(a, b) + model.velocity_lag
            inside = ahead < track_end[sl]
            lagged = np.full((b - a, 2), np.nan)
            lagged[inside] = zv[ahead[inside]]
            zv = lagged
        else:
            zv = zv[sl]
        if not model.raw_velocity:
            zv = np.where(measured[sl, None], vel, np.nan)
        ok = measured[sl] & np.isfinite(zx) & np.isfinite(zy)
        zr = np.full((b - a, 4), np.nan)
        zr[ok, 0], zr[ok, 1] = zx[ok], zy[ok]
        if model.observe_velocity:
            zr[:, 2:] = zv
        z[sl] = np.where(hr[:, None], zr, z[sl])
        # a raw observation on a frame the tracker also measured; the others fall back to nothing
        measured[sl] = np.where(hr, measured[sl] & (ok | np.isfinite(zv).all(axis=1)), measured[sl])
    return z, measured


def _image_columns(full: pl.DataFrame, starts: np.ndarray, xs: np.ndarray, var: np.ndarray, plan: _Plan,
                   has_pos: np.ndarray, cameras: Mapping[int, PtzCamera] | None) -> dict[str, np.ndarray]:
    """Smoothed ``x, vx, y, vy`` with their std; box size and world position linear across filled
    frames (the image model says nothing about them); lines of sight."""
    def masked(v: np.ndarray) -> np.ndarray:
        return np.where(plan.keep, v, np.nan)

    std = np.sqrt(np.maximum(var, 0.0))
    cols: dict[str, np.ndarray] = {}
    for k, name in enumerate(("x", "vx", "y", "vy")):
        cols[name] = masked(np.where(plan.smoothed, xs[:, k], full[name].to_numpy().astype(float)))
        cols[f"{name}_std"] = np.where(plan.smoothed, std[:, k], np.nan)
    frames = full["frame"].to_numpy()
    f = frames.astype(float)
    for name in ("w", "h", "X", "Y", "Z", "dx", "dy", "dz"):
        values = np.where(has_pos, full[name].to_numpy().astype(float), np.nan)
        cols[name] = masked(_interp(f, values, plan.filled, starts))
    cols["dx"], cols["dy"], cols["dz"] = _lines_of_sight(cols, frames, plan.smoothed, cameras)
    return cols


def _lines_of_sight(cols: dict[str, np.ndarray], frames: np.ndarray, smoothed: np.ndarray,
                    cameras: Mapping[int, PtzCamera] | None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Through the frame's camera from the smoothed pixel, else interpolated; renormalised."""
    d = np.stack([cols["dx"], cols["dy"], cols["dz"]], axis=1)
    if cameras:
        for i in np.flatnonzero(smoothed):
            cam = cameras.get(int(frames[i]))
            if cam is not None:
                d[i] = cam.line_of_sight(np.array([[cols["x"][i], cols["y"][i]]]))[0]
    norm = np.linalg.norm(d, axis=1)
    ok = np.isfinite(norm) & (norm > 0)
    d[ok] /= norm[ok][:, None]
    return d[:, 0], d[:, 1], d[:, 2]


def logged_times(frame_times: Mapping[int, int], frames: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The log's time of each of ``frames`` and whether the log has one."""
    if isinstance(frame_times, FrameTimes):
        keys, times = frame_times.sorted_arrays()
    else:
        keys = np.fromiter(frame_times.keys(), dtype=np.int64, count=len(frame_times))
        times = np.fromiter(frame_times.values(), dtype=np.int64, count=len(frame_times))
        order = np.argsort(keys, kind="stable")
        keys, times = keys[order], times[order]
    at = np.clip(np.searchsorted(keys, frames), 0, max(len(keys) - 1, 0))
    found = (keys[at] == frames) if len(keys) else np.zeros(len(frames), bool)
    return np.where(found, times[at] if len(keys) else 0, 0), found


def _finish(full: pl.DataFrame, starts: np.ndarray, frame_times: Mapping[int, int] | None) -> pl.DataFrame:
    """The extra columns (null where not set) and the times of added frames: the log's frame times,
    else interpolated within each track (``starts``)."""
    frames = full["frame"].to_numpy().astype(np.int64)
    known = full["t_ns"].is_not_null().to_numpy()
    t = full["t_ns"].fill_null(0).to_numpy().astype(np.int64)
    if frame_times and not known.all():  # (ints: float64 would round epoch times off their frames)
        missing = np.flatnonzero(~known)
        logged, found = logged_times(frame_times, frames[missing])
        t[missing[found]], known[missing[found]] = logged[found], True
    t = segments.interpolated_times(frames, t, known, starts)
    full = full.with_columns(*(pl.lit(None, dtype=t).alias(c) for c, t in EXTRA_SCHEMA.items() if c not in full.columns))
    return full.with_columns(pl.Series("t_ns", t, dtype=pl.Int64))


def smooth_trajectory(df: pl.DataFrame, config: SmoothConfig = SmoothConfig(), *,
                      frame_times: Mapping[int, int] | None = None,
                      cameras: Mapping[int, PtzCamera] | None = None,
                      observations: pl.DataFrame | None = None,
                      configs: Mapping[str, Any] | None = None) -> tuple[pl.DataFrame, list[TrackFit]]:
    """RTS-smooth every track of a trajectory table (see the module docstring).

    ``observations`` (:data:`OBS_SCHEMA`, from :func:`observation_rows` during the replay, e.g.
    ``ReplayRequest(observations=True)``): the trackers' raw measurements, used instead of their
    filtered output where present. ``configs`` (tracker name -> its config as replayed,
    ``ReplayResult.config``): a model that reads its tracker's config (groups: the EKF's process
    noise) reads that one; the config's defaults otherwise.

    ``frame_times`` (frame -> t_ns) gives added frames their log time; ``cameras`` (frame -> posed
    camera) lets lines of sight follow the smoothed pixels. Deterministic: no randomness, a fixed
    parameter grid, tracks in canonical order. All tracks are assembled at once (no loop per track
    over the table: issue 33).
    """
    if config.max_gap < 0:
        raise TrackreplayError(f"--max-gap must be >= 0, not {config.max_gap}")
    if df.is_empty():
        return df.with_columns(*(pl.lit(None, dtype=t).alias(c) for c, t in EXTRA_SCHEMA.items())).select(SMOOTH_COLUMNS), []
    table = _sorted(df.select(COLUMNS))
    raw = observations.select(list(OBS_SCHEMA)) if observations is not None and observations.height else None
    models = {t: smoothing_model(t, (configs or {}).get(t)) for t in table["tracker"].unique(maintain_order=True).to_list()}
    image = [t for t, m in models.items() if not isinstance(m, SpaceSmoothing)]
    parts, fits = [], []
    if image:
        mine = table if len(image) == len(models) else table.filter(pl.col("tracker").is_in(image))
        parts, fits = _smooth_image(mine, models, config, raw, frame_times, cameras)
    for tracker, model in models.items():
        if isinstance(model, SpaceSmoothing):
            mine = table if len(models) == 1 else table.filter(pl.col("tracker") == tracker)
            more, more_fits = _smooth_space(mine, model, config, raw, frame_times)
            parts, fits = parts + more, fits + more_fits
    out = pl.concat([p.select(SMOOTH_COLUMNS).cast({**SCHEMA, **EXTRA_SCHEMA}) for p in parts])
    return _sorted(out), sorted(fits, key=lambda f: (f.tracker, f.track_id))


def smooth_track_piece(piece: pl.DataFrame, config: SmoothConfig, given, *, frame_times: Mapping[int, int] | None = None,
                       cameras: Mapping[int, PtzCamera] | None = None) -> tuple[pl.DataFrame, list[TrackFit]]:
    """:func:`smooth_trajectory` of consecutive rows of one track whose smoother results are known
    (:mod:`.smooth_long`): ``given(full, starts)`` gives them for the piece's span (an image track:
    ``[(x, var, outliers, fit)]``, :func:`smooth_tracks`' value; a 3-D one: ``([fitted], [frame rate])``,
    :func:`_fit_space`'s value and :func:`frame_rate`). Everything else (spans, gaps, interpolations, times,
    lines of sight) is the whole table's code on the piece."""
    table = _sorted(piece.select(COLUMNS))
    tracker = table["tracker"][0]
    models = {tracker: smoothing_model(tracker)}
    if isinstance(models[tracker], SpaceSmoothing):
        parts, fits = _smooth_space(table, models[tracker], config, None, frame_times, given)
    else:
        parts, fits = _smooth_image(table, models, config, None, frame_times, cameras, given)
    return _sorted(pl.concat([p.select(SMOOTH_COLUMNS).cast({**SCHEMA, **EXTRA_SCHEMA}) for p in parts])), fits


def _sorted(df: pl.DataFrame) -> pl.DataFrame:
    """``df`` sorted by :data:`KEYS` (stable), not copied when it already is (a long table's copy)."""
    now, before = [pl.col(k) for k in KEYS], [pl.col(k).shift(1) for k in KEYS]
    ascending = (now[0] > before[0]) | ((now[0] == before[0]) & ((now[1] > before[1]) | ((now[1] == before[1]) &
                                                                                         (now[2] >= before[2]))))
    ok = df.select(ascending.fill_null(True).all() & ~pl.any_horizontal(pl.col(KEYS).is_null()).any()).item()
    return df if ok else df.sort(KEYS, maintain_order=True)


@dataclass(frozen=True)
class _SpaceTrack:
    """A 3-D track's observations for the smoother (its rows of the observation arrays: outliers are removed in place)."""

    z: np.ndarray  # (n, 3), NaN where not observed
    R0: np.ndarray  # (n, 3, 3), I where not observed
    ok: np.ndarray
    grid: tuple[float, ...]  # R's scales tried


def _smooth_space(table: pl.DataFrame, model: SpaceSmoothing, cfg: SmoothConfig, raw: pl.DataFrame | None,
                  frame_times: Mapping[int, int] | None, given=None) -> tuple[list[pl.DataFrame], list[TrackFit]]:
    """Every 3-D track of one tracker (groups): rows and fits, all tracks at once (``given(full, starts)``:
    the fits and frame rates, already computed: :func:`smooth_track_piece`)."""
    sp = _spans(table, pl.col("X").is_not_null() & (pl.col("status") != "lost"))
    parts = [_finish(df, segments.offsets(df["_tid"].to_numpy()), frame_times) for df in (sp.bare, sp.outside)]
    full, starts = sp.full, sp.starts
    status = full["status"].fill_null("lost").to_numpy().astype(object)
    P3 = np.stack([full[c].to_numpy().astype(float) for c in ("X", "Y", "Z")], axis=1)
    has_pos = np.isfinite(P3).all(axis=1) & (status != "lost")
    measured = has_pos & (status == "measured")
    z, R0, ok, grids = _space_observations(model, full, starts, raw, P3, measured)
    enough = segments.counts(ok, starts) >= 2
    rows = segments.per_row(enough, starts)
    if not rows.all():
        idle, idle_starts = _rows(full, ~rows)
        parts.append(_finish(idle, idle_starts, frame_times))
    if not rows.any():
        return parts, []
    rate = None
    if given is None:
        bounds = [(a, b) for a, b, e in zip(starts[:-1].tolist(), starts[1:].tolist(), enough) if e]
        # each track's own rows of z and R0 (views: the outliers are removed in place, and z, R0 serve nothing after)
        tracks = [_SpaceTrack(z[a:b], R0[a:b], ok[a:b].copy(), g) for (a, b), g in
                  zip(bounds, [g for g, e in zip(grids, enough) if e])]
        fitted = _fit_space(model, tracks, cfg)
        del tracks
    else:
        fitted, rate = given(full, starts)
    del z, R0
    if not rows.all():
        full, starts = _rows(full, rows)
        status, P3, has_pos, measured = status[rows], P3[rows], has_pos[rows], measured[rows]
    out, fits = _space_result(model, full, starts, fitted, status, P3, has_pos, measured, cfg, frame_times, rate)
    return parts + [_finish(out, starts, frame_times)], fits


def _space_result(model: SpaceSmoothing, full: pl.DataFrame, starts: np.ndarray, fitted: list[tuple], status: np.ndarray,
                  P3: np.ndarray, has_pos: np.ndarray, measured: np.ndarray, cfg: SmoothConfig,
                  frame_times: Mapping[int, int] | None, rate: np.ndarray | None = None) -> tuple[pl.DataFrame, list[TrackFit]]:
    """The 3-D tracks' rows (groups): 3-D position and velocity smoothed, gaps filled."""
    def joined(k: int, of=lambda x: x) -> np.ndarray:  # (one track: its own array)
        return of(fitted[0][k]) if len(fitted) == 1 else np.concatenate([of(f[k]) for f in fitted])

    xs, ok, outliers = joined(3), joined(5), joined(6)
    Ps = joined(4, lambda P: P if P.ndim == 2 else np.diagonal(P, axis1=1, axis2=2))  # variances
    plan = _plan(ok, measured, has_pos, status, starts, cfg.max_gap)
    cols = _space_columns(full, starts, xs, Ps, plan, has_pos, P3, frame_times, rate)
    out = _assemble(full, cols, np.where(plan.filled, np.nan, full["confidence"].to_numpy().astype(float)), plan)
    heads = full.select(pl.col("tracker", "track_id").gather(starts[:-1]))
    counted = zip(*(segments.counts(m, starts).tolist() for m in (ok, outliers, plan.filled)))
    fits = []
    for (tracker, track_id), (accel, s, ll, *_), (n_ok, n_out, n_fill) in zip(heads.iter_rows(), fitted, counted):
        q = accel**2
        fits.append(TrackFit(tracker, int(track_id), q, s, math.nan, ll, n_ok + n_out, n_out, n_fill, model.describe(q, s)))
    return out, fits


def _space_observations(model: SpaceSmoothing, full: pl.DataFrame, starts: np.ndarray, raw: pl.DataFrame | None,
                        P3: np.ndarray, measured: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, list]:
    """``z`` (n, 3) and ``R`` (n, 3, 3) on the observed rows (NaN and I elsewhere), those rows, and per
    track the grid of ``R``'s scale: the tracker's raw 3-D measurements with their covariance where
    the replay kept them, else its own ``X, Y, Z`` with ``R = I`` (``σ`` from the model's sigma grid, m)."""
    n = full.height
    z, R0, ok = P3.copy(), np.broadcast_to(np.eye(3), (n, 3, 3)).copy(), measured.copy()
    has_raw = _has_raw(full, starts, raw, "zX")
    if has_raw.any():
        r = _raw_rows(full, raw)
        zr = np.stack([r[c].to_numpy().astype(float) for c in ("zX", "zY", "zZ")], axis=1)
        c = {k: r[k].to_numpy().astype(float) for k in ("rXX", "rXY", "rXZ", "rYY", "rYZ", "rZZ")}
        Rr = np.stack([np.stack([c["rXX"], c["rXY"], c["rXZ"]], -1), np.stack([c["rXY"], c["rYY"], c["rYZ"]], -1),
                       np.stack([c["rXZ"], c["rYZ"], c["rZZ"]], -1)], axis=1)
        hr = segments.per_row(has_raw, starts)
        z, R0 = np.where(hr[:, None], zr, z), np.where(hr[:, None, None], Rr, R0)
        ok = np.where(hr, measured & np.isfinite(zr).all(axis=1) & np.isfinite(Rr).all(axis=(1, 2)), ok)
    z[~ok] = np.nan
    R0[~ok] = np.eye(3)
    return z, R0, ok, [model.scale_grid if h else model.sigma_grid for h in has_raw]



def _per_axis(model: SpaceSmoothing, track: _SpaceTrack) -> bool:
    """Whether ``track`` splits into three independent axes: the model's transition and process noise
    are the same constant velocity on each axis, and ``R`` is a multiple of I (no raw covariance)."""
    F = model.F()
    if not np.array_equal(F, np.kron(np.eye(3), np.array([[1.0, 1.0], [0.0, 1.0]]))):
        return False
    if any(not np.array_equal(Q := model.Q(a), np.kron(np.eye(3), Q[:2, :2])) for a in model.accel_grid):
        return False
    return bool((track.R0 == np.eye(3)).all())


SPACE_PRIOR = rts.Prior(float(rts_space.PRIOR[0, 0]), float(rts_space.PRIOR[1, 1]))


def _space_filter_axes(model: SpaceSmoothing, tracks: list[_SpaceTrack], accel: np.ndarray, s: np.ndarray, keep: bool):
    """:func:`_space_filter` for tracks that split into axes (:func:`_per_axis`): the image kernel
    (:mod:`.rts`) on three position axes, observed with ``R = s² I``."""
    out: list = [None] * len(tracks)
    width = LANE_ELEMENTS if keep else max(1, LANE_ELEMENTS // len(accel))
    def pack(lane: list[int]) -> rts.Columns:  # (packed where used: a long lane's columns go when done with)
        zs = [np.concatenate([tracks[i].z, np.full_like(tracks[i].z, np.nan)], axis=1) for i in lane]
        return rts.Columns.pack(zs, [np.ones(len(z)) for z in zs])

    for lane in _lanes([len(t.z) for t in tracks], width):
        a, sc = (accel[lane], s[lane]) if keep else (accel, s)
        Q, s2 = rts.axis_noise(model.Q, a), sc * sc
        if not keep:
            ll = rts.grid_loglik(lambda lane=lane: pack(lane), Q, s2, np.zeros_like(s2), LANE_ELEMENTS, SPACE_PRIOR)
            for j, i in enumerate(lane):
                out[i] = ll[:, j]
            continue
        for i in lane:
            out[i] = (np.empty((len(tracks[i].z), 6)), np.empty((len(tracks[i].z), 6)))
        for lo, (p, v, pa, _, pc) in rts.smooth_pieces(pack(lane), Q, s2, np.zeros_like(s2), SPACE_PRIOR):  # last first
            for j, i in enumerate(lane):
                m = min(len(tracks[i].z) - lo, len(p))
                if m > 0:
                    out[i][0][lo:lo + m] = np.stack([p[:m, :, j], v[:m, :, j]], axis=2).reshape(m, 6)  # X Ẋ Y Ẏ Z Ż
                    out[i][1][lo:lo + m] = np.tile(np.stack([pa[:m, 0, j], pc[:m, 0, j]], axis=1), 3)  # one covariance
    return out


def _space_filter(model: SpaceSmoothing, tracks: list[_SpaceTrack], accel: np.ndarray, s: np.ndarray, keep: bool):
    """:func:`rts_space.filter_space` of ``tracks`` in lanes, at grid points ``(accel, s)`` (each (G,))
    or, with ``keep``, at one ``(accel, s)`` per track (each (B,)) followed by the RTS pass.
    Returns per track its log-likelihoods (G,) or its smoothed ``x`` (n, 6) and the diagonal of ``P``
    (n, 6: the output needs only the variances). Tracks that split into axes go through the image kernel."""
    axes = [_per_axis(model, t) for t in tracks]
    if any(axes):
        out: list = [None] * len(tracks)
        for split in (True, False):
            part = [i for i in range(len(tracks)) if axes[i] == split]
            if part:
                run = _space_filter_axes if split else _space_filter
                idx = np.array(part)
                sub = run(model, [tracks[i] for i in part], accel[idx] if keep else accel, s[idx] if keep else s, keep)
                for i, r in zip(part, sub):
                    out[i] = r
        return out
    F = model.F()
    out: list = [None] * len(tracks)
    width = max(1, LANE_ELEMENTS // 64 // (1 if keep else len(accel)))
    for lane in _lanes([len(t.z) for t in tracks], width):
        cols = rts_space.SpaceColumns.pack([tracks[i].z for i in lane], [tracks[i].R0 for i in lane])
        a, sc = (accel[lane], s[lane]) if keep else (accel, s)
        Q = np.stack([model.Q(float(v)) for v in a])
        Q, s2 = (Q[None], (sc * sc)[None, :, None, None]) if keep else (Q[:, None], (sc * sc)[:, None, None, None])
        ll, xs, Ps = rts_space.filter_space(cols, F, Q, s2, keep)
        if keep:
            xs, Ps = rts_space.rts_space(xs, Ps, F, Q)
        for j, i in enumerate(lane):
            n = len(tracks[i].z)
            out[i] = (xs[:n, 0, j], np.diagonal(Ps[:n, 0, j], axis1=1, axis2=2).copy()) if keep else ll[:, j]
    return out


def _fit_space(model: SpaceSmoothing, tracks: list[_SpaceTrack], cfg: SmoothConfig) -> list[tuple]:
    """Per track, the acceleration and ``R`` scale of the highest likelihood (first on ties), the
    smoothed ``x, P``; then again without the measurements beyond ``outlier_sigma`` of their own
    noise (a splinter, a merge). Per track ``(accel, s, log-likelihood, x, diag P, observed rows, outliers)``;
    its ``z`` and ``R0`` lose the outliers in place."""
    best: list = [None] * len(tracks)
    for grid in dict.fromkeys(t.grid for t in tracks):
        part = [i for i, t in enumerate(tracks) if t.grid == grid]
        accel, s = (g.ravel() for g in np.meshgrid(np.array(model.accel_grid, float), np.array(grid, float), indexing="ij"))
        for i, ll in zip(part, _space_filter(model, [tracks[i] for i in part], accel, s, keep=False)):
            ll = np.where(np.isnan(ll), -math.inf, ll)
            g = int(np.argmax(ll))
            best[i] = (float(accel[g]), float(s[g]), float(ll[g]))
    accel, s = np.array([b[0] for b in best]), np.array([b[1] for b in best])
    smoothed = _space_filter(model, tracks, accel, s, keep=True)
    oks = [t.ok.copy() for t in tracks]
    outliers = [np.zeros(len(t.z), bool) for t in tracks]
    again = []
    for i, t in enumerate(tracks):
        if oks[i].sum() > 4:
            resid = np.where(oks[i][:, None], t.z - smoothed[i][0][:, [0, 2, 4]], 0.0)
            d2 = (resid * np.linalg.solve(t.R0 * s[i] * s[i], resid[..., None])[..., 0]).sum(axis=1) / 3.0
            bad = oks[i] & (np.sqrt(d2) > cfg.outlier_sigma)
            if bad.any() and (oks[i] & ~bad).sum() >= 2:
                outliers[i], t.z[bad], t.R0[bad] = bad, np.nan, np.eye(3)
                oks[i] = oks[i] & ~bad
                again.append(i)
                smoothed[i] = None  # (smoothed again below: not held meanwhile)
    if again:
        redo = _space_filter(model, [tracks[i] for i in again], accel[again], s[again], keep=True)
        for i, sm in zip(again, redo):
            smoothed[i] = sm
    return [(accel[i], s[i], best[i][2], *smoothed[i], oks[i], outliers[i]) for i in range(len(tracks))]


def span_times(t: np.ndarray, frames: np.ndarray, frame_times: Mapping[int, int] | None) -> np.ndarray:
    """Each row's time (ns, float; NaN unknown): its own, else the log's time of its frame."""
    if frame_times:
        logged, found = logged_times(frame_times, frames)
        t = np.where(np.isfinite(t), t, np.where(found, logged.astype(float), np.nan))
    return t


def frame_rate(t: np.ndarray) -> float:
    """A track's frames per second: 1 / its median frame interval (``t``: :func:`span_times` of its span)."""
    if np.isfinite(t).sum() >= 2:
        dt = np.nanmedian(np.diff(t)) * 1e-9
        return 1.0 / dt if np.isfinite(dt) and dt > 0 else math.nan
    return math.nan


def _space_columns(full: pl.DataFrame, starts: np.ndarray, xs: np.ndarray, Ps: np.ndarray, plan: _Plan,
                   has_pos: np.ndarray, P3: np.ndarray, frame_times: Mapping[int, int] | None,
                   rate: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """Smoothed ``X, Y, Z`` with their std and velocity (m/s at each track's median frame interval;
    ``rate``: each track's frames per second, when known); the image columns are the tracker's own box
    on its rows, linear across filled frames (the 3-D model says nothing about the box), a filled row's
    image velocity the rate of those positions."""
    frames = full["frame"].to_numpy().astype(np.int64)
    if rate is None:
        t = span_times(full["t_ns"].to_numpy().astype(float), frames, frame_times)
        rate = np.array([frame_rate(t[a:b]) for a, b in zip(starts[:-1].tolist(), starts[1:].tolist())])
    per_s = segments.per_row(rate, starts)
    f = frames.astype(float)
    cols: dict[str, np.ndarray] = {}
    for k, name in enumerate(("X", "Y", "Z")):
        cols[name] = np.where(plan.keep, np.where(plan.smoothed, xs[:, 2 * k], P3[:, k]), np.nan)
        cols[f"{name}_std"] = np.where(plan.smoothed, np.sqrt(np.maximum(Ps[:, 2 * k], 0.0)), np.nan)
        cols[f"V{name}"] = np.where(plan.smoothed, xs[:, 2 * k + 1] * per_s, np.nan)
    for name in ("x", "y", "w", "h", "vx", "vy"):
        values = np.where(has_pos, full[name].to_numpy().astype(float), np.nan)
        cols[name] = np.where(plan.keep, _interp(f, values, plan.filled, starts), np.nan)
    for v, p in (("vx", "x"), ("vy", "y")):  # a filled row moves as its own (linear) positions do
        values = np.where(has_pos, full[p].to_numpy().astype(float), np.nan)
        cols[v] = np.where(plan.filled & plan.keep, _interp_rate(f, values, plan.filled, starts), cols[v])
    return cols



class _FrameRows(Mapping):
    """A mapping keyed by frame number over arrays: ``frames`` (int64) in the order they were read, each
    frame's row found by a search of the sorted copy (by its own value when the frames are 0, 1, 2 ...).
    Iterates in the order the frames were read."""

    def __init__(self, frames) -> None:
        self.frames = np.array(frames, dtype=np.int64)
        self._order = np.argsort(self.frames, kind="stable")
        self._sorted = self.frames[self._order]
        # frames 0, 1, 2 ... in order (a log's images as read): a frame is its own row, no search
        self._dense = bool(np.array_equal(self.frames, np.arange(len(self.frames))))

    def _row(self, frame) -> int:
        if not isinstance(frame, (int, np.integer)) or isinstance(frame, bool):
            return -1
        if self._dense:
            return int(frame) if 0 <= frame < len(self.frames) else -1
        i = int(np.searchsorted(self._sorted, frame))
        return int(self._order[i]) if i < len(self._sorted) and self._sorted[i] == frame else -1

    def __contains__(self, frame) -> bool:
        return self._row(frame) >= 0

    def __iter__(self):
        return iter(self.frames.tolist())

    def __len__(self) -> int:
        return len(self.frames)


class FrameCameras(_FrameRows):
    """Frame -> the posed camera of that frame (:class:`PtzCamera`), built when asked from the frame's
    pan, tilt, zoom and focus kept as arrays (32 bytes a frame; a dict of cameras made ``log_context``
    of a 200k-frame log peak at 167 MB, now 59: ``benchmarks/bench_flight.py``). Iterates in the order
    the poses were added (the frames' times); the last few cameras asked for are kept (a caller that
    asks for one frame again)."""

    def __init__(self, frames, poses, lens) -> None:
        """``frames`` (n,), ``poses`` (n × 4 values: pan, tilt, zoom, focus), ``lens`` the lens table."""
        super().__init__(frames)
        self._poses = np.array(poses, dtype=np.float64).reshape(-1, 4)
        self._lens = lens
        self._recent: dict[int, PtzCamera] = {}

    def __getitem__(self, frame) -> PtzCamera:
        cam = self._recent.get(frame)
        if cam is not None:
            return cam
        row = self._row(frame)
        if row < 0:
            raise KeyError(frame)
        pan, tilt, zoom, focus = self._poses[row].tolist()
        cam = PtzCamera.from_reading(PtzReading(0, pan, tilt, zoom, focus), self._lens)
        if len(self._recent) >= 64:
            self._recent.pop(next(iter(self._recent)))
        self._recent[int(frame)] = cam
        return cam


class FrameTimes(_FrameRows):
    """Frame -> log time (ns) as two int64 arrays (16 bytes a frame, where a dict holds two Python ints and
    its table entry). Iterates in the order the frames were read; ``values()`` in the same order."""

    def __init__(self, frames, times) -> None:
        super().__init__(frames)
        self.times = np.array(times, dtype=np.int64)

    def __getitem__(self, frame) -> int:
        row = self._row(frame)
        if row < 0:
            raise KeyError(frame)
        return int(self.times[row])

    def values(self) -> list[int]:  # (not one look-up a frame)
        return self.times.tolist()

    def items(self) -> list[tuple[int, int]]:
        return list(zip(self.frames.tolist(), self.times.tolist()))

    def sorted_arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """Frames ascending and their times."""
        return self._sorted, self.times[self._order]


def log_context(log) -> tuple[Mapping[int, int], Mapping[int, PtzCamera]]:
    """Frame times (:class:`FrameTimes`) and (where the log has PTZ encoders and a lens table) the posed
    camera of every frame (:class:`FrameCameras`), read from ``log`` without decoding any image."""
    from trackreplay.replay.log.frames import FrameTopics, PtzInterpolator, _ptz_stream
    from trackreplay.replay.log.reader import LogReader
    from trackreplay.schemas.records import LensTable

    reader = log if isinstance(log, LogReader) else LogReader(log)
    topics = FrameTopics.detect(reader)
    indices, stamps = array("q"), array("q")
    for item in reader.messages([topics.image]):
        if item.lost is None:
            indices.append(item.index)
            stamps.append(item.log_time)
    index, stamp = np.frombuffer(indices, np.int64), np.frombuffer(stamps, np.int64)
    times: Mapping[int, int]
    if np.unique(index).size == index.size:
        times = FrameTimes(index, stamp)
    else:  # (an index read twice: the last time, as a dict keeps it)
        times = dict(zip(indices, stamps))
    del index, stamp, indices, stamps
    lens_pb = reader.first(topics.lens) if topics.lens else None
    if not (topics.ptz and lens_pb is not None):
        return times, {}
    lens = LensTable.from_pb(lens_pb)
    ptz = PtzInterpolator(_ptz_stream(reader, topics.ptz, None), 100_000_000)
    frames, poses = array("q"), array("d")  # 8 bytes a value, not a tuple of floats a frame
    if isinstance(times, FrameTimes):  # the frames in time order (stable: as sorted() by time orders them)
        order = np.argsort(times.times, kind="stable")
        in_time = zip(times.frames[order].tolist(), times.times[order].tolist())
    else:
        in_time = ((index, times[index]) for index in sorted(times, key=times.__getitem__))
    for index, t_ns in in_time:
        pose = ptz.at(t_ns)
        if pose is not None:
            frames.append(index)
            poses.extend((pose.pan, pose.tilt, pose.zoom, pose.focus))
    return times, FrameCameras(frames, poses, lens) if frames else {}
