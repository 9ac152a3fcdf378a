"""Offline fixed-interval smoothing of every track over the whole log (issue 13).

The trackers are causal: a frame's estimate uses only the past. After the event the whole log is
in hand, so every estimate may use the future as well. :func:`smooth_trajectory` runs, per track,
a Rauch–Tung–Striebel smoother (filterpy's ``KalmanFilter.batch_filter`` forward, then its
``rts_smoother`` backward) over the tracker's motion model, and fills the frames the tracker did
not measure from the smoothed state, with a standard deviation.

**Model.** Constant velocity in the image, per track: state ``(x, vx, y, vy)`` in px and
px/frame, white-acceleration process noise of spectral density ``q`` (px²/frame³), one step per
frame (``F = [[1, 1], [0, 1]]`` per axis, ``Q = q [[1/3, 1/2], [1/2, 1]]``). This is the motion
model of the flow tracker's image-plane position (seed 004 §4.3, whose third state, a
Gauss–Markov acceleration, is the white acceleration here) and of the colour particle filter
(seed 002: ``x ← x + ω``). The golf tracker's image position follows a ball the operator keeps
near the centre, so the same model is used for it; its 3-D flight has its own offline fit
(:mod:`trackreplay.replay.flight`). The group tracker's 3-D constant-velocity EKF (seed 003) is
not in the project yet (``trackers/groups``): its tracks get the image model until it lands.

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
  ``linear`` / ``cubic`` appear for rows filled by :func:`trackreplay.replay.export.fill_gaps`,
  which the smoother replaces wherever a model exists (every tracker of the project has one).

Box size ``w, h`` and the world position ``X, Y, Z`` of filled rows are linear interpolations of
the tracker's neighbouring values (the image model says nothing about them). With a camera pose in
the log (PTZ encoders and lens table) the lines of sight ``dx, dy, dz`` are recomputed from the
smoothed ``x, y`` through the frame's camera; without one they are interpolated and renormalised.

Measured against ground truth in ``docs/smoothing.md`` (``python docs/smoothing.py``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import polars as pl
from filterpy.kalman import KalmanFilter

from trackreplay.replay.trajectory import COLUMNS, SCHEMA
from trackreplay.schemas.errors import TrackreplayError
from trackreplay.trackers.geometry.ptz import PtzCamera

EXTRA_SCHEMA: dict[str, pl.DataType] = {
    "x_std": pl.Float64, "y_std": pl.Float64, "vx_std": pl.Float64, "vy_std": pl.Float64, "fill": pl.String,
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


@dataclass(frozen=True)
class ImageModel:
    """Constant velocity in the image: per axis ``(p, v)`` in px and px/frame, one step per frame.

    White acceleration integrated over the frame: ``Q = q [[1/3, 1/2], [1/2, 1]]`` per axis. With
    ``observe_velocity`` the track's own ``vx, vy`` on measured rows are observations too (noise
    ``σ_v / √confidence``): the flow tracker's velocity is its primary measurement (mean optical
    flow), filtered by its own Kalman filter.
    """

    name: str = "image constant velocity"
    observe_velocity: bool = False

    @staticmethod
    def F() -> np.ndarray:  # noqa: N802 (textbook symbol)
        return np.kron(np.eye(2), np.array([[1.0, 1.0], [0.0, 1.0]]))

    @staticmethod
    def Q(q: float) -> np.ndarray:  # noqa: N802
        return np.kron(np.eye(2), q * np.array([[1.0 / 3.0, 0.5], [0.5, 1.0]]))

    @staticmethod
    def H() -> np.ndarray:  # noqa: N802
        """z = (x, y, vx, vy) from the state (x, vx, y, vy)."""
        H = np.zeros((4, 4))
        H[0, 0] = H[1, 2] = H[2, 1] = H[3, 3] = 1.0
        return H


# The motion model each tracker's tracks are smoothed with (see the module docstring).
MODELS: dict[str, ImageModel] = {
    "flow": ImageModel("flow: image constant velocity, positions and velocities observed (seed 004 §4.3)",
                       observe_velocity=True),
    "colorpf": ImageModel("colorpf: image constant velocity (seed 002 transition)"),
    "golf": ImageModel("golf: image constant velocity (3-D: trackreplay flight)"),
    "groups": ImageModel("groups: image constant velocity (the group EKF's 3-D model is not in the project yet)"),
}
DEFAULT_MODEL = ImageModel()


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


MISSING_VAR = 1e12  # the variance of an absent component of z (it then carries no information)


def _run(model: ImageModel, z: np.ndarray, r: np.ndarray, q: float, sigma: float, sigma_v: float, smooth: bool):
    """Forward filter (and backward smoother) over ``z`` (n, 4) = (x, y, vx, vy), NaN where a
    component is not observed, with measurement variances ``(σ², σ², σ_v², σ_v²) r`` (n,).
    Returns (log-likelihood of the observed components, x, P, smoother gains)."""
    n = len(z)
    have = np.isfinite(z)
    first = int(np.flatnonzero(have[:, 0])[0])
    kf = KalmanFilter(dim_x=4, dim_z=4)
    kf.F, kf.H, kf.Q = model.F(), model.H(), model.Q(q)
    s0 = sigma * sigma * r[first]
    kf.x = np.array([z[first, 0], 0.0, z[first, 1], 0.0])
    kf.P = np.diag([s0 + 1e4, 1e2, s0 + 1e4, 1e2])  # vague, around the first observation
    base = np.array([sigma, sigma, sigma_v, sigma_v]) ** 2
    zs: list = []
    Rs: list = []
    for k in range(n):
        if not have[k].any():
            zs.append(None)
            Rs.append(np.diag(base))
            continue
        zs.append(np.where(have[k], z[k], 0.0))
        Rs.append(np.diag(np.where(have[k], base * r[k], MISSING_VAR)))
    means, covs, means_p, covs_p = kf.batch_filter(zs, Rs=Rs)
    H = kf.H
    ll = 0.0
    for k in range(n):
        if zs[k] is None or k == first:
            continue
        sel = have[k]
        y = (zs[k] - H @ means_p[k])[sel]
        S = (H @ covs_p[k] @ H.T + Rs[k])[np.ix_(sel, sel)]
        ll -= 0.5 * (float(y @ np.linalg.solve(S, y)) + math.log(np.linalg.det(S)) + sel.sum() * math.log(2.0 * math.pi))
    if not smooth:
        return ll, means, covs, None
    xs, Ps, K, _ = kf.rts_smoother(means, covs)
    return ll, xs, Ps, K


def _select(model: ImageModel, z: np.ndarray, r: np.ndarray, cfg: SmoothConfig) -> tuple[float, float, float, float]:
    """(q, σ₀, σ_v, log-likelihood) of the grid point with the highest likelihood (first on ties)."""
    best = (cfg.q_grid[0], cfg.sigma_grid[0], cfg.sigma_v_grid[0], -math.inf)
    sigma_vs = cfg.sigma_v_grid if np.isfinite(z[:, 2:]).any() else cfg.sigma_v_grid[:1]
    for q in cfg.q_grid:
        for s in cfg.sigma_grid:
            for sv in sigma_vs:
                ll = _run(model, z, r, q, s, sv, smooth=False)[0]
                if ll > best[3]:
                    best = (q, s, sv, ll)
    return best


def smooth_track(model: ImageModel, z: np.ndarray, confidence: np.ndarray, cfg: SmoothConfig = SmoothConfig()):
    """Smooth one track over consecutive frames.

    ``z`` (n, 2) or (n, 4): observed image positions (and velocities), NaN where a frame or a
    component is not an observation; ``confidence`` (n,): the tracker's confidence (NaN: none).
    Returns ``(x, P, K, outliers, fit)`` with ``x`` (n, 4) = (x, vx, y, vy), ``P`` (n, 4, 4), the
    smoother gains ``K``, ``outliers`` (n,) bool and ``fit = (q, σ₀, σ_v, log-likelihood)``.
    """
    conf = np.where(np.isfinite(confidence), np.maximum(confidence, cfg.min_confidence), 1.0)
    r = 1.0 / conf
    z = np.array(z, dtype=np.float64)
    if z.shape[1] == 2:
        z = np.concatenate([z, np.full_like(z, np.nan)], axis=1)
    observed = np.isfinite(z[:, :2]).all(axis=1)
    z[~observed] = np.nan
    outliers = np.zeros(len(z), bool)
    fit = _select(model, z, r, cfg)
    _, xs, Ps, K = _run(model, z, r, *fit[:3], smooth=True)
    if observed.sum() > 4:
        resid = z[:, :2] - xs[:, [0, 2]]
        var = fit[1] ** 2 * r  # the measurement's own variance: a sound observation lies well inside it
        bad = observed & (np.sqrt((resid**2).sum(axis=1) / (2.0 * var)) > cfg.outlier_sigma)
        if bad.any() and (observed & ~bad).sum() >= 2:
            outliers = bad
            z[bad] = np.nan
            fit = _select(model, z, r, cfg)
            _, xs, Ps, K = _run(model, z, r, *fit[:3], smooth=True)
    return xs, Ps, K, outliers, fit


def _gap_runs(missing: np.ndarray) -> list[tuple[int, int]]:
    runs, i, n = [], 0, missing.size
    while i < n:
        if missing[i]:
            j = i
            while j < n and missing[j]:
                j += 1
            runs.append((i, j))
            i = j
        else:
            i += 1
    return runs


def _interp(frames: np.ndarray, values: np.ndarray, where: np.ndarray) -> np.ndarray:
    ok = np.isfinite(values)
    out = values.copy()
    if ok.sum() >= 2:
        out[where] = np.interp(frames[where], frames[ok], values[ok])
    elif ok.sum() == 1:
        out[where] = values[ok][0]
    return out


def _smooth_one(track: pl.DataFrame, cfg: SmoothConfig, frame_times: Mapping[int, int] | None,
                cameras: Mapping[int, PtzCamera] | None) -> tuple[pl.DataFrame, TrackFit | None]:
    head = track.row(0, named=True)
    tracker, track_id = head["tracker"], head["track_id"]
    positioned = track.filter(pl.col("x").is_not_null() & pl.col("y").is_not_null() & (pl.col("status") != "lost"))
    if positioned.height == 0:
        return track.with_columns(*(pl.lit(None, dtype=t).alias(c) for c, t in EXTRA_SCHEMA.items())).select(SMOOTH_COLUMNS), None
    lo, hi = int(positioned["frame"].min()), int(positioned["frame"].max())
    frames = np.arange(lo, hi + 1, dtype=np.int64)
    full = pl.DataFrame({"frame": frames}).join(track, on="frame", how="left")
    n = len(frames)
    status = full["status"].fill_null("lost").to_numpy().astype(object)
    x = full["x"].to_numpy().astype(float)
    y = full["y"].to_numpy().astype(float)
    conf = full["confidence"].to_numpy().astype(float)
    has_pos = np.isfinite(x) & np.isfinite(y) & (status != "lost")
    measured = has_pos & (status == "measured")
    model = MODELS.get(tracker, DEFAULT_MODEL)
    vx = full["vx"].to_numpy().astype(float) if model.observe_velocity else np.full(n, np.nan)
    vy = full["vy"].to_numpy().astype(float) if model.observe_velocity else np.full(n, np.nan)
    z = np.where(measured[:, None], np.stack([x, y, vx, vy], axis=1), np.nan)
    if measured.sum() == 0:  # only predictions: nothing to smooth; keep the rows as they are
        out = full.with_columns(*(pl.lit(None, dtype=t).alias(c) for c, t in EXTRA_SCHEMA.items()))
        return _finish(out, tracker, track_id, frame_times), None
    xs, Ps, _, outliers, (q, s, sv, ll) = smooth_track(model, z, conf, cfg)

    # Runs of frames without an observation (predicted, lost, absent, or rejected as an outlier) are
    # filled by the smoother when at most max_gap long and bracketed by observations: the smoother
    # interpolates there. Elsewhere (a run that ends the track or is too long) it would extrapolate,
    # so those rows keep the tracker's own values (predicted) or stay lost.
    observed = measured & ~outliers
    fill_gap = np.zeros(n, bool)
    for a, b in _gap_runs(~observed):
        if a > 0 and b < n and b - a <= cfg.max_gap:
            fill_gap[a:b] = True
    smoothed = observed | fill_gap
    keep = smoothed | has_pos
    filled = fill_gap & ~measured  # predicted and gap rows taken from the smoother: status interpolated
    fill = np.full(n, None, dtype=object)
    fill[observed] = "rts"
    fill[fill_gap & measured] = "rts_outlier"
    fill[filled] = "rts_gap"
    new_status = np.where(filled, "interpolated", np.where(keep, status, "lost")).astype(object)
    f = frames.astype(float)

    def masked(v: np.ndarray) -> np.ndarray:
        return np.where(keep, v, np.nan)

    std = np.sqrt(np.maximum(np.stack([Ps[:, 0, 0], Ps[:, 1, 1], Ps[:, 2, 2], Ps[:, 3, 3]], axis=1), 0.0))
    raw = {"x": x, "vx": full["vx"].to_numpy().astype(float), "y": y, "vy": full["vy"].to_numpy().astype(float)}
    cols: dict[str, np.ndarray] = {}
    for k, name in enumerate(("x", "vx", "y", "vy")):
        cols[name] = masked(np.where(smoothed, xs[:, k], raw[name]))
        cols[f"{name}_std"] = np.where(smoothed, std[:, k], np.nan)
    for name in ("w", "h", "X", "Y", "Z", "dx", "dy", "dz"):
        values = np.where(has_pos, full[name].to_numpy().astype(float), np.nan)
        cols[name] = masked(_interp(f, values, filled))
    # Lines of sight: through the frame's camera from the smoothed pixel, else interpolated and renormalised.
    d = np.stack([cols["dx"], cols["dy"], cols["dz"]], axis=1)
    if cameras:
        for i in np.flatnonzero(smoothed):
            cam = cameras.get(int(frames[i]))
            if cam is not None:
                d[i] = cam.line_of_sight(np.array([[cols["x"][i], cols["y"][i]]]))[0]
    norm = np.linalg.norm(d, axis=1)
    ok = np.isfinite(norm) & (norm > 0)
    d[ok] /= norm[ok][:, None]
    cols["dx"], cols["dy"], cols["dz"] = d[:, 0], d[:, 1], d[:, 2]
    confidence = np.where(filled, np.nan, conf)
    out = full.with_columns(
        *(pl.Series(k, v, dtype=pl.Float64, nan_to_null=True) for k, v in cols.items()),
        pl.Series("confidence", confidence, dtype=pl.Float64, nan_to_null=True),
        pl.Series("status", new_status, dtype=pl.String),
        pl.Series("fill", fill, dtype=pl.String),
    )
    fit = TrackFit(tracker, int(track_id), q, s, sv, ll, int(measured.sum()), int(outliers.sum()), int(filled.sum()))
    # Rows of the track outside its positioned span (lost before the first / after the last position).
    outside = track.filter((pl.col("frame") < lo) | (pl.col("frame") > hi)).with_columns(
        *(pl.lit(None, dtype=t).alias(c) for c, t in EXTRA_SCHEMA.items()))
    out = pl.concat([_finish(out, tracker, track_id, frame_times), outside.select(SMOOTH_COLUMNS)])
    return out.sort("frame"), fit


def _finish(full: pl.DataFrame, tracker: str, track_id: int, frame_times: Mapping[int, int] | None) -> pl.DataFrame:
    """Identity columns and the times of added frames (the log's frame times, else interpolated)."""
    t = full["t_ns"].to_numpy().astype(float)
    missing = ~np.isfinite(t)
    if missing.any():
        frames = full["frame"].to_numpy()
        if frame_times:
            t[missing] = [frame_times.get(int(k), np.nan) for k in frames[missing]]
        t = _interp(frames.astype(float), t, ~np.isfinite(t))
    return full.with_columns(
        pl.lit(tracker).alias("tracker"),
        pl.lit(track_id, dtype=pl.Int64).alias("track_id"),
        pl.Series("t_ns", np.round(t), dtype=pl.Float64).cast(pl.Int64),
    ).select(SMOOTH_COLUMNS)


def smooth_trajectory(df: pl.DataFrame, config: SmoothConfig = SmoothConfig(), *,
                      frame_times: Mapping[int, int] | None = None,
                      cameras: Mapping[int, PtzCamera] | None = None) -> tuple[pl.DataFrame, list[TrackFit]]:
    """RTS-smooth every track of a trajectory table (see the module docstring).

    ``frame_times`` (frame -> t_ns) gives added frames their log time; ``cameras`` (frame -> posed
    camera) lets lines of sight follow the smoothed pixels. Deterministic: no randomness, a fixed
    parameter grid, tracks in canonical order.
    """
    if config.max_gap < 0:
        raise TrackreplayError(f"--max-gap must be >= 0, not {config.max_gap}")
    if df.is_empty():
        return df.with_columns(*(pl.lit(None, dtype=t).alias(c) for c, t in EXTRA_SCHEMA.items())).select(SMOOTH_COLUMNS), []
    parts, fits = [], []
    for _, track in df.select(COLUMNS).sort(["tracker", "track_id", "frame"]).group_by(["tracker", "track_id"], maintain_order=True):
        out, fit = _smooth_one(track, config, frame_times, cameras)
        parts.append(out.cast({**SCHEMA, **EXTRA_SCHEMA}))
        if fit is not None:
            fits.append(fit)
    return pl.concat(parts).sort(["tracker", "track_id", "frame"], maintain_order=True), fits


def log_context(log) -> tuple[dict[int, int], dict[int, PtzCamera]]:
    """Frame times and (where the log has PTZ encoders and a lens table) the posed camera of every
    frame, read from ``log`` without decoding any image."""
    from trackreplay.replay.frames import FrameTopics, PtzInterpolator, _ptz_stream
    from trackreplay.replay.reader import LogReader
    from trackreplay.schemas.records import LensTable

    reader = log if isinstance(log, LogReader) else LogReader(log)
    topics = FrameTopics.detect(reader)
    times: dict[int, int] = {}
    for item in reader.messages([topics.image]):
        if item.lost is None:
            times[item.index] = item.log_time
    cameras: dict[int, PtzCamera] = {}
    lens_pb = reader.first(topics.lens) if topics.lens else None
    if topics.ptz and lens_pb is not None:
        lens = LensTable.from_pb(lens_pb)
        ptz = PtzInterpolator(_ptz_stream(reader, topics.ptz, None), 100_000_000)
        for index in sorted(times, key=lambda i: times[i]):
            pose = ptz.at(times[index])
            if pose is not None:
                cameras[index] = PtzCamera.from_reading(pose, lens)
    return times, cameras
