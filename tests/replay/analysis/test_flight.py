"""The golf ball's 3-D flight fitted to lines of sight (issue 13)."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import polars as pl
import pytest

from trackreplay.recorder.synth.golf.flight import BallModel, Launch, simulate_shot
from trackreplay.replay.cli.main import main
from trackreplay.schemas.errors import TrackreplayError
from trackreplay.replay.analysis.flight import FlightConfig, FlightUnavailable, Observations, fit_flight, observations

GOLDEN = Path(__file__).resolve().parents[2] / "golden"


@pytest.fixture(scope="module")
def chip() -> tuple:
    """A short shot (carry ~50 m) seen from behind and to the side, 0.3 px noise, 20 % size noise."""
    ball = BallModel(friction=0.6, rolling_resistance=0.3)
    traj = simulate_shot(Launch(speed=28.0, elevation=28.0, azimuth=5.0, backspin_rpm=6000.0), ball)
    fps, t_launch = 30.0, 0.3
    t = np.arange(int((t_launch + traj.landing_time + 1.5) * fps)) / fps
    pos = traj.sample(t - t_launch).position
    cam = np.array([-8.0, -6.0, 2.5])
    rel = pos - cam
    r = np.linalg.norm(rel, axis=1)
    fx = np.clip(40.0 * r, 800.0, 8000.0)
    rng = np.random.default_rng(0)
    los = rel / r[:, None] + rng.normal(size=rel.shape) * (0.3 / fx)[:, None]
    los /= np.linalg.norm(los, axis=1, keepdims=True)
    size = fx * ball.diameter / r * np.exp(rng.normal(size=len(t)) * 0.2)
    obs = Observations(np.arange(len(t)), t, los, size, fx, cam)
    fit = fit_flight(obs, FlightConfig(step_s=1 / 60, jackknife_blocks=5), fps)
    return traj, t_launch, fit


def test_fit_recovers_a_known_flight(chip) -> None:
    traj, t_launch, fit = chip
    rep = fit.report
    landing = np.array([v.value for v in rep.landing_point])
    assert np.linalg.norm(landing[:2] - traj.landing_point[:2]) < 0.02 * traj.carry
    assert abs(rep.carry.value - traj.carry) < 0.02 * traj.carry
    assert abs(rep.apex_height.value - traj.apex_point[2]) < 0.5
    assert abs(rep.launch_time.value - t_launch) < 0.02
    assert abs(rep.launch_speed.value - 28.0) < 2.0 and abs(rep.launch_elevation.value - 28.0) < 2.0
    assert abs(rep.time_of_flight.value - traj.landing_time) < 0.05
    assert 0 < rep.carry.std < 5 and 0 < rep.landing_point[0].std < 5  # uncertainties are reported
    # ... and honest: the true landing point and carry lie within 3 sigma
    err = landing[:2] - traj.landing_point[:2]
    assert np.hypot(*err) < 3 * np.hypot(rep.landing_point[0].std, rep.landing_point[1].std)
    assert abs(rep.carry.value - traj.carry) < 3 * rep.carry.std
    assert "launch" in rep.describe()


def test_fit_is_deterministic(chip) -> None:
    _, _, fit = chip
    again = fit_flight(fit.observations, dataclasses.replace(fit.config, jackknife_blocks=0), 30.0)  # theta does not depend on it
    assert np.array_equal(again.theta, fit.theta)


def test_no_encoders_says_3d_is_not_available(tmp_path, capsys) -> None:
    traj = pl.DataFrame({"tracker": ["golf"], "track_id": [1], "frame": [0], "t_ns": [0], "x": [1.0], "y": [1.0],
                         "status": ["measured"]})
    with pytest.raises(FlightUnavailable, match="3-D not available"):
        observations(traj, {})
    # A log without PTZ encoders, end to end: one sentence, exit 2.
    log = GOLDEN / "flow-sim1-24f.mcap"
    path = tmp_path / "t.parquet"
    assert main(["replay", str(log), "--tracker", "flow", "--export", str(path), "--quiet"]) == 0
    assert main(["flight", str(path), str(log)]) == 2
    err = capsys.readouterr().err
    assert "3-D not available" in err and str(path) in err and str(log) in err  # both files named


def _rows(n: int, los) -> pl.DataFrame:
    los = np.broadcast_to(np.asarray(los, float), (n, 3)).copy()
    return pl.DataFrame({"track_id": [1] * n, "frame": np.arange(n), "t_ns": np.arange(n) * 33_333_333, "x": [1.0] * n,
                         "w": [6.0] * n, "h": [6.0] * n, "dx": los[:, 0], "dy": los[:, 1], "dz": los[:, 2],
                         "status": ["measured"] * n})


def test_bad_lines_of_sight_and_a_ball_that_never_moves_are_named() -> None:
    """Not a finite non-zero line of sight: one sentence naming the frame (exit 2), not least_squares'
    'Residuals are not finite' (exit 70). A ball still on the tee in every frame: no flight to fit
    (the fit used to report a 5 m/s launch with σ in the hundreds of metres)."""
    cams = {f: SimpleNamespace(intrinsics=SimpleNamespace(fx=2000.0, fy=2000.0), position=(0.0, 0.0, 2.0)) for f in range(12)}
    for bad in ((float("nan"), 0.0, -1.0), (0.0, 0.0, 0.0)):
        traj = _rows(12, (1.0, 0.0, -0.1)).with_columns(
            *[pl.when(pl.col("frame") == 4).then(v).otherwise(pl.col(c)).alias(c) for c, v in zip(("dx", "dy", "dz"), bad)])
        with pytest.raises(TrackreplayError, match="at measured frame 4 is not a finite, non-zero vector") as err:
            observations(traj, cams)
        assert err.value.exit_code == 2
    obs = observations(_rows(12, (1.0, 0.0, -0.1)), cams)
    with pytest.raises(FlightUnavailable, match="the ball does not move in the 12 measured frames"):
        fit_flight(obs)


def test_positions_in_chunks_are_the_positions_at_once(chip, monkeypatch) -> None:
    """Issue 33: ``flight_rows`` over a long log computes positions and their 1-σ a chunk of frames at a
    time (the 15 perturbed flights simulated once): the same values to the bit as all frames at once."""
    import trackreplay.replay.analysis.flight as flight

    _, _, fit = chip
    t = np.linspace(fit.observations.t[0] - 1.0, fit.t_end + 2.0, 503)  # before the launch and after the log
    whole = fit.positions(t)
    monkeypatch.setattr(flight, "POSITION_CHUNK", 37)
    chunked = fit.positions(t)
    assert all(np.array_equal(a, b) for a, b in zip(whole, chunked)) and np.isfinite(whole[0]).all()
    pos, J, phase = fit.sensitivity(t)
    assert np.array_equal(pos, whole[0]) and J.shape == (len(t), 3, len(fit.theta))
    assert np.array_equal(whole[1], np.sqrt(np.maximum(np.einsum("nap,pq,naq->na", J, fit.cov, J), 0.0)))


def _long_table() -> pl.DataFrame:
    """The golden tee shot's rows, a second golf track, and a flow track (not a ball's): three trackers' rows."""
    from trackreplay.replay.core.export import read_trajectory

    golf = read_trajectory(GOLDEN / "golf.trajectory.parquet")
    second = golf.with_columns(pl.lit(2, dtype=pl.Int64).alias("track_id"),
                               pl.when(pl.col("frame") % 3 == 0).then(pl.lit("predicted")).otherwise(pl.col("status")).alias("status"))
    flow = golf.with_columns(pl.lit("flow").alias("tracker"))
    return pl.concat([golf, second, flow]).sort("tracker", "track_id", "frame")


