"""Per-track operations on many tracks at once (replay/analysis/segments.py) give, to the bit, what the
per-track loops they replaced gave (issue 33)."""

from __future__ import annotations

import numpy as np

from trackreplay.replay.analysis import segments
from trackreplay.replay.core.trajectory import interpolated_times


def _tracks(seed: int = 0, count: int = 40):
    """Concatenated tracks of random lengths (1 .. 30 rows), rising frames with holes, NaN values."""
    rng = np.random.default_rng(seed)
    lengths = rng.integers(1, 30, count)
    starts = np.concatenate([[0], np.cumsum(lengths)])
    frames = np.concatenate([np.cumsum(rng.integers(1, 4, n)) + rng.integers(0, 100) for n in lengths]).astype(float)
    values = rng.normal(0, 50, starts[-1])
    values[rng.random(starts[-1]) < 0.5] = np.nan
    where = rng.random(starts[-1]) < 0.6
    return starts, frames, values, where


def _interp_one(frames, values, where):
    ok = np.isfinite(values)
    out = values.copy()
    if ok.sum() >= 2:
        out[where] = np.interp(frames[where], frames[ok], values[ok])
    elif ok.sum() == 1:
        out[where] = values[ok][0]
    return out


def _rate_one(frames, values, where):
    ok = np.isfinite(values)
    out = np.full(len(values), np.nan)
    if ok.sum() == 1:
        out[where] = 0.0
    if ok.sum() >= 2:
        fk, vk = frames[ok], values[ok]
        i = np.clip(np.searchsorted(fk, frames[where]), 1, len(fk) - 1)
        out[where] = (vk[i] - vk[i - 1]) / (fk[i] - fk[i - 1])
    return out


def _per_track(fn, starts, *arrays):
    return np.concatenate([fn(*(a[s:e] for a in arrays)) for s, e in zip(starts[:-1], starts[1:])])


def test_interp_and_rate_are_numpys_per_track_bit_for_bit() -> None:
    for seed in range(5):
        starts, frames, values, where = _tracks(seed)
        got = segments.interp(frames, values, where, starts)
        want = _per_track(_interp_one, starts, frames, values, where)
        assert np.array_equal(got, want, equal_nan=True)
        rate = segments.interp_rate(frames, values, where, starts)
        assert np.array_equal(rate, _per_track(_rate_one, starts, frames, values, where), equal_nan=True)


def test_a_track_never_reads_its_neighbours_values() -> None:
    starts = np.array([0, 3, 6])
    frames = np.array([0.0, 1.0, 2.0, 0.0, 1.0, 2.0])
    values = np.array([1.0, np.nan, np.nan, np.nan, np.nan, 7.0])
    where = np.isnan(values)
    assert segments.interp(frames, values, where, starts).tolist() == [1.0, 1.0, 1.0, 7.0, 7.0, 7.0]
    assert segments.interp_rate(frames, values, where, starts)[where].tolist() == [0.0, 0.0, 0.0, 0.0]


def test_short_gaps_are_bracketed_within_their_track() -> None:
    missing = np.array([0, 1, 1, 0, 1, 0, 0, 1, 1, 1, 0, 1], bool)
    starts = np.array([0, 5, 12])
    got = segments.short_gaps(missing, starts, max_gap=2)
    # track 0: rows 1-2 bracketed (filled), row 4 ends the track; track 1: rows 7-9 too long, row 11 ends it
    assert np.flatnonzero(got).tolist() == [1, 2]
    assert np.flatnonzero(segments.short_gaps(missing, starts, max_gap=3)).tolist() == [1, 2, 7, 8, 9]


def test_times_are_interpolated_within_each_track_as_for_one() -> None:
    rng = np.random.default_rng(3)
    starts, frames, _, _ = _tracks(3)
    frames = frames.astype(np.int64)
    t = frames * 33_333_333 + 1_700_000_000_000_000_000
    known = rng.random(len(t)) < 0.4
    got = segments.interpolated_times(frames, t, known, starts)
    want = _per_track(interpolated_times, starts, frames, t, known)
    assert np.array_equal(got, want)


def test_offsets_counts_and_rows() -> None:
    starts = segments.offsets(np.array([4, 4, 1, 1, 1, 9]))
    assert starts.tolist() == [0, 2, 5, 6]
    assert segments.offsets(np.array([], dtype=np.int64)).tolist() == [0]
    assert segments.counts(np.array([1, 0, 1, 1, 0, 1], bool), starts).tolist() == [1, 2, 1]
    assert segments.per_row(np.array([7, 8, 9]), starts).tolist() == [7, 7, 8, 8, 8, 9]
