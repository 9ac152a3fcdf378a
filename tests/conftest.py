"""Shared fixtures: small synthetic logs written by the project itself."""

from __future__ import annotations

from pathlib import Path

import pytest

from trackreplay.recorder.synth.flow_sims import FlowSimConfig, write_flow_sim


@pytest.fixture(scope="session")
def flow_sim1(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("logs") / "flow-sim1.mcap"
    write_flow_sim(path, FlowSimConfig(scene="flow-sim1"))
    return path


@pytest.fixture(scope="session")
def short_sim(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """flow-sim1 cut to 12 frames: quick end-to-end runs."""
    path = tmp_path_factory.mktemp("logs") / "short.mcap"
    write_flow_sim(path, FlowSimConfig(scene="flow-sim1", frames=12))
    return path


@pytest.fixture(scope="session")
def golf_short(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Three seconds of a small synthetic tee shot (640x360) with encoders and marked balls."""
    from trackreplay.recorder.synth.golf.flight import Launch
    from trackreplay.recorder.synth.golf.operator import OperatorConfig
    from trackreplay.recorder.synth.golf.scene import GolfSceneConfig, write_golf_teeshot

    path = tmp_path_factory.mktemp("logs") / "golf-short.mcap"
    write_golf_teeshot(path, GolfSceneConfig(
        width=640, height=360, seed=3, duration=3.0,
        launch=Launch(speed=32.0, elevation=24.0, azimuth=0.0, backspin_rpm=7000.0),
        operator=OperatorConfig(size_tee_px=20.0, size_launch_px=7.0, size_landing_px=14.0, size_ground_px=16.0),
    ))
    return path


GOLDEN = Path(__file__).resolve().parent / "golden"


@pytest.fixture(scope="session")
def tracker_logs(short_sim: Path, golf_short: Path) -> dict[str, Path]:
    """A short synthetic log per registered tracker (the small golden scenes for colorpf and groups)."""
    return {"flow": short_sim, "golf": golf_short,
            "colorpf": GOLDEN / "colorpf-approach-320x240.mcap", "groups": GOLDEN / "groups-crossing-320x240.mcap"}
