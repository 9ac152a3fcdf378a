"""Rauch–Tung–Striebel smoothing of many image tracks at once, at every noise of a grid (issue 33).

:mod:`trackreplay.replay.analysis.smooth`'s image model is constant velocity per axis with a
diagonal measurement noise, so its 4-state filter is two independent 2-state ``(p, v)`` filters
(``F``, ``Q``, ``R`` and the prior are block diagonal and stay so), and the two axes of a track,
observed on the same frames with the same variances, share one covariance: it is computed once.
Every step below runs the filter for all tracks (and all grid points) as numpy elementwise
operations on ``(grid, axis, track)`` arrays, frames in a Python loop. The update by a position
and a velocity of independent noise is done as two scalar updates (the same posterior; the
log-likelihood is the joint density by the chain rule). A velocity that is not observed is not
an observation (the filterpy version gave it a variance of 10¹², which moved the results by
under 10⁻¹¹ px).

This replaces filterpy's ``KalmanFilter.batch_filter`` and ``rts_smoother``, which run one track at
one noise in Python (9.5 ms a row over the 140-point grid); no maintained library batches a
time-varying filter over tracks and parameters. Recursions: Särkkä, *Bayesian Filtering and
Smoothing* (2013), Kalman filter eqs. 4.20–4.21 and RTS smoother eq. 8.6 (docs/papers.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

LOG_2PI = math.log(2.0 * math.pi)


@dataclass(frozen=True)
class Columns:
    """Observations of a batch of ``B`` tracks on ``N`` frames (a track shorter than the batch is
    padded with unobserved frames, which change nothing before its end). Means are ``(2, B)`` per
    frame (x and y axes); variances and masks ``(1, B)``, or ``(2, B)`` for the velocity when some
    track observes vx and vy on different frames (its axes then need their own covariance)."""

    zp: np.ndarray  # (N, 2, B) observed position (px), 0 where not observed
    zv: np.ndarray  # (N, 2, B) observed velocity (px/frame), 0 where not observed
    rp: np.ndarray  # (N, 1, B) the position's variance per σ₀² (1/confidence)
    rv: np.ndarray  # (N, A, B) the velocity's variance per σ_v²
    seen: np.ndarray  # (N, 1, B) 1.0 on an observed row
    seen_v: np.ndarray  # (N, A, B) 1.0 where the velocity is observed
    counted: np.ndarray  # (N, 1, B) 1.0 where the position counts in the likelihood (observed, not the first)
    counted_v: np.ndarray  # (N, A, B) 1.0 where the velocity counts in the likelihood
    p0: np.ndarray  # (2, B) the first observed position (the prior's mean)
    r0: np.ndarray  # (1, B) its variance per σ₀² (the prior's spread)
    components: np.ndarray  # (B,) observed components counted in each track's likelihood

    @staticmethod
    def pack(zs: list[np.ndarray], rs: list[np.ndarray]) -> Columns:
        """``zs[i]`` (n_i, 4) = (x, y, vx, vy), NaN where not observed (a row without x, y is not
        observed at all); ``rs[i]`` (n_i,) the variance scale of each row (1/confidence)."""
        b, n = len(zs), max(len(z) for z in zs)
        obs = [np.isfinite(z[:, 0]) for z in zs]
        vel = [o[:, None] & np.isfinite(z[:, 2:]) for o, z in zip(obs, zs)]
        a = 1 if all(np.array_equal(v[:, 0], v[:, 1]) for v in vel) else 2
        zp, zv = np.zeros((n, 2, b)), np.zeros((n, 2, b))
        rp, seen, counted = np.zeros((n, 1, b)), np.zeros((n, 1, b)), np.zeros((n, 1, b))
        rv, seen_v, counted_v = np.zeros((n, a, b)), np.zeros((n, a, b)), np.zeros((n, a, b))
        p0, r0, comp = np.zeros((2, b)), np.zeros((1, b)), np.zeros(b)
        for i, (z, r, o, v) in enumerate(zip(zs, rs, obs, vel)):
            m, first = len(z), int(np.flatnonzero(o)[0])
            c = o.copy()
            c[first] = False
            zp[:m, :, i] = np.where(o[:, None], z[:, :2], 0.0)
            zv[:m, :, i] = np.where(v, z[:, 2:], 0.0)
            rp[:m, 0, i], seen[:m, 0, i], counted[:m, 0, i] = np.where(o, r, 0.0), o, c
            rv[:m, :, i] = np.where(v[:, :a], r[:, None], 0.0)
            seen_v[:m, :, i], counted_v[:m, :, i] = v[:, :a], v[:, :a] & c[:, None]
            p0[:, i], r0[0, i] = z[first, :2], r[first]
            comp[i] = 2 * c.sum() + (v & c[:, None]).sum()
        return Columns(zp, zv, rp, rv, seen, seen_v, counted, counted_v, p0, r0, comp)


def _prior(cols: Columns, s2: np.ndarray, axes: int) -> tuple[np.ndarray, ...]:
    """Vague, around the first observation: mean ``(p₀, 0)``, covariance ``diag(σ₀² r + 10⁴, 10²)``."""
    a = np.broadcast_to(s2 * cols.r0 + 1e4, np.broadcast_shapes(np.shape(s2), (axes, cols.r0.shape[1]))).copy()
    p = np.broadcast_to(cols.p0, (*a.shape[:-2], 2, a.shape[-1])).copy()
    return p, np.zeros(p.shape), a, np.zeros(a.shape), np.full(a.shape, 1e2)


def filter_columns(cols: Columns, q: np.ndarray, s2: np.ndarray, sv2: np.ndarray, keep: bool):
    """Forward filter of every track at noises ``q``, ``σ₀²``, ``σ_v²`` (arrays broadcast against
    ``(…, 1, B)``): per frame the prediction ``x ← F x``, ``P ← F P Fᵀ + Q`` (``F = [[1, 1], [0, 1]]``,
    ``Q = q [[1/3, 1/2], [1/2, 1]]``), then scalar updates by the position and the velocity
    (``a - a²/s`` written ``a r / s``: no cancellation). Returns ``-2 ×`` the log-likelihood without
    its ``2π`` terms (…, B) and, with ``keep``, the filtered ``(p, v, a, b, c)`` of every frame."""
    q3, q2 = q / 3.0, q * 0.5
    axes = cols.rv.shape[1]
    p, v, a, b, c = _prior(cols, s2, axes)
    quad, logs = np.zeros(p.shape), np.zeros(a.shape)
    velocity, likelihood = bool(cols.seen_v.any()), not keep
    n = cols.zp.shape[0]
    kept = tuple(np.empty((n, *x.shape)) for x in (p, v, a, a, a)) if keep else ()
    rows = zip(cols.zp, cols.rp, cols.seen, cols.counted, cols.zv, cols.rv, cols.seen_v, cols.counted_v)
    for k, (zp, rp, seen, counted, zv, rv, seen_v, counted_v) in enumerate(rows):
        p += v  # predict
        t = b + c
        a += b
        a += t
        a += q3
        b = t + q2
        c += q
        r = s2 * rp  # position update
        s = a + r
        y = zp - p
        w = seen / s
        k1, k2 = a * w, b * w
        p += k1 * y
        v += k2 * y
        c -= k2 * b
        b -= k1 * b
        a = k1 * r + a * (1.0 - seen)
        if likelihood:
            quad += y * y * (counted / s)
            logs += np.log(s) * counted
        if velocity:
            r = sv2 * rv
            s = c + r
            y = zv - v
            w = seen_v / s
            k1, k2 = b * w, c * w
            p += k1 * y
            v += k2 * y
            a -= k1 * b
            b -= k2 * b
            c = k2 * r + c * (1.0 - seen_v)
            if likelihood:
                quad += y * y * (counted_v / s)
                logs += np.log(s) * counted_v
        for out, value in zip(kept, (p, v, a, b, c)):
            out[k] = value
    return quad.sum(axis=-2) + logs.sum(axis=-2) * (2 // axes), kept


def rts_columns(filtered: tuple[np.ndarray, ...], q: np.ndarray) -> tuple[np.ndarray, ...]:
    """The RTS backward pass over filtered ``(p, v, a, b, c)`` (N, …) at process noise ``q``: the
    gains ``G = P Fᵀ (F P Fᵀ + Q)⁻¹`` of every frame at once, then the recursion. Returns the
    smoothed ``(p, v, a, b, c)``."""
    p, v, a, b, c = filtered
    bc = b + c
    A, B, C = a + b + bc + q / 3.0, bc + q * 0.5, c + q  # the next frame's prediction covariance
    det = A * C - B * B
    ab = a + b
    g11, g12 = (ab * C - b * B) / det, (b * A - ab * B) / det
    g21, g22 = (bc * C - c * B) / det, (c * A - bc * B) / det
    fp = p + v
    ps, vs, as_, bs, cs = p.copy(), v.copy(), a.copy(), b.copy(), c.copy()
    for k in range(len(p) - 2, -1, -1):
        dp, dv = ps[k + 1] - fp[k], vs[k + 1] - v[k]
        ps[k] += g11[k] * dp + g12[k] * dv
        vs[k] += g21[k] * dp + g22[k] * dv
        dA, dB, dC = as_[k + 1] - A[k], bs[k + 1] - B[k], cs[k + 1] - C[k]
        u1, u2 = g11[k] * dA + g12[k] * dB, g11[k] * dB + g12[k] * dC
        w1, w2 = g21[k] * dA + g22[k] * dB, g21[k] * dB + g22[k] * dC
        as_[k] += g11[k] * u1 + g12[k] * u2
        bs[k] += g21[k] * u1 + g22[k] * u2
        cs[k] += g21[k] * w1 + g22[k] * w2
    return ps, vs, as_, bs, cs


def grid_loglik(cols: Columns, q: np.ndarray, s2: np.ndarray, sv2: np.ndarray, lane_elements: int) -> np.ndarray:
    """Log-likelihood (G, B) of every track at every grid point ``(q, σ₀², σ_v²)`` (each (G,)),
    at most ``lane_elements`` grid points × tracks at a time (the working set)."""
    g, b = len(q), cols.zp.shape[-1]
    step = max(1, lane_elements // b)
    out = np.empty((g, b))
    for lo in range(0, g, step):
        sl = slice(lo, lo + step)
        out[sl] = filter_columns(cols, q[sl, None, None], s2[sl, None, None], sv2[sl, None, None], keep=False)[0]
    return -0.5 * (out + cols.components * LOG_2PI)


def smooth_columns(cols: Columns, q: np.ndarray, s2: np.ndarray, sv2: np.ndarray) -> tuple[np.ndarray, ...]:
    """Filter and RTS at one noise per track (each (B,)): the smoothed ``(p, v)`` (N, 2, B) and
    ``(a, b, c)`` (N, A, B)."""
    _, kept = filter_columns(cols, q[None], s2[None], sv2[None], keep=True)
    return rts_columns(kept, q[None])
