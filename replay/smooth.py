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
(:mod:`trackreplay.replay.flight`). Group tracks are smoothed in 3-D with the group EKF's own model
(:class:`GroupModel`, seed 003 §3.2): state ``[X Ẋ Y Ẏ Z Ż]`` in the left camera frame, columns
``VX, VY, VZ`` (m/s) and ``X_std, Y_std, Z_std`` (m) added.

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

from trackreplay.replay.trajectory import COLUMNS, SCHEMA, interpolated_times
from trackreplay.schemas.errors import TrackreplayError
from trackreplay.trackers.geometry.ptz import PtzCamera

EXTRA_SCHEMA: dict[str, pl.DataType] = {
    "x_std": pl.Float64, "y_std": pl.Float64, "vx_std": pl.Float64, "vy_std": pl.Float64, "fill": pl.String,
    # 3-D models (groups): smoothed velocity (m/s, the log's frame rate) and position std (m)
    "VX": pl.Float64, "VY": pl.Float64, "VZ": pl.Float64, "X_std": pl.Float64, "Y_std": pl.Float64, "Z_std": pl.Float64,
}
# Raw observations (the tracker's measurement before its own filter), one row per track and frame:
# image position/velocity (flow: centroid and mean flow) or a 3-D point with its covariance (groups:
# the mean [u v d] of the group's points carried through the rig, R = J⁻¹ diag(σ_u², σ_v², σ_d²) J⁻ᵀ).
OBS_SCHEMA: dict[str, pl.DataType] = {
    "tracker": pl.String, "track_id": pl.Int64, "frame": pl.Int64,
    "zx": pl.Float64, "zy": pl.Float64, "zvx": pl.Float64, "zvy": pl.Float64,
    "zX": pl.Float64, "zY": pl.Float64, "zZ": pl.Float64,
    "rXX": pl.Float64, "rXY": pl.Float64, "rXZ": pl.Float64, "rYY": pl.Float64, "rYZ": pl.Float64, "rZZ": pl.Float64,
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
    # With raw observations (flow): observe the raw velocity (mean flow, eq. 11) instead of the
    # tracker's filtered one. Off: on flow-sim1-3 the raw mean flow made the smoothed velocity worse
    # (0.54 vs 0.48 px/frame RMSE) while the raw centroid made positions better (docs/smoothing.md).
    raw_velocity: bool = False
    velocity_lag: int = 0  # a raw velocity observed at frame k measures the state's velocity at k - lag

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
    "flow": ImageModel("flow: image constant velocity; raw centroid (eq. 11) and the tracker's velocity observed (seed 004 §4.3)",
                       observe_velocity=True),
    "colorpf": ImageModel("colorpf: image constant velocity (seed 002 transition)"),
    "golf": ImageModel("golf: image constant velocity (3-D: trackreplay flight)"),
}
DEFAULT_MODEL = ImageModel()


@dataclass(frozen=True)
class GroupModel:
    """The group EKF's own model (seed 003 §3.2, trackers/groups/ekf.py): state ``[X Ẋ Y Ẏ Z Ż]`` in
    the left camera frame (m, m/frame), ``Φ`` block-diagonal ``[[1, 1], [0, 1]]``, process noise
    ``q ΓΓᵀ`` with ``ΓΓᵀ = [[1/4, 1/2], [1/2, 1]]`` per axis (``q = σ_a²``, the EKF's own). Observed:
    the 3-D position, either the raw group measurement (mean ``[u v d]`` of its points through the
    rig, covariance ``R`` from the EKF's σ_u, σ_v, σ_d, scaled by ``s²`` chosen by maximum
    likelihood) or, without intermediates, the tracker's own ``X, Y, Z`` with noise ``σ`` (m)."""

    name: str = "groups: the group EKF's 3-D constant velocity (seed 003 §3.2)"
    # The EKF's own process noise (EkfConfig.accel_sigma², read when smoothing): the raw measurement
    # (the mean of the members' points) wanders as members hide and show, and maximum likelihood over
    # q then follows the wander (velocity RMSE 0.82 -> 1.15 m/s on groups-crossing); with the EKF's q
    # (0.004 m/frame² then) the smoothed velocity is 0.82 -> 0.31 m/s. Only R's scale is chosen by
    # maximum likelihood. An explicit grid here overrides it.
    q_grid: tuple[float, ...] | None = None  # (m/frame²)²
    scale_grid: tuple[float, ...] = (0.3, 1.0, 3.0)  # on the raw R (unitless)
    sigma_grid: tuple[float, ...] = (0.01, 0.03, 0.1, 0.3)  # m, on the tracker's X, Y, Z

    @staticmethod
    def F() -> np.ndarray:  # noqa: N802
        return np.kron(np.eye(3), np.array([[1.0, 1.0], [0.0, 1.0]]))

    @staticmethod
    def Q(q: float) -> np.ndarray:  # noqa: N802
        return np.kron(np.eye(3), q * np.array([[0.25, 0.5], [0.5, 1.0]]))

    @staticmethod
    def H() -> np.ndarray:  # noqa: N802
        H = np.zeros((3, 6))
        H[0, 0] = H[1, 2] = H[2, 4] = 1.0
        return H


