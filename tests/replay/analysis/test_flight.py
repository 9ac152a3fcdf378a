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
