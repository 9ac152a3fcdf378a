"""One long track smoothed in two passes over its rows (issue 33: `trackreplay smooth` of hours of one
track in memory that does not follow the track's table).

:func:`~trackreplay.replay.analysis.smooth.smooth_trajectory` holds a track's table, its span (every frame,
absent ones as nulls), its observation arrays and its output table at once: ~1 KB a row. Here the track's
rows are read a piece at a time (:meth:`LongTrack.add`): each piece is appended to a temporary Parquet file
(a row group a piece) and only what the smoother needs is kept, as arrays (~55 bytes a row: frame, flags,
``x, y, vx, vy`` and confidence, or ``X, Y, Z`` and time). The smoother (an image track:
:func:`~trackreplay.replay.analysis.smooth.smooth_tracks`; a 3-D one: ``smooth._fit_space`` and its frame
rate; the grid search, the RTS pass by :data:`~trackreplay.replay.analysis.rts.SCAN_FRAMES` pieces with its
filtered states in a temporary file, the outliers) runs once on the whole track's arrays, as the whole
table's path runs it. The rows are then read back and assembled a piece at a time (:meth:`LongTrack.pieces`)
by the whole table's own code (:func:`~trackreplay.replay.analysis.smooth.smooth_track_piece`) given those
results.

A piece is cut at an *anchor*: a row the smoother observed (a measurement, not an outlier), whose time is
known and whose interpolated columns (box, world position and line of sight; a 3-D track's image position,
box and image velocity) are finite (each that is finite anywhere in the track); a 3-D track's anchor also has
a measurement and a known image position before and after it. Both pieces hold it, the second drops it. A
gap then never crosses a cut (its run is bracketed by the anchor), and every interpolation of a column and of
the times sees the neighbours it sees in the whole table, so the rows are the whole table's, to the bit
(``tests/replay/analysis/test_smooth_long.py``). A track whose rows have no anchor is one piece; one without
a position or an observation, or a 3-D track with a row whose time neither it nor the log gives (its times
are interpolated across the track), is read whole.
"""

from __future__ import annotations

import dataclasses
import itertools
import tempfile
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np
import polars as pl

from trackreplay.replay.analysis import smooth as sm
from trackreplay.trackers.smoothing import SpaceSmoothing

LONG_ROWS = 1 << 15  # a track with more rows than this is smoothed in two passes (the command)
PIECE_FRAMES = 1 << 14  # frames of a piece of the second pass, cut at the next anchor after
INTERPOLATED = ("w", "h", "X", "Y", "Z", "dx", "dy", "dz")  # the columns interpolated across filled frames
SPACE_INTERPOLATED = ("x", "y", "w", "h", "vx", "vy")  # ... of a 3-D track (x, y first: their rates too)
_KEPT = ("frame", "positioned", "has_pos", "measured", "x", "y", "vx", "vy", "X", "Y", "Z", "confidence", "t", "t_known",
         "finite")