GROUP_MODEL = GroupModel()


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


def _interp_rate(frames: np.ndarray, values: np.ndarray, where: np.ndarray) -> np.ndarray:
    """The slope (per frame) of :func:`_interp`'s line at the ``where`` frames: the segment between the
    known values around each (0 with a single known value; NaN with none)."""
    ok = np.isfinite(values)
    out = np.full(len(values), np.nan)
    if ok.sum() == 1:
        out[where] = 0.0
    if ok.sum() < 2:
        return out
    fk, vk = frames[ok], values[ok]
    i = np.clip(np.searchsorted(fk, frames[where]), 1, len(fk) - 1)
    out[where] = (vk[i] - vk[i - 1]) / (fk[i] - fk[i - 1])
    return out


def _smooth_one(track: pl.DataFrame, cfg: SmoothConfig, frame_times: Mapping[int, int] | None,
                cameras: Mapping[int, PtzCamera] | None,
                raw: pl.DataFrame | None = None) -> tuple[pl.DataFrame, TrackFit | None]:
    head = track.row(0, named=True)
    tracker, track_id = head["tracker"], head["track_id"]
    if tracker == "groups":
        return _smooth_group(track, cfg, frame_times, raw)
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
    if raw is not None and raw.height and raw["zx"].is_not_null().any():
        # The tracker's raw measurements (before its own filter) replace its filtered output: the
        # smoother then filters them once, with the future, instead of smoothing a filtered track.
        r = pl.DataFrame({"frame": frames}).join(raw, on="frame", how="left")
        zx, zy = r["zx"].to_numpy().astype(float), r["zy"].to_numpy().astype(float)
        zv = np.stack([r["zvx"].to_numpy().astype(float), r["zvy"].to_numpy().astype(float)], axis=1)
        if model.velocity_lag:
            zv = np.concatenate([zv[model.velocity_lag:], np.full((model.velocity_lag, 2), np.nan)])
        if not model.raw_velocity:
            zv = np.where(measured[:, None], np.stack([vx, vy], axis=1), np.nan)
        ok = measured & np.isfinite(zx) & np.isfinite(zy)
        z = np.full((n, 4), np.nan)
        z[ok, 0], z[ok, 1] = zx[ok], zy[ok]
        if model.observe_velocity:
            z[:, 2:] = zv
        # a raw observation on a frame the tracker also measured; the others fall back to nothing
        measured = measured & (ok | np.isfinite(zv).all(axis=1))
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
        pl.Series("fill", fill.tolist(), dtype=pl.String),
    )
    fit = TrackFit(tracker, int(track_id), q, s, sv, ll, int(measured.sum()), int(outliers.sum()), int(filled.sum()))
    # Rows of the track outside its positioned span (lost before the first / after the last position).
    outside = track.filter((pl.col("frame") < lo) | (pl.col("frame") > hi)).with_columns(
        *(pl.lit(None, dtype=t).alias(c) for c, t in EXTRA_SCHEMA.items()))
    out = pl.concat([_finish(out, tracker, track_id, frame_times), outside.select(SMOOTH_COLUMNS)])
    return out.sort("frame"), fit


def _finish(full: pl.DataFrame, tracker: str, track_id: int, frame_times: Mapping[int, int] | None) -> pl.DataFrame:
    """Identity columns and the times of added frames (the log's frame times, else interpolated)."""
    frames = full["frame"].to_numpy()
    known = full["t_ns"].is_not_null().to_numpy()
    t = full["t_ns"].fill_null(0).to_numpy().astype(np.int64)
    if frame_times and not known.all():  # (ints: float64 would round epoch times off their frames)
        logged = [frame_times.get(int(k)) for k in frames]
        for i in np.flatnonzero(~known):
            if logged[i] is not None:
                t[i], known[i] = logged[i], True
    t = interpolated_times(frames, t, known)
    full = full.with_columns(*(pl.lit(None, dtype=t).alias(c) for c, t in EXTRA_SCHEMA.items() if c not in full.columns))
    return full.with_columns(
        pl.lit(tracker).alias("tracker"),
        pl.lit(track_id, dtype=pl.Int64).alias("track_id"),
        pl.Series("t_ns", t, dtype=pl.Int64),
    ).select(SMOOTH_COLUMNS)


