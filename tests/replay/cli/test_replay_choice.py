"""`replay`: the tracker is chosen from the marks (and said), `--set` overrides the config, and a
config file for another tracker is named as such."""

import json
from pathlib import Path

import pytest

from trackreplay.replay.cli.main import main


def _digest(capsys: pytest.CaptureFixture, argv: list[str]) -> str:
    assert main(argv) == 0
    return capsys.readouterr().out.split("digest ")[-1].strip()


def test_the_tracker_follows_the_marks_and_is_said(short_sim: Path, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    summary = tmp_path / "s.json"
    assert main(["replay", str(short_sim), "--quiet", "--summary", str(summary)]) == 0
    assert "tracker flow (the log's marks are labelled target" in capsys.readouterr().err
    assert json.loads(summary.read_text())["tracker"] == "flow"
    balls = tmp_path / "balls.mcap"
    assert main(["annotate", str(short_sim), "--frame", "0", "--box", "10,10,8,8", "--label", "ball", "--out", str(balls)]) == 0
    capsys.readouterr()
    assert main(["replay", str(balls), "--quiet"]) == 2  # flow reads only `target`; the others read every label
    err = capsys.readouterr().err.strip()
    assert "'ball'" in err and "give --tracker (flow, golf" in err and "\n" not in err


def test_set_overrides_the_config(short_sim: Path, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    base = ["replay", str(short_sim), "--tracker", "flow", "--quiet"]
    default = _digest(capsys, base)
    cfg = tmp_path / "flow.toml"
    cfg.write_text("[flow]\nr_pos = 50.0\npyramid_levels = 1\n")
    from_file = _digest(capsys, [*base, "--config", str(cfg)])
    assert from_file != default
    assert _digest(capsys, [*base, "--set", "flow.r_pos=50.0", "--set", "pyramid_levels=1"]) == from_file
    assert _digest(capsys, [*base, "--config", str(cfg), "--set", "r_pos=50.0"]) == from_file  # over the file's
    assert main([*base, "--set", "r_pos=1", "--set", "flow.r_pos=2"]) == 2
    assert "--set flow.r_pos given twice" in capsys.readouterr().err


def test_a_file_for_another_tracker_is_named(short_sim: Path, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    cfg = tmp_path / "golf.toml"
    cfg.write_text("[golf.particles]\nn = 100\n")
    assert main(["replay", str(short_sim), "--tracker", "flow", "--config", str(cfg), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert "golf.toml: this file configures golf, not the flow tracker; give --tracker golf" in err and "unknown key" not in err