class LongTrack:
    """One track's rows, added a piece at a time in frame order (:meth:`add`), then smoothed and
    given back a piece at a time (:meth:`pieces`); :attr:`fit` once they are all given. :meth:`close`
    removes the temporary file."""

    def __init__(self, tracker: str) -> None:
        self.model = sm.smoothing_model(tracker)
        self.space = isinstance(self.model, SpaceSmoothing)
        self.fit: sm.TrackFit | None = None
        self._dir = tempfile.TemporaryDirectory(prefix="trackreplay-smooth-")
        self._path = Path(self._dir.name) / "rows.parquet"
        self._writer: Any = None
        self._groups: list[int] = []
        self._kept: dict[str, list[np.ndarray]] = {k: [] for k in _KEPT}

    def add(self, piece: pl.DataFrame) -> None:
        """The track's next rows (the ★ columns, cast and checked; frames rising)."""
        import pyarrow.parquet as pq

        piece = piece.select(sm.COLUMNS)
        table = piece.to_arrow()
        if self._writer is None:
            self._writer = pq.ParquetWriter(self._path, table.schema)
        self._writer.write_table(table, row_group_size=max(1, piece.height))
        self._groups.append(piece.height)
        status = piece["status"].fill_null("lost")
        values = {c: piece[c].to_numpy().astype(float) for c in (("X", "Y", "Z") if self.space else ("x", "y", "vx", "vy"))}
        # :func:`smooth._smooth_image`'s and :func:`smooth._smooth_space`'s span (positioned) and rows (has_pos, measured)
        if self.space:
            has_pos = np.isfinite(values["X"]) & np.isfinite(values["Y"]) & np.isfinite(values["Z"])
            positioned = pl.col("X").is_not_null() & (pl.col("status") != "lost")
        else:
            has_pos = np.isfinite(values["x"]) & np.isfinite(values["y"])
            positioned = pl.col("x").is_not_null() & pl.col("y").is_not_null() & (pl.col("status") != "lost")
        has_pos &= (status != "lost").to_numpy()
        finite = np.zeros(piece.height, np.uint8)
        for k, c in enumerate(SPACE_INTERPOLATED if self.space else INTERPOLATED):
            finite |= np.isfinite(piece[c].to_numpy().astype(float)).astype(np.uint8) << k
        got = {
            "frame": piece["frame"].to_numpy().astype(np.int64),
            "positioned": piece.select(positioned.fill_null(False)).to_series().to_numpy(),
            "has_pos": has_pos, "measured": has_pos & (status == "measured").to_numpy(), **values,
            "confidence": piece["confidence"].to_numpy().astype(float) if not self.space else None,
            "t": piece["t_ns"].to_numpy().astype(float) if self.space else None,
            "t_known": piece["t_ns"].is_not_null().to_numpy(), "finite": finite,
        }
        for k, v in got.items():
            if v is not None:
                self._kept[k].append(v)

    def _rows(self, lo: int, hi: int) -> pl.DataFrame:
        """Rows ``lo .. hi`` (inclusive) of the track, read back from the temporary file."""
        import pyarrow.parquet as pq

        ends = np.cumsum(self._groups)
        first, last = int(np.searchsorted(ends, lo, "right")), int(np.searchsorted(ends, hi, "right"))
        start = int(ends[first - 1]) if first else 0
        part = pl.from_arrow(pq.ParquetFile(self._path).read_row_groups(list(range(first, last + 1))))
        return part.slice(lo - start, hi - lo + 1)

    def _whole(self, config: sm.SmoothConfig, frame_times, cameras) -> Iterator[pl.DataFrame]:
        """The track read whole and smoothed as the whole table is (a track without an anchor to cut at)."""
        out, fits = sm.smooth_trajectory(self._rows(0, sum(self._groups) - 1), config, frame_times=frame_times,
                                         cameras=cameras)
        self.fit = fits[0] if fits else None
        yield out

    def pieces(self, config: sm.SmoothConfig, frame_times: Mapping[int, int] | None = None,
               cameras: Mapping[int, Any] | None = None) -> Iterator[pl.DataFrame]:
        """The smoothed rows, a piece at a time in frame order (see the module docstring)."""
        if self._writer is not None:
            self._writer.close()
            self._writer = None
        kept = {}
        for k in _KEPT:  # one column at a time: its pieces are freed as it is joined
            pieces = self._kept.pop(k)
            kept[k] = np.concatenate(pieces) if pieces else np.zeros(0)
            del pieces
        frame, positioned = kept["frame"], kept["positioned"]
        if not positioned.any():
            yield from self._whole(config, frame_times, cameras)
            return
        at_pos = np.flatnonzero(positioned)
        lo, hi = int(frame[at_pos[0]]), int(frame[at_pos[-1]])
        inside = (frame >= lo) & (frame <= hi)
        at = frame[inside] - lo
        n = hi - lo + 1
        if self.space:
            yield from self._space_pieces(kept, lo, inside, at, n, config, frame_times)
            return
        # :func:`smooth._image_observations` without raw measurements, on the span's frames
        measured = kept["measured"][inside]
        nan = np.full(len(at), np.nan)
        velocity = self.model.observe_velocity
        seen = np.stack([kept["x"][inside], kept["y"][inside], kept["vx"][inside] if velocity else nan,
                         kept["vy"][inside] if velocity else nan], axis=1)
        z = np.full((n, 4), np.nan)
        z[at] = np.where(measured[:, None], seen, np.nan)
        confidence = np.full(n, np.nan)
        confidence[at] = kept["confidence"][inside]
        del seen, nan
        if not np.isfinite(z[:, :2]).all(axis=1).any():  # only predictions: kept as they are, whole
            yield from self._whole(config, frame_times, cameras)
            return
        frame, able = _able(kept, inside)
        del kept, measured, inside
        xs, var, outliers, fit = sm.smooth_tracks([z], [confidence], config, copy=False)[0]
        del z, confidence
        _give_back_freed_heap()
        cuts = _anchors(frame, able, outliers, lo)
        del frame, able

        def given(full: pl.DataFrame, starts: np.ndarray) -> list[tuple]:
            k, m = int(full["frame"][0]) - lo, int(starts[1])
            return [(xs[k:k + m], var[k:k + m], outliers[k:k + m], fit)]

        yield from self._assembled(cuts, given, config, frame_times, cameras)

    def _space_pieces(self, kept: dict[str, np.ndarray], lo: int, inside: np.ndarray, at: np.ndarray, n: int,
                      config: sm.SmoothConfig, frame_times) -> Iterator[pl.DataFrame]:
        """:meth:`pieces` of a 3-D track: :func:`smooth._fit_space` once on the span's arrays (its
        observations ``X, Y, Z`` with ``R = I``, as without raw measurements), its frame rate once."""
        frame = kept["frame"]
        measured = kept["measured"][inside]
        ok = np.zeros(n, bool)
        ok[at] = measured
        unknown = ~kept["t_known"]  # a time neither the row nor the log gives: interpolated across pieces, read whole
        found = sm.logged_times(frame_times, frame[unknown])[1] if frame_times and unknown.any() else ~unknown[unknown]
        if ok.sum() < 2 or not found.all():
            yield from self._whole(config, frame_times, None)
            return
        t = np.full(n, np.nan)
        t[at] = kept["t"][inside]
        rate = sm.frame_rate(sm.span_times(t, lo + np.arange(n, dtype=np.int64), frame_times))
        del t
        z = np.full((n, 3), np.nan)
        z[at] = np.where(measured[:, None], np.stack([kept[c][inside] for c in ("X", "Y", "Z")], axis=1), np.nan)
        frame, able = _able(kept, inside, space=True)
        del kept, measured, inside
        R0 = np.broadcast_to(np.eye(3), (n, 3, 3)).copy()
        track = sm._SpaceTrack(z, R0, ok, self.model.sigma_grid)
        accel, s, ll, xs, Ps, oks, outliers = sm._fit_space(self.model, [track], config)[0]
        del z, R0, track
        _give_back_freed_heap()
        cuts = _anchors(frame, able, outliers, lo)
        del frame, able

        def given(full: pl.DataFrame, starts: np.ndarray) -> tuple[list[tuple], np.ndarray]:
            k, m = int(full["frame"][0]) - lo, int(starts[1])
            return [(accel, s, ll, xs[k:k + m], Ps[k:k + m], oks[k:k + m], outliers[k:k + m])], np.array([rate])

        yield from self._assembled(cuts, given, config, frame_times, None)

    def _assembled(self, cuts: list[int], given, config: sm.SmoothConfig, frame_times, cameras) -> Iterator[pl.DataFrame]:
        """The rows between the cuts (each cut in both pieces, dropped from the second), assembled by
        :func:`smooth.smooth_track_piece` given the smoother's results; :attr:`fit` the track's."""
        bounds = [0, *cuts, sum(self._groups) - 1]
        counts = np.zeros(3, np.int64)
        first_fit = None
        for j, (a, b) in enumerate(itertools.pairwise(bounds)):
            out, fits = sm.smooth_track_piece(self._rows(a, b), config, given, frame_times=frame_times, cameras=cameras)
            first_fit = first_fit or fits[0]
            counts += (fits[0].observations - (j > 0), fits[0].outliers, fits[0].filled)  # the anchor twice: once
            yield out.slice(1) if j else out
        self.fit = dataclasses.replace(first_fit, observations=int(counts[0]), outliers=int(counts[1]),
                                       filled=int(counts[2]))

    def close(self) -> None:
        if self._writer is not None:
            self._writer.close()
        self._dir.cleanup()


