"""The batched RTS kernels' shortcuts give the same numbers to the bit as their plain forms (issue 33):
a single track filtered in Python floats (``filter_one``) and the likelihood's terms summed a block of
frames at a time (``BLOCK``)."""

from __future__ import annotations

import numpy as np
import pytest

from trackreplay.replay.analysis import rts
from trackreplay.trackers.smoothing import DEFAULT_SMOOTHING


def _track(n: int, velocity: bool, axes: int = 2, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """A noisy constant-velocity track with unobserved frames (and velocities on some frames)."""
    rng = np.random.default_rng(seed)
    k = np.arange(n, dtype=float)[:, None]
    z = np.concatenate([10 + 0.7 * k + rng.normal(0, 1.0, (n, axes)), np.full((n, axes), np.nan)], axis=1)
    if velocity:
        z[:, axes:] = 0.7 + rng.normal(0, 0.2, (n, axes))
    z[rng.random(n) < 0.2] = np.nan
    z[0, :axes] = [10.0] * axes
    return z, 1.0 / rng.uniform(0.2, 1.0, n)


@pytest.mark.parametrize("velocity", [False, True])
@pytest.mark.parametrize("axes", [2, 3])
def test_one_track_in_floats_is_the_batched_filter(velocity: bool, axes: int) -> None:
    z, r = _track(700, velocity, axes)
    cols = rts.Columns.pack([z], [r])
    Q = rts.axis_noise(DEFAULT_SMOOTHING.Q, np.array([0.1]))
    s2, sv2 = np.array([4.0]), np.array([0.25])
    noise = tuple(x[None] for x in Q)
    _, batched = rts.filter_columns(cols, noise, s2[None], sv2[None], True)
    floats = rts.filter_one(cols, tuple(float(x[0]) for x in Q), 4.0, 0.25)
    for a, b in zip(batched, floats):
        assert a.shape == b.shape and np.array_equal(a, b)


@pytest.mark.parametrize("velocity", [False, True])
def test_likelihood_summed_by_blocks_is_summed_frame_by_frame(velocity: bool, monkeypatch) -> None:
    tracks = [_track(n, velocity, seed=n) for n in (300, 611, 257)]
    cols = rts.Columns.pack([z for z, _ in tracks], [r for _, r in tracks])
    q = np.array([1e-3, 0.1, 10.0, 1e-3, 0.1, 10.0])
    s, sv = np.array([0.3, 0.3, 1.0, 1.0, 3.0, 3.0]), np.array([0.1, 1.0, 0.1, 1.0, 0.1, 1.0])
    Q = rts.axis_noise(DEFAULT_SMOOTHING.Q, q)
    blocked = rts.grid_loglik(cols, Q, s * s, sv * sv, 1 << 14)
    monkeypatch.setattr(rts, "BLOCK", 1)  # one frame's terms at a time: the plain running sums
    plain = rts.grid_loglik(cols, Q, s * s, sv * sv, 1 << 14)
    assert np.isfinite(blocked).all() and np.array_equal(blocked, plain)


def _grid(velocity: bool):
    q = np.repeat([1e-4, 1e-2, 1.0], 4)
    s = np.tile([0.3, 3.0], 6)
    sv = np.tile(np.repeat([0.1, 3.0], 2), 3) if velocity else np.full(12, 0.1)
    return rts.axis_noise(DEFAULT_SMOOTHING.Q, q), s * s, sv * sv


@pytest.mark.parametrize("velocity", [False, True])
def test_likelihood_by_pieces_is_the_sequential_one(velocity: bool, monkeypatch) -> None:
    """Issue 33: a long lane's likelihood computed by pieces filtered side by side (each started early
    from a guess, restarted where it does not join its predecessor) is the frame-by-frame one up to
    the order of the sums, at every grid point, slow filters (q = 1e-4, σ = 3) included."""
    tracks = [_track(n, velocity, seed=n) for n in (1500, 1211)]
    cols = rts.Columns.pack([z for z, _ in tracks], [r for _, r in tracks])
    Q, s2, sv2 = _grid(velocity)
    monkeypatch.setattr(rts, "PIECES_FROM", 10**9)
    plain = rts.grid_loglik(cols, Q, s2, sv2, 1 << 14)
    for piece, warm in ((256, 16), (128, 64)):
        stats: list = []
        noise = tuple(x[:, None, None] for x in Q)
        got = rts._pieces_loglik(cols, noise, s2[:, None, None], sv2[:, None, None], rts.IMAGE_PRIOR, piece, warm,
                                 stats=stats)
        assert got is not None and stats[0] > 0 and stats[-1] == 0  # some seams needed a restart, all joined
        pieces = -0.5 * (got + cols.components * rts.LOG_2PI)
        assert np.abs(pieces - plain).max() <= 1e-12 * np.abs(plain).max()
        assert np.array_equal(pieces.argmax(axis=0), plain.argmax(axis=0))


def test_pieces_that_never_join_fall_back_to_the_sequential_filter(monkeypatch) -> None:
    z, r = _track(1200, True)
    cols = rts.Columns.pack([z], [r])
    Q, s2, sv2 = _grid(True)
    monkeypatch.setattr(rts, "PIECES_FROM", 10**9)
    plain = rts.grid_loglik(cols, Q, s2, sv2, 1 << 14)
    monkeypatch.setattr(rts, "PIECES_FROM", 300)
    monkeypatch.setattr(rts, "PIECE", 128)
    monkeypatch.setattr(rts, "ROUNDS", 0)  # no restart: a seam that does not join sends the lane back
    noise = tuple(x[:, None, None] for x in Q)
    assert rts._pieces_loglik(cols, noise, s2[:, None, None], sv2[:, None, None], rts.IMAGE_PRIOR, 128, 4) is None
    monkeypatch.setattr(rts, "WARM", 4)
    assert np.array_equal(rts.grid_loglik(cols, Q, s2, sv2, 1 << 14), plain)


@pytest.mark.parametrize("tracker", ["flow", "groups"])
def test_long_tracks_smooth_to_the_same_table_by_pieces(tracker: str, monkeypatch, benchmark_module) -> None:
    """The smoothed table of long tracks is the same to the bit whether the grid search filters them
    frame by frame or by pieces (the same noise is chosen); the fits' likelihoods agree to 1e-12."""
    from trackreplay.replay.analysis.smooth import smooth_trajectory

    table = benchmark_module("bench_smooth").synthetic_trajectory(5000, tracker, tracks=2, seed=3)
    monkeypatch.setattr(rts, "PIECE", 512)
    monkeypatch.setattr(rts, "WARM", 64)
    monkeypatch.setattr(rts, "PIECES_FROM", 1100)
    calls: list = []
    real = rts._pieces_loglik
    monkeypatch.setattr(rts, "_pieces_loglik", lambda *a, **k: calls.append(1) or real(*a, **k))
    pieces, fits = smooth_trajectory(table)
    assert calls
    monkeypatch.setattr(rts, "PIECES_FROM", 10**9)
    plain, plain_fits = smooth_trajectory(table)
    assert pieces.equals(plain, null_equal=True)
    for a, b in zip(fits, plain_fits):
        assert (a.q, a.sigma, a.sigma_v, a.outliers, a.filled) == (b.q, b.sigma, b.sigma_v, b.outliers, b.filled)
        assert abs(a.log_likelihood - b.log_likelihood) <= 1e-12 * abs(b.log_likelihood)


@pytest.mark.parametrize("velocity", [False, True])
def test_rts_scan_by_blocks_is_the_scan_at_once(velocity: bool, monkeypatch) -> None:
    """Issue 33: the backward pass's prefix scan composed in place a block of frames at a time (no
    whole-track temporaries) gives the same smoothed states to the bit."""
    tracks = [_track(n, velocity, seed=n) for n in (300, 611, 257)]
    cols = rts.Columns.pack([z for z, _ in tracks], [r for _, r in tracks])
    Q = rts.axis_noise(DEFAULT_SMOOTHING.Q, np.array([1e-3, 0.1, 10.0]))
    s2, sv2 = np.array([0.09, 1.0, 9.0]), np.array([0.01, 1.0, 0.25])
    whole = rts.smooth_columns(cols, Q, s2, sv2)
    for rows in (7, 64):  # blocks shorter and longer than the scan's strides
        monkeypatch.setattr(rts, "SCAN_ELEMENTS", rows * 2 * 3)
        blocked = rts.smooth_columns(cols, Q, s2, sv2)
        assert all(np.isfinite(b).all() and np.array_equal(a, b) for a, b in zip(whole, blocked))


def test_filter_of_gathered_columns_is_the_filter_of_their_copy() -> None:
    """Issue 33: restarting pieces filters the window's columns gathered a block at a time (``columns``),
    not copied (a copy per grid point × piece grew with the track): the same sums and states to the bit."""
    import dataclasses

    tracks = [_track(n, True, seed=n) for n in (400, 333, 371, 290)]
    cols = rts.Columns.pack([z for z, _ in tracks], [r for _, r in tracks])
    which = np.array([2, 0, 2, 3])  # a column twice, out of order
    copy = dataclasses.replace(cols, **{f: getattr(cols, f)[..., which] for f in ("zp", "zv", "rp", "rv", "counted",
                                                                                 "counted_v")})
    Q = tuple(x[None, None, :] for x in rts.axis_noise(DEFAULT_SMOOTHING.Q, np.array([1e-2, 0.1, 1.0, 10.0])))
    s2, sv2 = np.array([0.09, 1.0, 9.0, 1.0])[None, None], np.array([0.01, 1.0, 0.25, 1.0])[None, None]
    start = (np.zeros((2, 1, 2, 4)) + 10.0, np.stack([np.full((1, 1, 4), v) for v in (50.0, 1.0, 5.0)]))
    own = (np.arange(400) % 3 != 0)[:, None, None] * np.ones((1, 1, 4))
    snaps = (10, 200)
    got = rts._filter_loglik(cols, Q, s2, sv2, rts.IMAGE_PRIOR, start=start, own=own, snaps=snaps, sums=True,
                             columns=which)
    want = rts._filter_loglik(copy, Q, s2, sv2, rts.IMAGE_PRIOR, start=start, own=own[..., which], snaps=snaps, sums=True)
    assert np.array_equal(got[0], want[0]) and np.array_equal(got[1], want[1]) and np.isfinite(got[0]).all()
    for f in snaps:
        assert all(np.array_equal(a, b) for a, b in zip(got[2][f], want[2][f]))


def _pieces_together(cols, Q, s2, sv2, spill: bool) -> tuple[np.ndarray, ...]:
    out = [np.full((cols.zp.shape[0], *x.shape[1:]), np.nan) for x in rts.smooth_columns(cols, Q, s2, sv2)]
    order = []
    for lo, piece in rts.smooth_pieces(cols, Q, s2, sv2, spill=spill):
        order.append(lo)
        for x, y in zip(out, piece):
            x[lo:lo + len(y)] = y
    assert order == sorted(order, reverse=True)  # the last piece first
    return tuple(out)


@pytest.mark.parametrize("velocity", [False, True])
@pytest.mark.parametrize("lengths", [(300, 611, 257), (611,)])
def test_rts_in_pieces_spilled_is_the_whole_pass(velocity: bool, lengths: tuple[int, ...], monkeypatch) -> None:
    """Issue 33: a long lane's RTS a piece of ``SCAN_FRAMES`` frames at a time (the forward pass's states
    written to a temporary file, the backward pass piece by piece, the last first) gives the in-memory
    pass's numbers to the bit: several pieces, unobserved frames, tracks ending in different pieces, and
    one track alone (filtered in Python floats)."""
    tracks = [_track(n, velocity, seed=n) for n in lengths]
    cols = rts.Columns.pack([z for z, _ in tracks], [r for _, r in tracks])
    b = len(lengths)
    Q = rts.axis_noise(DEFAULT_SMOOTHING.Q, np.array([1e-3, 0.1, 10.0][:b]))
    s2, sv2 = np.array([0.09, 1.0, 9.0][:b]), np.array([0.01, 1.0, 0.25][:b])
    one_scan = rts.smooth_columns(cols, Q, s2, sv2)  # 611 frames: one scan
    monkeypatch.setattr(rts, "SCAN_FRAMES", 64)  # ten pieces
    whole = rts.smooth_columns(cols, Q, s2, sv2)
    spilled = _pieces_together(cols, Q, s2, sv2, spill=True)
    kept = _pieces_together(cols, Q, s2, sv2, spill=False)
    for w, s, k, o in zip(whole, spilled, kept, one_scan):
        assert np.isfinite(s).all() and np.array_equal(w, s) and np.array_equal(w, k)
        # the pieces change only how the backward maps are associated: rounding, against one scan of the lane
        assert np.allclose(s, o, rtol=1e-12, atol=1e-12 * np.abs(o).max())


def test_filter_in_pieces_is_the_whole_filter() -> None:
    """The forward pass a piece at a time carries its state: the same filtered states to the bit."""
    tracks = [_track(n, True, seed=n) for n in (300, 611, 257)]
    cols = rts.Columns.pack([z for z, _ in tracks], [r for _, r in tracks])
    Q = tuple(x[None] for x in rts.axis_noise(DEFAULT_SMOOTHING.Q, np.array([1e-3, 0.1, 10.0])))
    s2, sv2 = np.array([[0.09, 1.0, 9.0]]), np.array([[0.01, 1.0, 0.25]])
    _, whole = rts.filter_columns(cols, Q, s2, sv2, True)
    pieces = list(rts.filter_chunks(cols, Q, s2, sv2, rts.IMAGE_PRIOR, 100))
    assert [lo for lo, _ in pieces] == list(range(0, 611, 100))
    for k, w in enumerate(whole):
        assert np.array_equal(w, np.concatenate([p[k] for _, p in pieces]))
    one = rts.Columns.pack([tracks[1][0]], [tracks[1][1]])
    q = tuple(float(x[0, 1]) for x in Q)
    floats = rts.filter_one(one, q, 1.0, 1.0)
    chunks = list(rts.filter_one_chunks(one, q, 1.0, 1.0, rts.IMAGE_PRIOR, 100))
    for k, w in enumerate(floats):
        assert np.array_equal(w, np.concatenate([p[k] for _, p in chunks]))
