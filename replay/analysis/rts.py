"""Rauch–Tung–Striebel smoothing of many tracks at once, at every noise of a grid (issue 33).

:mod:`trackreplay.replay.analysis.smooth`'s image model is constant velocity per axis with a
diagonal measurement noise, so its 4-state filter is independent 2-state ``(p, v)`` filters, one
per axis (``F``, ``Q``, ``R`` and the prior are block diagonal and stay so); the axes of a track,
observed on the same frames with the same variances, share one covariance, computed once. A 3-D
track observed with ``R = s² I`` splits the same way (three axes). Every frame runs the filter for
all tracks and grid points as numpy elementwise operations on ``(grid, axis, track)`` arrays, the
frames in a Python loop; the update by a position and a velocity of independent noise is two
scalar updates (the same posterior; the log-likelihood is the joint density by the chain rule).
The backward pass is a parallel prefix scan of each frame's affine step (log₂ N rounds, each composed
in place a block of frames at a time: its memory is the maps themselves), over pieces of
:data:`SCAN_FRAMES` frames, the last first, each piece's maps applied to the smoothed state after it; a
long lane's filtered states wait for it in a temporary file (:func:`smooth_pieces`). The grid
search's likelihood of a long track is computed by pieces filtered side by side, each started a
little early from a guess and checked to join its predecessor (:func:`_pieces_loglik`).

filterpy's ``KalmanFilter.batch_filter`` and ``rts_smoother``, which this replaces, run one track at
one noise in Python (9.5 ms a row over flow's 140-point grid); no maintained library batches a
time-varying filter over tracks and parameters. A velocity the tracker does not give is not an
observation here (filterpy's version gave it a variance of 10¹², which moved positions by under
10⁻¹¹ px). Kalman filter: the general discrete filter of seed 004 §3.2, eqs. 12–24 (docs/papers.md);
smoother: Rauch, Tung and Striebel, AIAA Journal 3(8), 1965.
"""

from __future__ import annotations

import math
from array import array
from collections.abc import Callable, Iterator
from dataclasses import dataclass

import numpy as np

LOG_2PI = math.log(2.0 * math.pi)
# The variance of what a frame does not observe: its update then moves the state by ~10⁻⁹⁰ of itself,
# nothing at double precision, and every frame is the same arithmetic (no masks)
UNSEEN = 1e100


@dataclass(frozen=True)
class Columns:
    """Observations of a batch of ``B`` tracks on ``N`` frames (a track shorter than the batch is
    padded with unobserved frames, which change nothing before its end). Means are ``(D, B)`` per
    frame (D axes: x, y in the image, X, Y, Z in 3-D); variances and masks ``(1, B)``, or ``(D, B)``
    for the velocity when some track observes its axes' velocities on different frames (its axes
    then need their own covariance)."""

    zp: np.ndarray  # (N, D, B) observed position, 0 where not observed
    zv: np.ndarray  # (N, D, B) observed velocity (per frame), 0 where not observed
    rp: np.ndarray  # (N, 1, B) the position's variance per σ₀² (1/confidence), UNSEEN where not observed
    rv: np.ndarray  # (N, A, B) the velocity's variance per σ_v², UNSEEN where not observed
    counted: np.ndarray  # (N, 1, B) 1.0 where the position counts in the likelihood (observed, not the first)
    counted_v: np.ndarray  # (N, A, B) 1.0 where the velocity counts in the likelihood
    p0: np.ndarray  # (D, B) the first observed position (the prior's mean)
    r0: np.ndarray  # (1, B) its variance per σ₀² (the prior's spread)
    components: np.ndarray  # (B,) observed components counted in each track's likelihood
    last: np.ndarray  # (B,) each track's last frame
    velocity: bool  # some track observes a velocity

    @staticmethod
    def pack(zs: list[np.ndarray], rs: list[np.ndarray]) -> Columns:
        """``zs[i]`` (n_i, 2D) = D positions then D velocities (image: x, y, vx, vy), NaN where not
        observed (a row without its first position is not observed at all); ``rs[i]`` (n_i,) the
        variance scale of each row (1/confidence)."""
        b, n, d = len(zs), max(len(z) for z in zs), zs[0].shape[1] // 2
        obs = [np.isfinite(z[:, 0]) for z in zs]
        vel = [o[:, None] & np.isfinite(z[:, d:]) for o, z in zip(obs, zs)]
        a = 1 if all((v == v[:, :1]).all() for v in vel) else d
        zp, zv = np.zeros((n, d, b)), np.zeros((n, d, b))
        rp, counted = np.full((n, 1, b), UNSEEN), np.zeros((n, 1, b))
        rv, counted_v = np.full((n, a, b), UNSEEN), np.zeros((n, a, b))
        p0, r0, comp = np.zeros((d, b)), np.zeros((1, b)), np.zeros(b)
        for i, (z, r, o, v) in enumerate(zip(zs, rs, obs, vel)):
            m, first = len(z), int(np.flatnonzero(o)[0])
            c = o.copy()
            c[first] = False
            zp[:m, :, i] = np.where(o[:, None], z[:, :d], 0.0)
            zv[:m, :, i] = np.where(v, z[:, d:], 0.0)
            rp[:m, 0, i], counted[:m, 0, i] = np.where(o, r, UNSEEN), c
            rv[:m, :, i] = np.where(v[:, :a], r[:, None], UNSEEN)
            counted_v[:m, :, i] = v[:, :a] & c[:, None]
            p0[:, i], r0[0, i] = z[first, :d], r[first]
            comp[i] = d * c.sum() + (v & c[:, None]).sum()
        last = np.array([len(z) - 1 for z in zs])
        velocity = any(v.any() for v in vel)
        return Columns(zp, zv, rp, rv, counted, counted_v, p0, r0, comp, last, velocity)