@pytest.mark.parametrize("suffix", [".parquet", ".csv"])
def test_flight_input_read_in_batches_is_the_whole_tables(tmp_path, suffix) -> None:
    """Issue 33: ``flight`` keeps only the ball's measured rows with a line of sight, read a few rows at a time;
    the same rows, tracks and counts as the whole table's; a file it cannot read so is left to the whole read."""
    from trackreplay.replay.analysis.flight import flight_input, read_flight_input
    from trackreplay.replay.cli.commands.flight import _is_ball
    from trackreplay.replay.core.export import read_trajectory, write_trajectory

    path = write_trajectory(_long_table(), tmp_path / f"t{suffix}")
    whole = flight_input(read_trajectory(path, keep_fill=True), _is_ball)
    for rows in (5, 7, 64, 4096):
        got = read_flight_input(path, _is_ball, rows=rows)
        assert got is not None and got.rows.equals(whole.rows, null_equal=True)
        assert got.tracks == whole.tracks == {1, 2} and got.measured == whole.measured and got.most_measured() == 1
    assert set(whole.rows["tracker"]) == {"golf"} and whole.rows.height == 2 * 17 - 6  # flow's rows left out
    # no ball tracker at all: every tracker's rows
    flows = write_trajectory(_long_table().filter(pl.col("tracker") == "flow"), tmp_path / f"f{suffix}")
    assert read_flight_input(flows, _is_ball, rows=5).rows.height == 17
    # out of canonical order (a frame twice across batches would go unseen), or a defect: read whole
    shuffled = write_trajectory(_long_table().reverse(), tmp_path / f"r{suffix}")
    assert read_flight_input(shuffled, _is_ball, rows=5) is None
    bad = write_trajectory(_long_table().with_columns(pl.when(pl.col("frame") == 40).then(pl.lit("seen"))
                                                      .otherwise(pl.col("status")).alias("status")), tmp_path / f"b{suffix}")
    assert read_flight_input(bad, _is_ball, rows=5) is None
    with pytest.raises(TrackreplayError, match="status 'seen'"):
        read_trajectory(bad)


