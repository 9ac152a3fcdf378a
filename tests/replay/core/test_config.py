"""Tracker configs from TOML, dicts and instances, flat and nested (replay/core/config.py)."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import pytest

from trackreplay.replay.core.config import config_from_dict, config_from_toml, config_to_dict, load_config
from trackreplay.schemas.errors import TrackreplayError
from trackreplay.trackers.flow.config import FlowConfig


@dataclass(frozen=True)
class Particles:
    n: int = 300
    sigma_px: float = 3.0
    spread: tuple[float, ...] = (1.0, 2.0)

    def __post_init__(self) -> None:
        if self.n < 1:
            raise ValueError(f"n must be positive, not {self.n}")


@dataclass(frozen=True)
class Lut:
    bins: int = 32
    names: tuple[str, ...] = ("grass", "sky")


@dataclass(frozen=True)
class Nested:
    particles: Particles = field(default_factory=Particles)
    lut: Lut | None = field(default_factory=Lut)
    lost_after: int = 10


def test_from_toml_reads_a_flow_table_lists_become_tuples(tmp_path: Path) -> None:
    path = tmp_path / "flow.toml"
    path.write_text("[flow]\nfov = 61\ncond_max = 30\nsigmas = [1.0, 0.0]\ninit_center = [10, 20]\n")
    cfg = config_from_toml(FlowConfig, path, table="flow")
    assert cfg.fov == 61 and cfg.cond_max == 30 and cfg.sigmas == (1.0, 0.0) and cfg.init_center == (10, 20)
    hash(cfg)


def test_nested_tables_build_nested_configs(tmp_path: Path) -> None:
    path = tmp_path / "c.toml"
    path.write_text("[golf]\nlost_after = 4\n[golf.particles]\nn = 500\nspread = [[1, 2], [3]]\n[golf.lut]\nbins = 16\n")
    cfg = config_from_toml(Nested, path, table="golf")
    assert cfg == Nested(Particles(n=500, spread=((1, 2), (3,))), Lut(bins=16), lost_after=4)
    hash(cfg)
    assert config_from_dict(Nested, config_to_dict(cfg)) == cfg
    assert config_to_dict(cfg)["particles"]["spread"] == [[1, 2], [3]]


def test_an_unknown_nested_key_names_the_file_and_the_key_path(tmp_path: Path) -> None:
    path = tmp_path / "c.toml"
    path.write_text("[golf.particles]\nnn = 5\n")
    with pytest.raises(TrackreplayError) as err:
        config_from_toml(Nested, path, table="golf")
    assert str(err.value) == f"{path}: unknown key golf.particles.nn; known: n, sigma_px, spread"


def test_an_unknown_top_level_key_without_a_table(tmp_path: Path) -> None:
    path = tmp_path / "bad.toml"
    path.write_text("epsilonn = 0.5\n")
    with pytest.raises(TrackreplayError, match=rf"^{path}: unknown key epsilonn; known: alpha, cond_max"):
        config_from_toml(FlowConfig, path, table="flow")


def test_invalid_values_name_the_table(tmp_path: Path) -> None:
    with pytest.raises(TrackreplayError, match=r"^cfg: invalid particles \(n must be positive, not 0\)$"):
        config_from_dict(Nested, {"particles": {"n": 0}}, "cfg")
    with pytest.raises(TrackreplayError, match="particles must be a table of keys"):
        config_from_dict(Nested, {"particles": 5}, "cfg")


@pytest.mark.parametrize("values", [{"fov": 50}, {"neighbourhood": 4}, {"alpha": 1.0}, {"sigmas": []}, {"r_vel": 0}])
def test_invalid_flow_values_are_one_sentence_errors(values) -> None:
    with pytest.raises(TrackreplayError, match="^FlowConfig config \\(--set or a dict\\): invalid FlowConfig"):
        load_config(FlowConfig, values)


def test_load_config_accepts_none_an_instance_a_dict_and_a_path(tmp_path: Path) -> None:
    path = tmp_path / "c.toml"
    path.write_text("[particles]\nsigma_px = 2.5\n")
    assert load_config(Nested) == Nested()
    given = Nested(lost_after=3)
    assert load_config(Nested, given) is given
    assert load_config(Nested, {"particles": {"sigma_px": 2.5}}) == Nested(Particles(sigma_px=2.5))
    assert load_config(Nested, path, table="golf") == Nested(Particles(sigma_px=2.5))
    assert load_config(Nested, str(path)) == Nested(Particles(sigma_px=2.5))
    with pytest.raises(TrackreplayError, match="must be given as None, a Nested, a dict or a TOML path, not FlowConfig"):
        load_config(Nested, FlowConfig())


def test_missing_or_malformed_files_are_one_sentence_errors(tmp_path: Path) -> None:
    with pytest.raises(TrackreplayError, match="does not exist"):
        load_config(FlowConfig, tmp_path / "none.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("fov = \n")
    with pytest.raises(TrackreplayError, match="is not valid TOML"):
        load_config(FlowConfig, bad)


@pytest.mark.parametrize("values, message", [
    ({"particles": {"n": 2.5}}, "particles.n must be an integer, not 2.5"),
    ({"particles": {"n": True}}, "particles.n must be an integer, not True"),
    ({"particles": {"sigma_px": "6"}}, "particles.sigma_px must be a number, not '6'"),
])
def test_a_value_of_the_wrong_type_names_its_key(values, message) -> None:
    """One sentence naming the key, not a TypeError deep in a tracker (a float particle count
    reached numpy as an array size)."""
    with pytest.raises(TrackreplayError, match=f"^cfg: {message}$"):
        config_from_dict(Nested, values, "cfg")


def test_an_integer_is_a_number() -> None:
    assert config_from_dict(Nested, {"particles": {"sigma_px": 6}}, "cfg").particles.sigma_px == 6


def _numeric_paths(cls, prefix=()):
    """Every number (or list of numbers) key of a config dataclass, nested tables followed."""
    import dataclasses
    import typing

    hints = typing.get_type_hints(cls)
    for f in dataclasses.fields(cls):
        default = f.default_factory() if f.default is dataclasses.MISSING else f.default
        if dataclasses.is_dataclass(default):
            yield from _numeric_paths(type(default), prefix + (f.name,))
        elif isinstance(default, float) or (isinstance(default, tuple) and default and isinstance(default[0], float)):
            yield prefix + (f.name,), default, hints[f.name]


def _nested(path, value):
    out = value
    for key in reversed(path):
        out = {key: out}
    return out


@pytest.mark.parametrize("tracker", ["flow", "golf", "colorpf", "groups"])
def test_no_float_key_takes_nan_or_infinity(tracker) -> None:
    """A review found nan/inf passing every check and crashing replays deep inside numpy/OpenCV (exit
    70, one a segfault): each float key of every tracker now refuses them by name."""
    from trackreplay.replay.core.registry import get

    cls = get(tracker).config_cls
    paths = list(_numeric_paths(cls))
    assert len(paths) > 5
    for path, default, _ in paths:
        for bad in (float("nan"), float("inf"), float("-inf")):
            value = tuple(bad for _ in default) if isinstance(default, tuple) else bad
            with pytest.raises(TrackreplayError, match=f"{'.'.join(path)} must be a finite number"):
                config_from_dict(cls, _nested(path, value), "c.toml")


@pytest.mark.parametrize("tracker,values", [
    ("golf", {"lut": {"hist_bins": -1}}), ("golf", {"reinit": {"parabola_history": -1}}),
    ("golf", {"blobs": {"shape_area_px": -1.0}}), ("groups", {"klt": {"quality": -1.0}}),
    ("groups", {"klt": {"min_distance": 1e12}}), ("groups", {"klt": {"win": -1}}), ("groups", {"klt": {"levels": -1}}),
    ("groups", {"background": {"frames": -1}}),
])
def test_out_of_range_values_found_by_review_are_refused(tracker, values) -> None:
    from trackreplay.replay.core.registry import get

    with pytest.raises(TrackreplayError, match="c.toml: invalid"):
        config_from_dict(get(tracker).config_cls, values, "c.toml")