def smooth_trajectory(df: pl.DataFrame, config: SmoothConfig = SmoothConfig(), *,
                      frame_times: Mapping[int, int] | None = None,
                      cameras: Mapping[int, PtzCamera] | None = None,
                      observations: pl.DataFrame | None = None) -> tuple[pl.DataFrame, list[TrackFit]]:
    """RTS-smooth every track of a trajectory table (see the module docstring).

    ``observations`` (:data:`OBS_SCHEMA`, from :func:`observation_rows` during the replay, e.g.
    ``ReplayRequest(observations=True)``): the trackers' raw measurements, used instead of their
    filtered output where present.

    ``frame_times`` (frame -> t_ns) gives added frames their log time; ``cameras`` (frame -> posed
    camera) lets lines of sight follow the smoothed pixels. Deterministic: no randomness, a fixed
    parameter grid, tracks in canonical order.
    """
    if config.max_gap < 0:
        raise TrackreplayError(f"--max-gap must be >= 0, not {config.max_gap}")
    if df.is_empty():
        return df.with_columns(*(pl.lit(None, dtype=t).alias(c) for c, t in EXTRA_SCHEMA.items())).select(SMOOTH_COLUMNS), []
    parts, fits = [], []
    raw_by_track: dict = {}
    if observations is not None and observations.height:
        for key, part in observations.sort(["tracker", "track_id", "frame"]).group_by(["tracker", "track_id"], maintain_order=True):
            raw_by_track[tuple(key)] = part.drop("tracker", "track_id")
    for key, track in df.select(COLUMNS).sort(["tracker", "track_id", "frame"]).group_by(["tracker", "track_id"], maintain_order=True):
        out, fit = _smooth_one(track, config, frame_times, cameras, raw_by_track.get(tuple(key)))
        parts.append(out.cast({**SCHEMA, **EXTRA_SCHEMA}))
        if fit is not None:
            fits.append(fit)
    return pl.concat(parts).sort(["tracker", "track_id", "frame"], maintain_order=True), fits


def _run_group(z: np.ndarray, R: np.ndarray, q: float, smooth: bool):
    """Kalman filter (and RTS) of the group model over ``z`` (n, 3), NaN rows unobserved, with
    per-frame measurement covariances ``R`` (n, 3, 3). Returns (log-likelihood, x, P)."""
    m = GROUP_MODEL
    n = len(z)
    have = np.isfinite(z).all(axis=1)
    first = int(np.flatnonzero(have)[0])
    kf = KalmanFilter(dim_x=6, dim_z=3)
    kf.F, kf.H, kf.Q = m.F(), m.H(), m.Q(q)
    x0 = np.zeros(6)
    x0[[0, 2, 4]] = z[first]
    kf.x = x0
    kf.P = np.diag([1.0, 0.05, 1.0, 0.05, 1.0, 0.05]) ** 2 + np.kron(R[first], np.diag([1.0, 0.0]))
    zs = [z[k] if have[k] else None for k in range(n)]
    Rs = [R[k] if have[k] else np.eye(3) for k in range(n)]
    means, covs, means_p, covs_p = kf.batch_filter(zs, Rs=Rs)
    H = kf.H
    ll = 0.0
    for k in np.flatnonzero(have):
        if k == first:
            continue
        y = z[k] - H @ means_p[k]
        S = H @ covs_p[k] @ H.T + Rs[k]
        ll -= 0.5 * (float(y @ np.linalg.solve(S, y)) + math.log(np.linalg.det(S)) + 3 * math.log(2.0 * math.pi))
    if not smooth:
        return ll, means, covs
    xs, Ps, _, _ = kf.rts_smoother(means, covs)
    return ll, xs, Ps


