"""Issue 33, defect 4: TOML configs that ended in an internal error, or cost gigabytes: numbers far
beyond any parameter's range (trackers turn some into sizes), nesting 500 deep, a 50 MB line."""

import resource
from pathlib import Path

import pytest

from trackreplay.replay.core import registry
from trackreplay.replay.core.config import MAX_TOML_LINE, config_to_dict, load_config, read_toml
from trackreplay.schemas.errors import TrackreplayError


@pytest.mark.parametrize("value", ["1e308", "1e-300", "-1e308", "10000000000000000000000"])
def test_a_number_far_out_of_range_is_refused_with_its_key(tmp_path: Path, value: str) -> None:
    path = tmp_path / "golf.toml"
    path.write_text(f"[golf.contrast]\nregistration_px = {value}\n")
    with pytest.raises(TrackreplayError, match=rf"golf.toml: golf.contrast.registration_px = \S+ is out of range"):
        load_config(registry.get("golf").config_cls, path, table="golf")


@pytest.mark.parametrize("name", ["flow", "golf", "groups", "colorpf"])
def test_every_default_is_within_range(name: str) -> None:
    entry = registry.get(name)
    assert load_config(entry.config_cls, config_to_dict(entry.config_cls()), table=name) == entry.config_cls()


def test_toml_nested_500_deep_names_file_and_line(tmp_path: Path) -> None:
    path = tmp_path / "deep.toml"
    path.write_text("[flow]\nfov = 51\nx = " + "[" * 500 + "]" * 500 + "\n")
    with pytest.raises(TrackreplayError, match=rf"^{path}:3: nested more than 32 deep$"):
        read_toml(path)


def test_a_50mb_toml_line_is_refused_in_bounded_memory(tmp_path: Path) -> None:
    path = tmp_path / "long.toml"
    with open(path, "w") as fh:
        fh.write("[flow]\n# " + "x" * 50_000_000 + "\nfov = 51\n")
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    with pytest.raises(TrackreplayError, match=rf"^{path}:2: a line longer than {MAX_TOML_LINE} bytes"):
        read_toml(path)
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before < 20_000  # KB: the line is never held
