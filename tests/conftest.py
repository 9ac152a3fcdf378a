"""Shared fixtures: small synthetic logs written by the project itself."""

from __future__ import annotations

from pathlib import Path

import pytest

from recorder.synth.flow_sims import FlowSimConfig, write_flow_sim


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
def tracker_logs(short_sim: Path) -> dict[str, Path]:
    """A short synthetic log per registered tracker."""
    return {"flow": short_sim}