def _give_back_freed_heap() -> None:
    """glibc's ``malloc_trim``: the smoother's arrays, freed, stay in the C heap, which the second pass's
    tables (polars' and pyarrow's own allocators) cannot reuse; given back, the process peaks lower. Nothing
    where the C library is not glibc."""
    import ctypes

    try:
        ctypes.CDLL(None).malloc_trim(0)
    except (AttributeError, OSError):
        pass


def _able(kept: dict[str, np.ndarray], inside: np.ndarray, space: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """The rows' frames and the rows where the second pass may cut, but for the outliers (not known yet):
    measured, time known, each interpolated column finite there if it is anywhere in the track. A 3-D
    track's cut also has a measured row before and after it (a piece of fewer than two is not smoothed) and
    a known ``x`` and ``y`` before and after it (a filled row's image velocity past the last known one is the
    last two's rate)."""
    has_pos, finite = kept["has_pos"], kept["finite"]
    anywhere = int(np.bitwise_or.reduce(finite[has_pos])) if has_pos.any() else 0
    able = inside & kept["measured"] & kept["t_known"] & ((finite & anywhere) == anywhere)
    if space:
        for rows in (kept["measured"] & inside, *(has_pos & (finite & (1 << k) > 0) for k in (0, 1) if anywhere & (1 << k))):
            before = np.cumsum(rows) - rows
            able &= (before >= 1) & (before < before[-1] + rows[-1] - 1)
    return kept["frame"], able


def _anchors(frame: np.ndarray, able: np.ndarray, outliers: np.ndarray, lo: int) -> list[int]:
    """The rows the second pass cuts at, :data:`PIECE_FRAMES` frames apart or more: ``able`` (:func:`_able`)
    and observed (not an outlier); never the first or last row."""
    rows = np.flatnonzero(able[:-1])
    rows = rows[(rows > 0) & ~outliers[frame[rows] - lo]]
    frames = frame[rows]
    cuts: list[int] = []
    target = lo + PIECE_FRAMES
    while True:  # (one step a piece)
        k = int(np.searchsorted(frames, target))
        if k >= len(rows):
            return cuts
        cuts.append(int(rows[k]))
        target = int(frames[k]) + PIECE_FRAMES
