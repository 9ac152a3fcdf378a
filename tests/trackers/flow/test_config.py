import pytest

from trackreplay.schemas.errors import TrackreplayError
from trackreplay.trackers.flow.config import FlowConfig


def test_defaults_are_the_papers() -> None:
    cfg = FlowConfig()
    assert (cfg.fov, cfg.neighbourhood, cfg.derivative, cfg.epsilon) == (51, 5, 5, 0.5)
    assert 0 < cfg.alpha < 1 and cfg.online


def test_from_toml_reads_a_flow_table(tmp_path) -> None:
    path = tmp_path / "flow.toml"
    path.write_text("[flow]\nfov = 61\ncond_max = 30\nsigmas = [1.0, 0.0]\ninit_center = [10, 20]\n")
    cfg = FlowConfig.from_toml(path)
    assert cfg.fov == 61 and cfg.cond_max == 30 and cfg.sigmas == (1.0, 0.0) and cfg.init_center == (10, 20)
    hash(cfg)


def test_unknown_keys_are_one_sentence_errors(tmp_path) -> None:
    with pytest.raises(TrackreplayError, match="unknown FlowConfig key.*fovv"):
        FlowConfig.from_dict({"fovv": 51})
    path = tmp_path / "bad.toml"
    path.write_text("epsilonn = 0.5\n")
    with pytest.raises(TrackreplayError, match=str(path)):
        FlowConfig.from_toml(path)


@pytest.mark.parametrize("values", [{"fov": 50}, {"neighbourhood": 4}, {"alpha": 1.0}, {"sigmas": []}, {"r_vel": 0}])
def test_invalid_values_are_rejected(values) -> None:
    with pytest.raises(TrackreplayError):
        FlowConfig.from_dict(values)
