"""The notebook API: ``trackreplay.replay_log`` with every form of config, and the CLI's digest."""

from __future__ import annotations

import json
from pathlib import Path

import polars as pl
import pytest

import trackreplay
from trackreplay.replay.cli.main import main
from trackreplay.schemas.errors import TrackreplayError
from trackreplay.trackers.flow.config import FlowConfig

GOLDEN = Path(__file__).parent / "golden"
LOG = GOLDEN / "flow-sim1-24f.mcap"
EXPECTED = json.loads((GOLDEN / "expected.json").read_text())


def cli_digest(tmp_path: Path, *extra: str) -> str:
    summary = tmp_path / "summary.json"
    assert main(["replay", str(LOG), "--tracker", "flow", "--quiet", "--summary", str(summary), *extra]) == 0
    return json.loads(summary.read_text())["digest"]


def test_defaults_give_the_golden_digest_and_a_polars_trajectory() -> None:
    result = trackreplay.replay_log(LOG, "flow")
    assert result.digest == EXPECTED["flow"]["digest"]
    assert isinstance(result.trajectory, pl.DataFrame) and result.trajectory.height == EXPECTED["flow"]["frames"]
    assert result.trajectory["tracker"].unique().to_list() == ["flow"]


def test_dict_toml_and_dataclass_configs_agree_with_the_cli(tmp_path: Path) -> None:
    toml = tmp_path / "c.toml"
    toml.write_text("[flow]\nfov = 41\nsigmas = [1.0, 0.0]\n")
    from_dict = trackreplay.replay_log(LOG, "flow", config={"fov": 41, "sigmas": [1.0, 0.0]})
    from_toml = trackreplay.replay_log(LOG, "flow", config=toml)
    from_path_string = trackreplay.replay_log(str(LOG), "flow", config=str(toml))
    from_dataclass = trackreplay.replay_log(LOG, "flow", config=FlowConfig(fov=41, sigmas=(1.0, 0.0)))
    digests = {r.digest for r in (from_dict, from_toml, from_path_string, from_dataclass)}
    assert digests == {cli_digest(tmp_path, "--config", str(toml))}
    assert digests != {EXPECTED["flow"]["digest"]}  # the config took effect
    assert from_dict.trajectory.equals(from_dataclass.trajectory)


def test_seed_window_and_rrd_pass_through(tmp_path: Path) -> None:
    rrd = tmp_path / "out.rrd"
    result = trackreplay.replay_log(LOG, "flow", seed=3, start_s=0.1, end_s=0.4, rrd=rrd)
    assert result.digest == cli_digest(tmp_path, "--seed", "3", "--start", "0.1", "--end", "0.4")
    assert 0 < result.frames < EXPECTED["flow"]["frames"] and rrd.stat().st_size > 0
    assert result.seed == 3


def test_a_bad_config_key_is_a_one_sentence_error() -> None:
    with pytest.raises(TrackreplayError, match=r"^flow config \(--set or a dict\): unknown key fovv; known: "):
        trackreplay.replay_log(LOG, "flow", config={"fovv": 41})


def test_the_api_is_on_the_package_without_importing_it_eagerly() -> None:
    import subprocess
    import sys

    code = "import sys, trackreplay; assert 'polars' not in sys.modules; trackreplay.replay_log; assert 'polars' in sys.modules"
    subprocess.run([sys.executable, "-c", code], check=True, timeout=120)
    assert {"replay_log", "iter_steps", "ReplayStep", "__version__"} <= set(dir(trackreplay))
