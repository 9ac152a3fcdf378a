"""A long image track smoothed in two passes, its rows given back a piece at a time (issue 33), is the whole
table's smoothing to the bit: rows, columns and the fit."""

from __future__ import annotations

import numpy as np
import polars as pl
import pytest

from trackreplay.replay.analysis import smooth_long
from trackreplay.replay.analysis.smooth import FrameTimes, SmoothConfig, smooth_trajectory


def _hard_track(bench, tracker: str, rows: int, seed: int) -> pl.DataFrame:
    """A synthetic track (gaps, absent frames, outliers) with lost rows before and after its span, world
    positions and lines of sight on some rows only, and rows whose time is unknown."""
    df = bench.synthetic_trajectory(rows, tracker, tracks=1, seed=seed)
    n = df.height
    rng = np.random.default_rng(seed)
    k = np.arange(n)
    world = (k % 97 < 60) & (rng.random(n) < 0.9)
    sight = k % 13 != 0
    nulls = rng.random(n) < 0.02
    lost = (k < 5) | (k >= n - 4)
    return df.with_columns(
        pl.when(pl.Series(world)).then(pl.col("x") * 0.01).otherwise(None).alias("X"),
        pl.when(pl.Series(world)).then(pl.lit(2.0)).otherwise(None).alias("Z"),
        pl.when(pl.Series(sight)).then(pl.col("y") * 1e-3).otherwise(None).alias("dx"),
        pl.when(pl.Series(sight)).then(pl.lit(1.0)).otherwise(None).alias("dz"),
        pl.when(pl.Series(nulls)).then(None).otherwise(pl.col("t_ns")).alias("t_ns"),
        pl.when(pl.Series(lost)).then(pl.lit("lost")).otherwise(pl.col("status")).alias("status"),
        *(pl.when(pl.Series(lost)).then(None).otherwise(pl.col(c)).alias(c) for c in ("x", "y")),
    )


def _streamed(table: pl.DataFrame, batch: int, **kw) -> tuple[pl.DataFrame, object, int]:
    track = smooth_long.LongTrack(table["tracker"][0])
    try:
        for at in range(0, table.height, batch):
            track.add(table.slice(at, batch))
        parts = list(track.pieces(SmoothConfig(), **kw))
    finally:
        track.close()
    return pl.concat(parts), track.fit, len(parts)


@pytest.mark.parametrize("tracker", ["flow", "colorpf"])
def test_a_long_track_in_pieces_is_the_whole_tables(tracker: str, benchmark_module, monkeypatch) -> None:
    bench = benchmark_module("bench_smooth")
    table = _hard_track(bench, tracker, 3000, seed=11)
    frames = np.arange(0, 3200)
    times = FrameTimes(frames, frames * 33_333_333)  # absent frames take the log's time
    monkeypatch.setattr(smooth_long, "PIECE_FRAMES", 150)
    for kw in ({}, {"frame_times": times}):
        got, fit, pieces = _streamed(table, 333, **kw)
        want, fits = smooth_trajectory(table, frame_times=kw.get("frame_times"))
        assert pieces >= 10 and got.schema == want.schema and got.equals(want, null_equal=True)
        assert fit == fits[0] and fit.outliers > 0 and fit.filled > 0
        assert want["t_ns"].null_count() == 0 and got.filter(pl.col("fill") == "rts_gap").height > 0


def test_a_long_track_without_anchors_or_observations(benchmark_module, monkeypatch) -> None:
    """A column finite on one row only leaves that row the only place to cut; a track only predicted, and
    one never positioned, are read whole as the whole table's path reads them."""
    bench = benchmark_module("bench_smooth")
    table = _hard_track(bench, "flow", 1500, seed=12)
    fit_for_a_cut = (pl.col("status") == "measured") & pl.all_horizontal(pl.col("t_ns", "X", "dx").is_not_null())
    at = table.with_row_index().filter(fit_for_a_cut & (pl.col("index") >= 700))["frame"][0]
    one = table.with_columns(pl.when(pl.col("frame") == at).then(pl.lit(3.0)).otherwise(None).alias("h"))
    monkeypatch.setattr(smooth_long, "PIECE_FRAMES", 100)
    got, fit, pieces = _streamed(one, 200)
    want, fits = smooth_trajectory(one)
    assert pieces == 2 and got.equals(want, null_equal=True) and fit == fits[0]
    for status in ("predicted", "lost"):
        idle = table.with_columns(pl.lit(status).alias("status"))
        got, fit, pieces = _streamed(idle, 200)
        want, fits = smooth_trajectory(idle)
        assert pieces == 1 and got.equals(want, null_equal=True) and fit is None and fits == []


def _hard_space_track(bench, rows: int, seed: int) -> pl.DataFrame:
    """A synthetic 3-D (groups) track with lost rows before and after its span, image columns on some rows
    only, and rows whose time is unknown."""
    df = bench.synthetic_trajectory(rows, "groups", tracks=1, seed=seed)
    n = df.height
    rng = np.random.default_rng(seed)
    k = np.arange(n)
    lost = (k < 5) | (k >= n - 4)
    return df.with_columns(
        pl.when(pl.Series(k % 89 < 70)).then(pl.col("X") * 50.0).otherwise(None).alias("x"),
        pl.when(pl.Series(k % 89 < 70)).then(pl.col("Y") * 50.0).otherwise(None).alias("y"),
        pl.when(pl.Series(k % 7 != 0)).then(pl.lit(4.0)).otherwise(None).alias("w"),
        pl.when(pl.Series(rng.random(n) < 0.02)).then(None).otherwise(pl.col("t_ns")).alias("t_ns"),
        pl.when(pl.Series(lost)).then(pl.lit("lost")).otherwise(pl.col("status")).alias("status"),
        *(pl.when(pl.Series(lost)).then(None).otherwise(pl.col(c)).alias(c) for c in ("X", "Y", "Z")),
    )


def test_a_long_3d_track_in_pieces_is_the_whole_tables(benchmark_module, monkeypatch) -> None:
    """A groups track: smoothed in 3-D once (its frame rate once), assembled a piece at a time; a row whose
    time neither it nor the log gives (interpolated across pieces) and the track is read whole."""
    bench = benchmark_module("bench_smooth")
    table = _hard_space_track(bench, 3000, seed=13)
    frames = np.arange(0, 3200)
    times = FrameTimes(frames, frames * 33_333_333)
    monkeypatch.setattr(smooth_long, "PIECE_FRAMES", 150)
    for kw, many in (({"frame_times": times}, True), ({}, False)):
        got, fit, pieces = _streamed(table, 333, **kw)
        want, fits = smooth_trajectory(table, frame_times=kw.get("frame_times"))
        assert (pieces >= 10) == many and got.schema == want.schema and got.equals(want, null_equal=True)
        assert fit == fits[0] and fit.outliers > 0 and fit.filled > 0
        assert got.filter(pl.col("fill") == "rts_gap")["VX"].is_not_null().all()
