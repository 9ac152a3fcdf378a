"""The terminal holds our sentences only: Rerun's Rust log lines and Ray's start-up warnings (its token
authentication notice) are switched off in the CLI process unless --debug."""

import logging
import os
import subprocess
import sys
from pathlib import Path

import pytest

from trackreplay.replay.cli.main import QUIET_LOGGERS, main

GOLDEN = Path(__file__).resolve().parents[2] / "golden"


def test_a_verb_quiets_the_libraries_and_restores_the_loggers(monkeypatch, capsys) -> None:
    monkeypatch.delenv("RUST_LOG", raising=False)
    before = {name: logging.getLogger(name).level for name in QUIET_LOGGERS}
    seen = {}

    def spy(args):
        seen["rust"] = os.environ.get("RUST_LOG")
        seen["levels"] = {name: logging.getLogger(name).level for name in QUIET_LOGGERS}
        return 0

    import trackreplay.replay.cli.commands.config_cmd as config_cmd

    monkeypatch.setattr(config_cmd, "run", spy)
    assert main(["config", "flow"]) == 0
    assert seen["rust"] == "off" and set(seen["levels"].values()) == {logging.ERROR}
    assert {name: logging.getLogger(name).level for name in QUIET_LOGGERS} == before


def test_debug_and_a_users_rust_log_are_left_alone(monkeypatch) -> None:
    import trackreplay.replay.cli.commands.config_cmd as config_cmd

    seen = {}
    monkeypatch.setattr(config_cmd, "run", lambda args: seen.setdefault("rust", os.environ.get("RUST_LOG")) and 0)
    monkeypatch.delenv("RUST_LOG", raising=False)
    assert main(["--debug", "config", "flow"]) == 0 and seen["rust"] is None
    seen.clear()
    monkeypatch.setenv("RUST_LOG", "info")
    assert main(["config", "flow"]) == 0 and seen["rust"] == "info"


@pytest.mark.slow
def test_a_viewer_that_never_answers_is_one_sentence(tmp_path: Path) -> None:
    """Measured before: four coloured Rerun lines (WARN re_grpc_client, ERROR re_sdk) after our sentence."""
    env = {k: v for k, v in os.environ.items() if k != "RUST_LOG"}
    cmd = [sys.executable, "-m", "trackreplay.replay.cli.main", "replay", str(GOLDEN / "flow-sim1-24f.mcap"),
           "--tracker", "flow", "--quiet", "--connect", "rerun+http://127.0.0.1:9/proxy"]
    run = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=120)
    assert run.returncode == 5
    assert run.stderr.startswith("trackreplay: error: cannot stream to the Rerun viewer") and run.stderr.count("\n") == 1


@pytest.mark.slow
def test_batch_on_ray_prints_no_token_warning(tmp_path: Path) -> None:
    pytest.importorskip("ray")
    env = {k: v for k, v in os.environ.items() if not k.startswith("RAY_AUTH")}
    cmd = [sys.executable, "-m", "trackreplay.replay.cli.main", "batch", str(GOLDEN / "flow-sim1-24f.mcap"),
           "--tracker", "flow", "--seeds", "0", "--out", str(tmp_path / "b"), "--workers", "1"]
    run = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=300)
    assert run.returncode == 0, run.stderr
    assert "WARNING" not in run.stderr and "Token authentication" not in run.stderr