def _smooth_group(track: pl.DataFrame, cfg: SmoothConfig, frame_times: Mapping[int, int] | None,
                  raw: pl.DataFrame | None) -> tuple[pl.DataFrame, TrackFit | None]:
    """A group track through :class:`GroupModel`: 3-D position and velocity smoothed, gaps filled."""
    head = track.row(0, named=True)
    tracker, track_id = head["tracker"], head["track_id"]
    positioned = track.filter(pl.col("X").is_not_null() & (pl.col("status") != "lost"))
    if positioned.height == 0:
        return _finish(track, tracker, track_id, frame_times).sort("frame"), None
    lo, hi = int(positioned["frame"].min()), int(positioned["frame"].max())
    frames = np.arange(lo, hi + 1, dtype=np.int64)
    full = pl.DataFrame({"frame": frames}).join(track, on="frame", how="left")
    n = len(frames)
    status = full["status"].fill_null("lost").to_numpy().astype(object)
    P3 = np.stack([full[c].to_numpy().astype(float) for c in ("X", "Y", "Z")], axis=1)
    has_pos = np.isfinite(P3).all(axis=1) & (status != "lost")
    measured = has_pos & (status == "measured")
    use_raw = raw is not None and raw.height > 0 and raw["zX"].is_not_null().any()
    if use_raw:
        r = pl.DataFrame({"frame": frames}).join(raw, on="frame", how="left")
        z = np.stack([r[c].to_numpy().astype(float) for c in ("zX", "zY", "zZ")], axis=1)
        c = {k: r[k].to_numpy().astype(float) for k in ("rXX", "rXY", "rXZ", "rYY", "rYZ", "rZZ")}
        R0 = np.stack([np.stack([c["rXX"], c["rXY"], c["rXZ"]], -1), np.stack([c["rXY"], c["rYY"], c["rYZ"]], -1),
                       np.stack([c["rXZ"], c["rYZ"], c["rZZ"]], -1)], axis=1)
        ok = measured & np.isfinite(z).all(axis=1) & np.isfinite(R0).all(axis=(1, 2))
        grid = GROUP_MODEL.scale_grid
    else:
        z = P3.copy()
        R0 = np.broadcast_to(np.eye(3), (n, 3, 3)).copy()
        ok = measured.copy()
        grid = GROUP_MODEL.sigma_grid
    z[~ok] = np.nan
    R0[~ok] = np.eye(3)
    if ok.sum() < 2:
        return _finish(full, tracker, track_id, frame_times).sort("frame"), None

    def run(q, s, smooth):
        return _run_group(z, R0 * s * s, q, smooth)

    q_grid = GROUP_MODEL.q_grid
    if q_grid is None:
        from trackreplay.trackers.groups.config import EkfConfig

        q_grid = (EkfConfig().accel_sigma ** 2,)
    best = (q_grid[0], grid[0], -math.inf)
    for q in q_grid:
        for s in grid:
            ll = run(q, s, False)[0]
            if ll > best[2]:
                best = (q, s, ll)
    q, s, ll = best
    _, xs, Ps = run(q, s, True)
    outliers = np.zeros(n, bool)
    if ok.sum() > 4:  # a wrong measurement (a splinter, a merge) beyond outlier_sigma of its own noise
        resid = z - xs[:, [0, 2, 4]]
        d2 = np.full(n, 0.0)
        for k in np.flatnonzero(ok):
            d2[k] = float(resid[k] @ np.linalg.solve(R0[k] * s * s, resid[k])) / 3.0
        bad = ok & (np.sqrt(d2) > cfg.outlier_sigma)
        if bad.any() and (ok & ~bad).sum() >= 2:
            outliers = bad
            z[bad] = np.nan
            R0[bad] = np.eye(3)
            ok = ok & ~bad
            _, xs, Ps = run(q, s, True)
    fill_gap = np.zeros(n, bool)
    for a, b in _gap_runs(~ok):
        if a > 0 and b < n and b - a <= cfg.max_gap:
            fill_gap[a:b] = True
    smoothed = ok | fill_gap
    keep = smoothed | has_pos
    filled = fill_gap & ~measured
    fill = np.full(n, None, dtype=object)
    fill[ok] = "rts"
    fill[fill_gap & measured] = "rts_outlier"
    fill[filled] = "rts_gap"
    new_status = np.where(filled, "interpolated", np.where(keep, status, "lost")).astype(object)
    t = full["t_ns"].to_numpy().astype(float)
    if frame_times:
        t = np.where(np.isfinite(t), t, [frame_times.get(int(k), np.nan) for k in frames])
    dt = np.nanmedian(np.diff(t)) * 1e-9 if np.isfinite(t).sum() >= 2 else math.nan
    per_s = 1.0 / dt if np.isfinite(dt) and dt > 0 else math.nan
    f = frames.astype(float)
    cols: dict[str, np.ndarray] = {}
    for k, name in enumerate(("X", "Y", "Z")):
        cols[name] = np.where(keep, np.where(smoothed, xs[:, 2 * k], P3[:, k]), np.nan)
        cols[f"{name}_std"] = np.where(smoothed, np.sqrt(np.maximum(Ps[:, 2 * k, 2 * k], 0.0)), np.nan)
        cols[f"V{name}"] = np.where(smoothed, xs[:, 2 * k + 1] * per_s, np.nan)
    # Image columns: the tracker's own box on its rows, linear across filled frames (the 3-D model
    # says nothing about the box).
    for name in ("x", "y", "w", "h", "vx", "vy"):
        values = np.where(has_pos, full[name].to_numpy().astype(float), np.nan)
        cols[name] = np.where(keep, _interp(f, values, filled), np.nan)
    for v, p in (("vx", "x"), ("vy", "y")):  # a filled row moves as its own (linear) positions do
        values = np.where(has_pos, full[p].to_numpy().astype(float), np.nan)
        cols[v] = np.where(filled & keep, _interp_rate(f, values, filled), cols[v])
    out = full.with_columns(
        *(pl.Series(k, v, dtype=pl.Float64, nan_to_null=True) for k, v in cols.items()),
        pl.Series("confidence", np.where(filled, np.nan, full["confidence"].to_numpy().astype(float)), dtype=pl.Float64, nan_to_null=True),
        pl.Series("status", new_status, dtype=pl.String),
        pl.Series("fill", fill.tolist(), dtype=pl.String),
    )
    fit = TrackFit(tracker, int(track_id), q, s, math.nan, ll, int(ok.sum() + outliers.sum()), int(outliers.sum()), int(filled.sum()))
    outside = track.filter((pl.col("frame") < lo) | (pl.col("frame") > hi))
    out = pl.concat([_finish(out, tracker, track_id, frame_times), _finish(outside, tracker, track_id, frame_times)])
    return out.sort("frame"), fit


