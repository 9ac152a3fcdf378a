"""`trackreplay config TRACKER`: commented TOML that reads back into the same config."""

from __future__ import annotations

import tomllib

import pytest

from trackreplay.replay.core import registry
from trackreplay.replay.cli.main import main
from trackreplay.replay.core.config import load_config
from trackreplay.replay.core.config_toml import config_toml, field_comments


@pytest.mark.parametrize("tracker", registry.NAMES)
def test_default_config_round_trips(tracker: str, tmp_path, capsys) -> None:
    entry = registry.get(tracker)
    assert main(["config", tracker]) == 0
    text = capsys.readouterr().out
    assert f"[{tracker}]" in text
    data = tomllib.loads(text)  # valid TOML
    path = tmp_path / "c.toml"
    path.write_text(text)
    assert load_config(entry.config_cls, path, table=tracker) == entry.config_cls()
    assert data[tracker]


def test_comments_come_from_the_source() -> None:
    from trackreplay.trackers.flow.config import FlowConfig

    comments = field_comments(FlowConfig)
    assert comments["epsilon"].startswith("px/frame (eq. 11")
    text = config_toml(FlowConfig(), "flow")
    assert "epsilon = 0.5  # px/frame (eq. 11" in text
    assert "# init_center =" in text  # None: written commented out, the default stays


def test_a_file_is_resolved_over_the_defaults(tmp_path, capsys) -> None:
    path = tmp_path / "c.toml"
    path.write_text("[flow]\nepsilon = 0.75\n")
    assert main(["config", "flow", "--config", str(path)]) == 0
    assert "epsilon = 0.75" in capsys.readouterr().out


def test_another_trackers_table_beside_this_ones_is_refused(tmp_path) -> None:
    """A review concatenated `config groups` and `config flow`: the [flow] table was silently ignored."""
    import pytest

    from trackreplay.replay.core.config import load_config
    from trackreplay.schemas.errors import TrackreplayError
    from trackreplay.trackers.groups.config import GroupsConfig

    path = tmp_path / "both.toml"
    path.write_text("[groups]\nrate_hz = 24.0\n\n[flow]\nfovv = 3\n")
    with pytest.raises(TrackreplayError, match=r"'flow' beside the \[groups\] table would be ignored"):
        load_config(GroupsConfig, path, table="groups")
    path.write_text("[groups]\nrate_hz = 24.0\n\n[groups.grouping]\nradius_m = 0.8\n")
    assert load_config(GroupsConfig, path, table="groups").grouping.radius_m == 0.8


def test_batch_sets_over_a_file_refuse_another_trackers_table_too(tmp_path) -> None:
    """A code review: batch/diff --set read the file on their own and dropped the other table silently."""
    import pytest

    from trackreplay.replay.runs.batch_config import apply_sets
    from trackreplay.schemas.errors import TrackreplayError

    path = tmp_path / "both.toml"
    path.write_text("[golf]\nmax_predicted_frames = 4\n\n[colorpf]\nn_particles = 10\n")
    with pytest.raises(TrackreplayError, match=r"'colorpf' beside the \[golf\] table would be ignored"):
        apply_sets("golf", path, {"particles.n": 500})
    path.write_text("[golf]\nmax_predicted_frames = 4\n")
    assert apply_sets("golf", path, {"particles.n": 500}) == {"max_predicted_frames": 4, "particles": {"n": 500}}
