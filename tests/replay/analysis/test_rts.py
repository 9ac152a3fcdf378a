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
