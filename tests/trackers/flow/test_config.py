import pytest

from trackreplay.trackers.flow.config import FlowConfig

# Reading a FlowConfig from TOML or a dict is tested with the reader, in tests/replay/core/test_config.py.


def test_defaults_are_the_papers() -> None:
    cfg = FlowConfig()
    assert (cfg.fov, cfg.neighbourhood, cfg.derivative, cfg.epsilon) == (51, 5, 5, 0.5)
    assert 0 < cfg.alpha < 1 and cfg.online


@pytest.mark.parametrize("values", [{"fov": 50}, {"neighbourhood": 4}, {"alpha": 1.0}, {"sigmas": ()}, {"r_vel": 0}])
def test_invalid_values_are_rejected(values) -> None:
    with pytest.raises(ValueError):
        FlowConfig(**values)


def test_the_track_is_lost_on_the_lost_after_th_frame_without_moving_pixels() -> None:
    from trackreplay.trackers.lifecycle import TrackLife

    life = TrackLife(FlowConfig(lost_after=3).lifecycle)
    assert [life.missed() for _ in range(3)] == ["predicted", "predicted", "lost"]
