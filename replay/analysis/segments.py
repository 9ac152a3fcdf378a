"""Per-track operations on many tracks' rows at once (issue 33).

The offline tools hold every track's rows in one table, tracks one after another; ``starts`` (T + 1,)
gives each track's first row and the end. These functions do, for all tracks in one numpy pass, what a
loop over the tracks would do one at a time — with the same arithmetic, so the results are the same
to the bit (``tests/replay/analysis/test_segments.py`` compares them with the per-track versions).
"""

from __future__ import annotations

import numpy as np


def offsets(track: np.ndarray) -> np.ndarray:
    """``starts`` of rows grouped by ``track`` (equal values adjacent): each run's first row, then the end."""
    n = len(track)
    if n == 0:
        return np.zeros(1, dtype=np.int64)
    return np.concatenate([[0], np.flatnonzero(track[1:] != track[:-1]) + 1, [n]]).astype(np.int64)


def single(n: int) -> np.ndarray:
    """``starts`` of one track of ``n`` rows."""
    return np.array([0, n], dtype=np.int64)


def track_of_row(starts: np.ndarray) -> np.ndarray:
    """The track index (0 .. T-1) of every row."""
    return np.repeat(np.arange(len(starts) - 1), np.diff(starts))


def per_row(values: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """A per-track value on each of the track's rows."""
    return np.repeat(values, np.diff(starts))


def counts(mask: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """How many rows of each track ``mask`` holds (T,)."""
    c = np.concatenate([[0], np.cumsum(mask, dtype=np.int64)])
    return c[starts[1:]] - c[starts[:-1]]


def _known_ranks(ok: np.ndarray, starts: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Positions of the known rows, and per row: known rows before it (all tracks), its track's
    first known rank and its track's number of known rows."""
    cum = np.concatenate([[0], np.cumsum(ok, dtype=np.int64)])
    seg = track_of_row(starts)
    first = cum[starts[:-1]][seg]
    count = (cum[starts[1:]] - cum[starts[:-1]])[seg]
    return np.flatnonzero(ok), cum[:-1], first, count


def interp(frames: np.ndarray, values: np.ndarray, where: np.ndarray, starts: np.ndarray | None = None) -> np.ndarray:
    """Per track, :func:`numpy.interp` of its finite ``values`` at its ``where`` rows (the ends held;
    one known value everywhere; none: unchanged). ``frames`` rise within a track."""
    starts = single(len(values)) if starts is None else starts
    ok = np.isfinite(values)
    out = values.copy()
    pos, before, first, count = _known_ranks(ok, starts)
    rows = np.flatnonzero(where & (count >= 1))
    if rows.size == 0:
        return out
    first, count = first[rows], count[rows]
    # the last known row at or before each (numpy.interp's j: xp[j] <= x < xp[j+1]), local to its track
    j = before[rows] + ok[rows] - 1 - first
    left, right = j < 0, j >= count - 1
    inner = ~left & ~right
    out[rows[left]] = values[pos[first[left]]]
    out[rows[right]] = values[pos[first[right] + count[right] - 1]]
    a, b = pos[first[inner] + j[inner]], pos[first[inner] + j[inner] + 1]
    slope = (values[b] - values[a]) / (frames[b] - frames[a])
    out[rows[inner]] = slope * (frames[rows[inner]] - frames[a]) + values[a]
    return out


def interp_rate(frames: np.ndarray, values: np.ndarray, where: np.ndarray, starts: np.ndarray | None = None) -> np.ndarray:
    """Per track, the slope (per frame) of :func:`interp`'s line at the ``where`` rows: the segment
    between the known values around each (0 with a single known value; NaN with none)."""
    starts = single(len(values)) if starts is None else starts
    ok = np.isfinite(values)
    out = np.full(len(values), np.nan)
    pos, before, first, count = _known_ranks(ok, starts)
    out[where & (count == 1)] = 0.0
    rows = np.flatnonzero(where & (count >= 2))
    first, count = first[rows], count[rows]
    i = np.clip(before[rows] - first, 1, count - 1)  # numpy.searchsorted(known frames, frame), clipped
    a, b = pos[first + i - 1], pos[first + i]
    out[rows] = (values[b] - values[a]) / (frames[b] - frames[a])
    return out


def short_gaps(missing: np.ndarray, starts: np.ndarray, max_gap: int) -> np.ndarray:
    """The ``missing`` rows in runs of at most ``max_gap`` rows with a row that is not missing on both
    sides in the same track (a gap the smoother interpolates)."""
    n = len(missing)
    track_start = np.zeros(n, bool)
    track_start[starts[:-1][starts[:-1] < n]] = True
    track_end = np.zeros(n, bool)
    track_end[starts[1:][starts[1:] > 0] - 1] = True
    prev_missing = np.concatenate([[False], missing[:-1]]) & ~track_start
    next_missing = np.concatenate([missing[1:], [False]]) & ~track_end
    a = np.flatnonzero(missing & ~prev_missing)
    b = np.flatnonzero(missing & ~next_missing) + 1
    inside = ~track_start[a] & ~track_end[b - 1]
    out = np.zeros(n, bool)
    out[missing] = np.repeat(inside & (b - a <= max_gap), b - a)
    return out


def interpolated_times(frames: np.ndarray, times: np.ndarray, known: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """Per track, :func:`trackreplay.replay.core.trajectory.interpolated_times`: the known log times
    exactly, the others linear in the frame between their known neighbours (integers, rounded half
    up), the ends held; a track with none known keeps 0."""
    t = np.where(known, np.asarray(times), 0).astype(np.int64)
    f = np.asarray(frames, dtype=np.int64)
    n = len(t)
    if not known.any() or known.all():
        return t
    seg = track_of_row(starts)
    idx = np.arange(n)
    prev = np.maximum.accumulate(np.where(known, idx, -1))
    nxt = np.minimum.accumulate(np.where(known, idx, n)[::-1])[::-1]
    has_prev, has_next = prev >= starts[:-1][seg], nxt < starts[1:][seg]
    inner = ~known & has_prev & has_next
    a, b = prev[inner], nxt[inner]
    num, den = (t[b] - t[a]) * (f[inner] - f[a]), f[b] - f[a]
    t[inner] = t[a] + (2 * num + den) // (2 * den)  # rounded half up
    head, tail = ~known & ~has_prev & has_next, ~known & has_prev & ~has_next
    t[head] = t[nxt[head]]
    t[tail] = t[prev[tail]]
    return t