@dataclass(frozen=True)
class Prior:
    """The prior around a track's first observation: mean ``(p₀, 0)``, covariance
    ``diag(σ₀² r₀ + position, velocity)`` per axis."""

    position: float = 1e4  # vague (image: px²)
    velocity: float = 1e2


IMAGE_PRIOR = Prior()


def axis_noise(Q, values) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(Q_pp, Q_pv, Q_vv)`` of one axis of the process noise ``Q(v)`` (a block diagonal
    constant-velocity model's, state ``(p₁, v₁, p₂, v₂, …)``) at every value ``v``."""
    blocks = np.array([np.asarray(Q(float(v)))[:2, :2] for v in values]).reshape(-1, 2, 2)
    return blocks[:, 0, 0], blocks[:, 0, 1], blocks[:, 1, 1]


def _prior(cols: Columns, s2: np.ndarray, axes: int, prior: Prior) -> tuple[np.ndarray, np.ndarray]:
    """The means ``[p, v]`` (2, …, D, B) and covariances ``[a, b, c]`` (3, …, A, B) before the first frame."""
    a = s2 * cols.r0 + prior.position
    shape = np.broadcast_shapes(np.shape(a), (axes, cols.r0.shape[1]))
    cov = np.zeros((3, *shape))
    cov[0], cov[2] = a, prior.velocity
    pv = np.zeros((2, *shape[:-2], *cols.p0.shape))
    pv[0] = cols.p0
    return pv, cov


def filter_columns(cols: Columns, Q: tuple[np.ndarray, ...], s2: np.ndarray, sv2: np.ndarray, keep: bool,
                   prior: Prior = IMAGE_PRIOR):
    """Forward filter of every track at process noise ``Q = (Q_pp, Q_pv, Q_vv)``, measurement noise
    ``σ₀²``, ``σ_v²`` (arrays broadcast against ``(…, 1, B)``): per frame the prediction ``x ← F x``,
    ``P ← F P Fᵀ + Q`` (``F = [[1, 1], [0, 1]]``), then scalar updates by the position and the velocity
    (``a - a²/s`` written ``a r / s``: no cancellation; an unobserved frame has variance
    :data:`UNSEEN`). Returns ``-2 ×`` the log-likelihood without its ``2π`` terms (…, B) (without
    ``keep``: :func:`_filter_loglik`) or, with ``keep``, ``((), filtered (p, v, a, b, c) of every frame)``."""
    if not keep:
        return _filter_loglik(cols, Q, s2, sv2, prior), ()
    return (), next(filter_chunks(cols, Q, s2, sv2, prior, cols.zp.shape[0]))[1]


def filter_chunks(cols: Columns, Q: tuple[np.ndarray, ...], s2: np.ndarray, sv2: np.ndarray, prior: Prior,
                  frames: int) -> Iterator[tuple[int, tuple[np.ndarray, ...]]]:
    """:func:`filter_columns` with ``keep``, ``frames`` frames at a time: ``(lo, (p, v, a, b, c))`` of
    frames ``lo ..``, the state carried from one piece to the next (the same operations in the same
    order: the pieces are the whole pass's rows to the bit)."""
    q3, q2, q = Q
    axes = cols.rv.shape[1]
    pv, cov = _prior(cols, s2, axes, prior)
    p, v, a, b, c = pv[0], pv[1], cov[0], cov[1], cov[2]  # views: updated in place
    n = cols.zp.shape[0]
    for lo in range(0, n, frames):
        hi = min(n, lo + frames)
        means, covs = np.empty((hi - lo, *pv.shape)), np.empty((hi - lo, *cov.shape))
        for k in range(lo, hi):
            zp, rp, zv, rv = cols.zp[k], cols.rp[k], cols.zv[k], cols.rv[k]
            p += v  # predict
            t = b + c
            a += b
            a += t
            a += q3
            np.add(t, q2, out=b)
            c += q
            r = s2 * rp  # position update: gains K = (a, b) / s
            s = a + r
            w = np.reciprocal(s)
            K = cov[:2] * w
            y = zp - p
            pv += K * y
            c -= K[1] * b
            b -= K[0] * b
            np.multiply(K[0], r, out=a)
            if cols.velocity:
                r = sv2 * rv  # velocity update: K = (b, c) / s
                s = c + r
                w = np.reciprocal(s)
                K = cov[1:] * w
                y = zv - v
                pv += K * y
                a -= K[0] * b
                b -= K[1] * b
                np.multiply(K[1], r, out=c)
            means[k - lo], covs[k - lo] = pv, cov
        yield lo, (means[:, 0], means[:, 1], covs[:, 0], covs[:, 1], covs[:, 2])


BLOCK = 256  # frames whose likelihood terms are summed at once (at most)
BLOCK_ELEMENTS = 1 << 16  # ... and at most this many values of a state column (grid points × axes × tracks) a buffer


def _filter_loglik(cols: Columns, Q: tuple[np.ndarray, ...], s2: np.ndarray, sv2: np.ndarray, prior: Prior,
                   start: tuple[np.ndarray, np.ndarray] | None = None, own: np.ndarray | None = None,
                   snaps: tuple[int, ...] = (), sums: bool = False, columns: np.ndarray | None = None):
    """:func:`filter_columns` without ``keep``: ``-2 ×`` the log-likelihood (without its ``2π`` terms).
    The same operations in the same order, with fewer numpy calls a frame (the cost of a long track,
    whose arrays are small): each frame's innovations and variances go to a buffer, and every
    :data:`BLOCK` frames (fewer in a wide lane: :data:`BLOCK_ELEMENTS`) their terms ``y² / s`` and ``log s`` are computed at once and added to the
    sums in frame order (a sum along the first axis adds row after row: the sums are those of adding
    them frame by frame); the measurement variances of a block are scaled at once.

    For :func:`_pieces_loglik`: ``start`` the means and covariances before the first frame instead of
    the prior; ``own`` (N, 1, B) 1.0 on the frames whose position term counts (0.0 elsewhere; the
    velocity's and the ``log s`` terms follow ``counted``); ``snaps`` the frames after which the
    state is copied; with ``sums``, returns ``(quad, logs, {frame: (means, covariances)})``; ``columns``
    the tracks of ``cols`` (and ``own``) filtered, gathered a block of frames at a time (not copied whole)."""
    q3, q2, q = Q
    axes = cols.rv.shape[1]
    pv, cov = _prior(cols, s2, axes, prior) if start is None else (start[0].copy(), start[1].copy())
    kept: dict[int, tuple[np.ndarray, np.ndarray]] = {}
    p, v, a, b, c = pv[0], pv[1], cov[0], cov[1], cov[2]  # views: updated in place
    gains, gains_v, cb = cov[:2], cov[1:], cov[2:0:-1]  # (a, b), (b, c), (c, b)
    bc_noise = np.stack(np.broadcast_arrays(q2, q))  # (Q_pv, Q_vv), added to (b, c) at once
    quad, logs = np.zeros(p.shape), np.zeros(a.shape)
    step = 2 if cols.velocity else 1  # terms per frame: the position's, then the velocity's
    block = max(1, min(BLOCK, BLOCK_ELEMENTS // p.size))  # a wide lane already amortises numpy's calls
    Y, W, S = np.empty((step * block, *p.shape)), np.empty((step * block, *a.shape)), np.empty((step * block, *a.shape))
    K, Kb = np.empty(cov[:2].shape), np.empty(cov[:2].shape)
    K_rev = K[::-1]
    Ky = np.empty(np.broadcast_shapes(K.shape, (1, *p.shape)))
    lead = (slice(None), *([None] * (a.ndim - 2)))  # the grid's axes, before the frames' (A, B)
    n = cols.zp.shape[0]

    def rows(x: np.ndarray, lo: int, hi: int) -> np.ndarray:
        return x[lo:hi] if columns is None else x[lo:hi][..., columns]

    for lo in range(0, n, block):
        hi = min(n, lo + block)
        rp = s2 * rows(cols.rp, lo, hi)[lead]
        rv = sv2 * rows(cols.rv, lo, hi)[lead] if cols.velocity else None
        zp, zv = rows(cols.zp, lo, hi), rows(cols.zv, lo, hi) if cols.velocity else None
        for j in range(hi - lo):
            p += v  # predict: a += b; t = b + c; a += t; a += q3; (b, c) = (t + q2, c + q)
            a += b
            np.add(b, c, out=b)
            a += b
            a += q3
            gains_v += bc_noise
            r = rp[j]  # position update: gains K = (a, b) / s
            w = np.reciprocal(np.add(a, r, out=S[step * j]), out=W[step * j])
            np.multiply(gains, w, out=K)
            y = np.subtract(zp[j], p, out=Y[step * j])
            pv += np.multiply(K, y, out=Ky)
            cb -= np.multiply(K_rev, b, out=Kb)  # c -= K₁ b, b -= K₀ b (the old b in both)
            np.multiply(K[0], r, out=a)
            if rv is not None:
                r = rv[j]  # velocity update: K = (b, c) / s
                w = np.reciprocal(np.add(c, r, out=S[step * j + 1]), out=W[step * j + 1])
                np.multiply(gains_v, w, out=K)
                y = np.subtract(zv[j], v, out=Y[step * j + 1])
                pv += np.multiply(K, y, out=Ky)
                gains -= np.multiply(K, b, out=Kb)  # a -= K₀ b, b -= K₁ b
                np.multiply(K[1], r, out=c)
            if lo + j in snaps:
                kept[lo + j] = (pv.copy(), cov.copy())
        m = step * (hi - lo)
        counted = np.empty((m, *cols.counted_v.shape[1:-1], Y.shape[-1]))
        counted[::step] = rows(cols.counted, lo, hi)
        if cols.velocity:
            counted[1::step] = rows(cols.counted_v, lo, hi)
            W[1:m:2] = counted[1::2][lead] * W[1:m:2]  # a velocity's term counts only where observed
        if own is not None:
            W[0:m:step] = rows(own, lo, hi)[lead] * W[0:m:step]
        quad = np.concatenate([quad[None], Y[:m] * Y[:m] * W[:m]]).sum(axis=0)  # 0 on the first observation
        logs = np.concatenate([logs[None], np.log(S[:m]) * counted[lead]]).sum(axis=0)
    if sums:
        return quad, logs, kept
    return quad.sum(axis=-2) + logs.sum(axis=-2) * (cols.zp.shape[1] // axes)


def _compose(first: tuple[np.ndarray, ...], then: tuple[np.ndarray, ...]) -> tuple[np.ndarray, ...]:
    """``first ∘ then`` of two backward maps ``(G, u, U)``: ``x ↦ G x + u``, ``P ↦ G P Gᵀ + U``;
    ``G = (g11, g12, g21, g22)``, ``u = (u_p, u_v)``, ``U = (U_a, U_b, U_c)``."""
    g11, g12, g21, g22, up, uv, ua, ub, uc = first
    h11, h12, h21, h22, wp, wv, wa, wb, wc = then
    m11, m12 = g11 * wa + g12 * wb, g11 * wb + g12 * wc  # G₁ U₂
    m21, m22 = g21 * wa + g22 * wb, g21 * wb + g22 * wc
    return (g11 * h11 + g12 * h21, g11 * h12 + g12 * h22, g21 * h11 + g22 * h21, g21 * h12 + g22 * h22,
            g11 * wp + g12 * wv + up, g21 * wp + g22 * wv + uv,
            m11 * g11 + m12 * g12 + ua, m11 * g21 + m12 * g22 + ub, m21 * g21 + m22 * g22 + uc)


SCAN_ELEMENTS = 1 << 15  # values of one state column a block of :func:`rts_columns` computes at once


def _step_maps(p, v, a, b, c, Q, lo: int, last: np.ndarray) -> list[np.ndarray]:
    """Each frame's backward map ``(G, u, U)`` for the frames from ``lo`` (see :func:`rts_columns`)."""
    bc = b + c
    A, B, C = a + b + bc + Q[0], bc + Q[1], c + Q[2]  # the next frame's prediction covariance P⁻
    det = A * C - B * B
    ab = a + b
    g = [(ab * C - b * B) / det, (b * A - ab * B) / det, (bc * C - c * B) / det, (c * A - bc * B) / det]
    fp = p + v
    u = [p - g[0] * fp - g[1] * v, v - g[2] * fp - g[3] * v]  # x_k - G F x_k
    m11, m12 = g[0] * A + g[1] * B, g[0] * B + g[1] * C  # G P⁻
    m21, m22 = g[2] * A + g[3] * B, g[2] * B + g[3] * C
    U = [a - m11 * g[0] - m12 * g[1], b - m11 * g[2] - m12 * g[3], c - m21 * g[2] - m22 * g[3]]
    end = ((lo + np.arange(len(p)))[:, None] >= last)[:, None, :]  # a track's last frame and the padding after it
    return [np.where(end, 0.0, x) for x in g] + [np.where(end, x, y) for x, y in zip((p, v, a, b, c), (*u, *U))]


SCAN_FRAMES = 8192  # frames of one backward scan: a longer lane's pass is these pieces, the last first


def _backward_piece(filtered: tuple[np.ndarray, ...], Q: tuple[np.ndarray, ...], lo: int, last: np.ndarray,
                    after: tuple[np.ndarray, ...] | None) -> tuple[np.ndarray, ...]:
    """The smoothed ``(p, v, a, b, c)`` of frames ``lo ..`` from their filtered states: each frame's
    backward map (:func:`_step_maps`) composed by a prefix scan to the piece's end, then applied to
    ``after``, the smoothed state of the frame after the piece (None: the piece ends the lane)."""
    p, a = filtered[0], filtered[2]
    n = len(p)
    rows = max(1, SCAN_ELEMENTS // max(p[0].size, a[0].size))
    maps = [np.empty(a.shape) for _ in range(4)] + [np.empty(x.shape) for x in filtered]
    for k in range(0, n, rows):  # the maps a block of frames at a time (the temporaries stay small)
        for x, y in zip(maps, _step_maps(*(x[k:k + rows] for x in filtered), Q, lo + k, last)):
            x[k:k + rows] = y
    d = 1
    while d < n:  # each map becomes itself ∘ the one d frames later (all from the previous round's maps)
        for k in range(0, n - d, rows):  # in place by blocks: a block reads only frames not yet written
            hi = min(n - d, k + rows)
            head = _compose(tuple(x[k:hi] for x in maps), tuple(x[k + d:hi + d] for x in maps))
            for x, y in zip(maps, head):
                x[k:hi] = y
        d *= 2
    if after is not None:  # x ↦ G x + u, P ↦ G P Gᵀ + U at the next piece's first smoothed state
        state = (0.0, 0.0, 0.0, 0.0, *after)
        for k in range(0, n, rows):
            for x, y in zip(maps[4:], _compose(tuple(x[k:k + rows] for x in maps), state)[4:]):
                x[k:k + rows] = y
    return tuple(maps[4:])


def rts_columns(filtered: tuple[np.ndarray, ...], Q: tuple[np.ndarray, ...], last: np.ndarray) -> tuple[np.ndarray, ...]:
    """The RTS pass over filtered ``(p, v, a, b, c)`` (N, …, B) at process noise ``Q``, each track
    ending at frame ``last`` (B,). Each frame's step back, ``x ↦ x_k + G (x - F x_k)`` and
    ``P ↦ P_k + G (P - P⁻_{k+1}) Gᵀ`` with ``G = P_k Fᵀ (P⁻_{k+1})⁻¹``, is an affine map; the maps are
    composed by a parallel prefix scan (log₂ N vectorised rounds instead of N Python steps), the
    last frame's map the constant filtered state. A lane longer than :data:`SCAN_FRAMES` is scanned a
    piece of that many frames at a time, the last first, each piece's maps applied to the smoothed
    state after it (:func:`_backward_piece`: the same pieces, and so the same numbers, as
    :func:`smooth_pieces`). Returns the smoothed ``(p, v, a, b, c)``."""
    n = len(filtered[0])
    out = tuple(np.empty(x.shape) for x in filtered)
    after = None
    for lo in reversed(range(0, n, SCAN_FRAMES)):
        piece = _backward_piece(tuple(x[lo:lo + SCAN_FRAMES] for x in filtered), Q, lo, last, after)
        for x, y in zip(out, piece):
            x[lo:lo + SCAN_FRAMES] = y
        after = tuple(x[:1] for x in piece)
    return out


SPILL_FRAMES = 2 * SCAN_FRAMES  # a lane at least this long keeps its filtered states in a temporary file


class _Spill:
    """Pieces of arrays (each piece the same shapes but its frames) written one after another to an
    unnamed temporary file and read back in any order: the filtered states of a long lane, between
    the forward pass and the backward one, in the page cache rather than the process's memory."""

    def __init__(self) -> None:
        import tempfile

        self._file = tempfile.TemporaryFile()  # noqa: SIM115 (kept open across calls; removed when closed or at exit)
        self._where: dict[int, tuple[int, list[tuple[int, ...]]]] = {}

    def put(self, key: int, arrays: tuple[np.ndarray, ...]) -> None:
        self._file.seek(0, 2)
        self._where[key] = (self._file.tell(), [x.shape for x in arrays])
        for x in arrays:
            self._file.write(np.ascontiguousarray(x, dtype=np.float64).data)

    def get(self, key: int) -> tuple[np.ndarray, ...]:
        at, shapes = self._where.pop(key)
        self._file.seek(at)
        return tuple(np.fromfile(self._file, dtype=np.float64, count=math.prod(s)).reshape(s) for s in shapes)

    def close(self) -> None:
        self._file.close()


def smooth_pieces(cols: Columns, Q: tuple[np.ndarray, ...], s2: np.ndarray, sv2: np.ndarray,
                  prior: Prior = IMAGE_PRIOR, spill: bool | None = None) -> Iterator[tuple[int, tuple[np.ndarray, ...]]]:
    """:func:`smooth_columns` a piece of :data:`SCAN_FRAMES` frames at a time, the last piece first:
    ``(lo, (p, v, a, b, c))`` of frames ``lo ..`` (each piece's arrays its own). The forward pass keeps
    each piece's filtered states, in memory or (``spill``; None: a lane of :data:`SPILL_FRAMES` frames or
    more) in a temporary file, and the backward pass reads them back the last first (issue 33: a long
    track's pass then holds a piece's states, not the track's). The numbers are :func:`smooth_columns`'
    to the bit: the same filter (its state carried across pieces) and the same backward pieces."""
    n = cols.zp.shape[0]
    noise = tuple(x[None] for x in Q)
    one = cols.zp.shape[-1] == 1 and cols.rv.shape[1] == 1
    if one:
        forward = filter_one_chunks(cols, tuple(float(x[0]) for x in Q), float(s2[0]), float(sv2[0]), prior, SCAN_FRAMES)
    else:
        forward = filter_chunks(cols, noise, s2[None], sv2[None], prior, SCAN_FRAMES)
    store = _Spill() if (n >= SPILL_FRAMES if spill is None else spill) else None
    kept: dict[int, tuple[np.ndarray, ...]] = {}
    try:
        for lo, filtered in forward:
            if store is None:
                kept[lo] = filtered
            else:
                store.put(lo, filtered)
        last = cols.last
        del cols, forward  # (the backward pass needs only the filtered states: a caller's temporary columns go)
        after = None
        for lo in reversed(range(0, n, SCAN_FRAMES)):
            filtered = kept.pop(lo) if store is None else store.get(lo)
            piece = _backward_piece(filtered, noise, lo, last, after)
            del filtered
            after = tuple(x[:1].copy() for x in piece)
            yield lo, piece
    finally:
        if store is not None:
            store.close()


def grid_loglik(cols: Columns | Callable[[], Columns], Q: tuple[np.ndarray, ...], s2: np.ndarray, sv2: np.ndarray,
                lane_elements: int, prior: Prior = IMAGE_PRIOR) -> np.ndarray:
    """Log-likelihood (G, B) of every track at every grid point ``(Q, σ₀², σ_v²)`` (each (G,)),
    at most ``lane_elements`` grid points × tracks at a time (the working set). ``cols`` may be a
    function that packs them: a long lane's columns are then not kept while its pieces (their copy
    cut by :func:`_window`, made once) are filtered, and are packed again only for the fall-back."""
    pack = cols if callable(cols) else (lambda: cols)
    lane: Columns | None = pack()
    g, b, n = len(s2), lane.zp.shape[-1], lane.zp.shape[0]
    components = lane.components
    pieces = n >= PIECES_FROM
    window = _window(lane, PIECE, WARM) if pieces else None
    if pieces and callable(cols):
        lane = None  # (issue 33: the window holds the lane's observations)
    step = max(1, lane_elements // b // (1 if not pieces else max(1, n // PIECE // 2)))
    out = np.empty((g, b))
    for lo in range(0, g, step):
        sl = slice(lo, lo + step)
        noise = tuple(x[sl, None, None] for x in Q)
        got = _pieces_loglik(lane, noise, s2[sl, None, None], sv2[sl, None, None], prior, window=window) if pieces else None
        if got is None:
            lane = pack() if lane is None else lane
            got = filter_columns(lane, noise, s2[sl, None, None], sv2[sl, None, None], False, prior)[0]
        out[sl] = got
    return -0.5 * (out + components * LOG_2PI)


def smooth_columns(cols: Columns, Q: tuple[np.ndarray, ...], s2: np.ndarray, sv2: np.ndarray,
                   prior: Prior = IMAGE_PRIOR) -> tuple[np.ndarray, ...]:
    """Filter and RTS at one noise per track (each (B,)): the smoothed ``(p, v)`` (N, D, B) and
    ``(a, b, c)`` (N, A, B). One track alone (a long one) is filtered in scalar floats
    (:func:`filter_one`): the same arithmetic without numpy's cost per call on 1-element arrays.
    The pieces of :func:`smooth_pieces` put together (kept in memory)."""
    out: tuple[np.ndarray, ...] = ()
    for lo, piece in smooth_pieces(cols, Q, s2, sv2, prior, spill=False):
        if not out:
            n = cols.zp.shape[0]
            out = tuple(np.empty((n, *x.shape[1:])) for x in piece)
        for x, y in zip(out, piece):
            x[lo:lo + len(y)] = y
    return out


def filter_one(cols: Columns, Q: tuple[float, float, float], s2: float, sv2: float,
               prior: Prior = IMAGE_PRIOR) -> tuple[np.ndarray, ...]:
    """:func:`filter_columns` with ``keep`` for a single track whose axes share one covariance
    (``B = A = 1``), in Python floats: every operation is the one :func:`filter_columns` does, in
    the same order (IEEE double either way), so the results are the same to the bit
    (``tests/replay/analysis/test_rts.py``). Returns the filtered ``(p, v, a, b, c)``."""
    return next(filter_one_chunks(cols, Q, s2, sv2, prior, cols.zp.shape[0]))[1]


def filter_one_chunks(cols: Columns, Q: tuple[float, float, float], s2: float, sv2: float, prior: Prior,
                      frames: int) -> Iterator[tuple[int, tuple[np.ndarray, ...]]]:
    """:func:`filter_one` ``frames`` frames at a time: ``(lo, (p, v, a, b, c))`` of frames ``lo ..``
    (the state carried across pieces: the same numbers)."""
    q3, q2, q = Q
    n, d = cols.zp.shape[0], cols.zp.shape[1]
    p, v = cols.p0[:, 0].tolist(), [0.0] * d
    a, b, c = s2 * float(cols.r0[0, 0]) + prior.position, 0.0, prior.velocity
    axes = range(d)
    for lo in range(0, n, frames):
        means, covs = array("d"), array("d")  # 8 bytes a value, as numpy's
        hi = min(n, lo + frames)
        for at in range(lo, hi, 4096):  # the observations as floats a block at a time
            end = min(hi, at + 4096)
            zp, zv = cols.zp[at:end, :, 0].tolist(), cols.zv[at:end, :, 0].tolist()
            rp, rv = cols.rp[at:end, 0, 0].tolist(), cols.rv[at:end, 0, 0].tolist()
            for k in range(len(zp)):
                for i in axes:  # predict
                    p[i] += v[i]
                t = b + c
                a = a + b + t + q3
                b = t + q2
                c += q
                r = s2 * rp[k]  # position update
                w = 1.0 / (a + r)
                k0, k1 = a * w, b * w
                z = zp[k]
                for i in axes:
                    y = z[i] - p[i]
                    p[i] += k0 * y
                    v[i] += k1 * y
                c -= k1 * b
                b -= k0 * b
                a = k0 * r
                if cols.velocity:
                    r = sv2 * rv[k]  # velocity update
                    w = 1.0 / (c + r)
                    k0, k1 = b * w, c * w
                    z = zv[k]
                    for i in axes:
                        y = z[i] - v[i]
                        p[i] += k0 * y
                        v[i] += k1 * y
                    a -= k0 * b
                    b -= k1 * b
                    c = k1 * r
                means.extend(p)
                means.extend(v)
                covs.extend((a, b, c))
        m = np.frombuffer(means, dtype=np.float64).reshape(hi - lo, 2, d, 1)
        C = np.frombuffer(covs, dtype=np.float64).reshape(hi - lo, 3, 1, 1)
        yield lo, (m[:, 0], m[:, 1], C[:, 0], C[:, 1], C[:, 2])


PIECE = 2048  # frames a piece of a long track owns in :func:`_pieces_loglik`
WARM = 256  # frames a piece is filtered before its own, from a guess, to reach the filter's state
TOL = 1e-9  # the largest mismatch at a seam, in standard deviations
PIECES_FROM = 2 * PIECE + WARM  # frames from which a lane's likelihood is computed by pieces
ROUNDS = 8  # restarts of the pieces whose seam does not match, before the sequential filter


def _window(cols: Columns, piece: int, warm: int) -> tuple[Columns, np.ndarray, int]:
    """``cols`` cut in pieces: piece 0 owns frames ``[0, piece + warm)``, piece ``j ≥ 1`` owns
    ``[j piece + warm, (j + 1) piece + warm)`` and is filtered from frame ``j piece`` (its first
    ``warm`` frames count nothing). Returns the pieces as tracks (column ``b P + j``: track ``b``'s
    piece ``j``; past the track's end unobserved), their ``own`` weights (span, 1, B P) and ``P``."""
    n, b = cols.zp.shape[0], cols.zp.shape[-1]
    span = piece + warm
    count = 1 + -(-max(0, n - span) // piece)
    idx = np.arange(span)[:, None] + piece * np.arange(count)[None, :]  # (span, P) global frame
    valid = idx < n
    idx = np.minimum(idx, n - 1)
    warmup = (np.arange(span)[:, None] < warm) & (np.arange(count)[None, :] > 0)

    def cut(x: np.ndarray, fill: float, mask: np.ndarray | None = None) -> np.ndarray:
        w = np.moveaxis(x[idx], 1, -1)  # (span, c, B, P)
        keep = valid if mask is None else valid & ~mask
        w = np.where(keep[:, None, None, :], w, fill)
        return np.ascontiguousarray(w.reshape(span, x.shape[1], b * count))

    zp, zv, rp, rv = cut(cols.zp, 0.0), cut(cols.zv, 0.0), cut(cols.rp, UNSEEN), cut(cols.rv, UNSEEN)
    counted, counted_v = cut(cols.counted, 0.0, warmup), cut(cols.counted_v, 0.0, warmup)
    own = np.broadcast_to((valid & ~warmup)[:, None, None, :], (span, 1, b, count)).reshape(span, 1, b * count) * 1.0
    # the guess a piece starts from: the prior around its window's first observed position
    seen = rp[:, 0, :] < UNSEEN
    first = np.where(seen.any(axis=0), seen.argmax(axis=0), 0)
    cols_idx = np.arange(b * count)
    p0 = np.where(seen.any(axis=0), zp[first, :, cols_idx].T, 0.0)
    r0 = np.where(seen.any(axis=0), rp[first, 0, cols_idx], 1.0)[None]
    p0[:, ::count], r0[:, ::count] = cols.p0, cols.r0  # piece 0: the track's own prior
    last = np.full(b * count, span - 1)
    return Columns(zp, zv, rp, rv, counted, counted_v, p0, r0, np.zeros(b * count), last, cols.velocity), own, count


def _seams(kept: dict, piece: int, warm: int, count: int, tol: float) -> np.ndarray:
    """(G, B P): the pieces (and grid points) whose state at the end of their warm-up differs from
    their predecessor's at the same frame (its last) by more than ``tol`` standard deviations
    (means by their std, covariances by the product of their stds); never a track's first piece."""
    (pa, ca), (pe, ce) = kept[warm - 1], kept[piece + warm - 1]
    sa, sc = np.sqrt(ce[0][..., :-1]), np.sqrt(ce[2][..., :-1])  # (G, A, BP - 1)
    worst = np.maximum(np.abs(pa[0][..., 1:] - pe[0][..., :-1]) / sa, np.abs(pa[1][..., 1:] - pe[1][..., :-1]) / sc)
    worst = worst.max(axis=-2)
    for k, scale in enumerate((sa * sa, sa * sc, sc * sc)):
        worst = np.maximum(worst, (np.abs(ca[k][..., 1:] - ce[k][..., :-1]) / scale).max(axis=-2))
    bad = np.zeros((worst.shape[0], worst.shape[-1] + 1), bool)
    bad[:, 1:] = ~(worst <= tol)  # NaN: not matched
    bad[:, ::count] = False  # a track's first piece starts from its prior
    return bad


def _take(x: np.ndarray, g: np.ndarray, c: np.ndarray) -> np.ndarray:
    """``x`` (k, G, X, C) at the pairs (grid point ``g``, column ``c``): (k, 1, X, K)."""
    return np.moveaxis(x[:, g, :, c], 0, -1)[:, None]


def _put(x: np.ndarray, g: np.ndarray, c: np.ndarray, y: np.ndarray) -> None:
    """Inverse of :func:`_take`."""
    x[:, g, :, c] = np.moveaxis(y[:, 0], -1, 0)


def _pieces_loglik(cols: Columns | None, Q: tuple[np.ndarray, ...], s2: np.ndarray, sv2: np.ndarray, prior: Prior,
                   piece: int | None = None, warm: int | None = None, tol: float | None = None,
                   stats: list | None = None, window: tuple | None = None) -> np.ndarray | None:
    """:func:`_filter_loglik` of a long lane cut in pieces filtered side by side (issue 33): one
    Python step a frame costs ~24 numpy calls whatever the arrays' size, so a long track's 140 grid
    points paid that on every frame; its pieces, as columns, pay it once per piece length.

    Each piece (:func:`_window`) is filtered from ``warm`` frames before its own, starting from a
    guess (the prior around that window's first observation). The filter forgets its start (the
    Kalman filter of an observable constant-velocity model is exponentially stable), so at the end
    of the warm-up the piece holds the state its predecessor reached on that frame: this is
    checked, per grid point, to ``tol`` standard deviations (:func:`_seams`). A piece that does
    not match (a slow filter: small ``q``, large ``σ``) is filtered again from its predecessor's
    state on the frame before its window, as many rounds as needed (each round carries a correct
    state at least one piece further; at most :data:`ROUNDS`, else None: the caller filters frame
    by frame). Each frame's terms are those of the sequential filter to within the seams'
    tolerance; a piece's terms are summed in frame order, and the pieces' sums in order, so the
    likelihood differs from the sequential sum by rounding only (relative ~1e-14; the tests allow
    1e-12). ``piece``, ``warm``, ``tol``: :data:`PIECE`, :data:`WARM`, :data:`TOL` by default;
    ``stats`` (a list) receives the number of unmatched seams of each round; ``window``: ``_window(cols,
    piece, warm)`` already cut (``cols`` is then not read)."""
    piece, warm, tol = piece or PIECE, warm or WARM, TOL if tol is None else tol
    win, own, count = window or _window(cols, piece, warm)
    snaps = {warm - 1, piece - 1, piece + warm - 1}
    quad, logs, kept = _filter_loglik(win, Q, s2, sv2, prior, own=own, snaps=snaps, sums=True)
    noise = [np.broadcast_to(np.reshape(x, -1), quad.shape[:1]) for x in (*Q, s2, sv2)]  # (G,) each
    for _ in range(ROUNDS + 1):
        bad = _seams(kept, piece, warm, count, tol)
        if stats is not None:
            stats.append(int(bad.sum()))
        if not bad.any():
            break
        g, c = np.nonzero(bad)
        q3, q2, q, a2, b2 = (x[g][None, None] for x in noise)
        start = tuple(_take(x, g, c - 1) for x in kept[piece - 1])
        q_, l_, k_ = _filter_loglik(win, (q3, q2, q), a2, b2, prior, start=start, own=own, snaps=snaps, sums=True,
                                    columns=c)  # gathered as filtered: a copy per pair was ~3 KB a row
        quad[g, :, c], logs[g, :, c] = q_[0].T, l_[0].T
        for f in snaps:
            for x, y in zip(kept[f], k_[f]):
                _put(x, g, c, y)
    else:
        return None
    b = win.zp.shape[-1] // count
    quad, logs = quad.reshape(*quad.shape[:-1], b, count), logs.reshape(*logs.shape[:-1], b, count)
    tq, tl = quad[..., 0], logs[..., 0]
    for j in range(1, count):
        tq, tl = tq + quad[..., j], tl + logs[..., j]
    return tq.sum(axis=-2) + tl.sum(axis=-2) * (win.zp.shape[1] // win.rv.shape[1])