def observation_rows(tracker: str, frame_index: int, intermediates, states, rig=None) -> list[dict]:
    """The raw measurements of one replay step (:data:`OBS_SCHEMA` rows; empty for trackers whose
    output is already their measurement). Flow: the centroid of the moving set and the mean flow
    (eq. 11) before its Kalman filter. Groups: per group updated this frame (and not born of a merge),
    the mean ``[u v d]`` of its points, carried to 3-D with the covariance of the EKF's σ_u, σ_v, σ_d
    (into the world frame, like the trajectory, when the rig's pose is known)."""
    if intermediates is None:
        return []
    rows: list[dict] = []
    if tracker == "flow":
        c = getattr(intermediates, "centroid", None)
        v = getattr(intermediates, "raw_velocity", None)
        if c is None or v is None or not states:
            return []
        tid = int(states[0].track_id)
        if np.isfinite(c).all() or np.isfinite(v).all():
            rows.append({"tracker": tracker, "track_id": tid, "frame": int(frame_index), "zx": float(c[0]), "zy": float(c[1]),
                         "zvx": float(v[0]), "zvy": float(v[1])})
    elif tracker == "groups":
        g = getattr(intermediates, "groups", None)
        if g is None or rig is None or not len(g.ids):
            return []
        from trackreplay.trackers.groups.config import EkfConfig

        e = EkfConfig()
        Ruvd = np.diag([e.sigma_u**2, e.sigma_v**2, e.sigma_d**2])
        uvd, labels = intermediates.points.uvd, intermediates.labels
        for k, gid in enumerate(g.ids.tolist()):
            if g.status[k] != "measured" or g.merged_from[k]:
                continue
            sel = labels == gid
            if not sel.any():
                continue
            m = uvd[sel].mean(axis=0)
            if not (np.isfinite(m).all() and m[2] > 0):
                continue
            p = rig.to_points(m[None])[0]
            Ji = np.linalg.inv(rig.jacobian(p))
            R = Ji @ Ruvd @ Ji.T
            pose = getattr(rig, "pose", None)
            if pose is not None:  # the trajectory's X Y Z are then in the world frame: so are its observations
                p, R = pose.to_world(p[None])[0], pose.rotate_cov(R)
            rows.append({"tracker": tracker, "track_id": int(gid), "frame": int(frame_index),
                         "zX": float(p[0]), "zY": float(p[1]), "zZ": float(p[2]),
                         "rXX": R[0, 0], "rXY": R[0, 1], "rXZ": R[0, 2], "rYY": R[1, 1], "rYZ": R[1, 2], "rZZ": R[2, 2]})
    return rows


def observations_table(rows: list[dict]) -> pl.DataFrame:
    full = [{k: r.get(k) for k in OBS_SCHEMA} for r in rows]
    return pl.DataFrame(full, schema=OBS_SCHEMA, orient="row", nan_to_null=False) if full else pl.DataFrame(schema=OBS_SCHEMA)


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