def test_flight_rows_written_in_parts_are_the_whole_table(chip, tmp_path) -> None:
    """The fitted flight at every frame is built and written a part at a time: the same rows (Parquet) and the
    same bytes (CSV) as the whole table."""
    from trackreplay.replay.analysis.flight import flight_row_parts, flight_rows, write_flight
    from trackreplay.replay.core.export import write_trajectory

    _, _, fit = chip
    times = {int(f): int(f) * 33_333_333 for f in range(-5, 300)}  # before the launch and after the shot
    whole = flight_rows(fit, times, {})
    parts = list(flight_row_parts(fit, times, {}, chunk=37))
    assert len(parts) == 9 and pl.concat(parts).equals(whole, null_equal=True) and whole["X"].is_not_null().all()
    for suffix in (".parquet", ".csv"):
        assert write_flight(fit, times, {}, tmp_path / f"p{suffix}", chunk=37) == whole.height
        write_trajectory(whole, tmp_path / f"w{suffix}")
    assert pl.read_parquet(tmp_path / "p.parquet").equals(pl.read_parquet(tmp_path / "w.parquet"), null_equal=True)
    assert (tmp_path / "p.csv").read_bytes() == (tmp_path / "w.csv").read_bytes()


def test_flight_command_reading_and_writing_in_parts_is_the_whole_tables(tmp_path, monkeypatch, capsys) -> None:
    """The command on the golden tee shot, its trajectory read 5 rows at a time and its output written 16 frames
    at a time, against the whole table's path: the same report and the same rows."""
    import trackreplay.replay.analysis.flight as flight
    from trackreplay.replay.core.export import write_trajectory

    log = GOLDEN / "golf-teeshot-640x360.mcap"
    traj = write_trajectory(_long_table(), tmp_path / "t.parquet")
    outputs = {}
    for name in ("parts", "whole"):
        with monkeypatch.context() as m:
            if name == "parts":
                m.setattr(flight, "READ_ROWS", 5)
                m.setattr(flight, "ROWS_CHUNK", 16)
            else:
                m.setattr(flight, "read_flight_input", lambda *a, **k: None)
                m.setattr(flight, "ROWS_CHUNK", 1 << 20)
            out, report = tmp_path / f"{name}.parquet", tmp_path / f"{name}.json"
            assert main(["flight", str(traj), str(log), "--out", str(out), "--report", str(report), "--quiet"]) == 0
            outputs[name] = (pl.read_parquet(out), report.read_text(), capsys.readouterr().out.replace(str(out), "OUT"))
    (a, ra, pa), (b, rb, pb) = outputs["parts"], outputs["whole"]
    assert a.equals(b, null_equal=True) and ra == rb and pa == pb and a.height == 60
