"""The golf ball's 3-D flight fitted to lines of sight (issue 13)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import polars as pl
import pytest

from trackreplay.recorder.synth.golf.flight import BallModel, Launch, simulate_shot
from trackreplay.replay.cli import main
from trackreplay.replay.flight import FlightConfig, FlightUnavailable, Observations, fit_flight, observations

GOLDEN = Path(__file__).resolve().parents[1] / "golden"


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
    assert "3-D not available" in capsys.readouterr().err
