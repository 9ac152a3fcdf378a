"""`synth --background PHOTO` needs scikit-image: an extra of its own, named in the one-sentence refusal."""

import sys
import tomllib
from pathlib import Path

import pytest

from trackreplay.replay.cli.main import main

ROOT = Path(__file__).resolve().parents[3]


def test_photos_without_scikit_image_name_the_extra(monkeypatch: pytest.MonkeyPatch, tmp_path: Path,
                                                    capsys: pytest.CaptureFixture) -> None:
    monkeypatch.setitem(sys.modules, "skimage", None)  # (an import of it then raises ImportError)
    monkeypatch.setitem(sys.modules, "skimage.data", None)
    out = tmp_path / "s.mcap"
    assert main(["synth", "flow-sim1", str(out), "--background", "camera", "--frames", "2"]) == 2
    err = capsys.readouterr().err.strip()
    assert "pip install 'trackreplay[scenes]'" in err and "\n" not in err and not out.exists()


def test_the_scenes_extra_installs_scikit_image() -> None:
    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["optional-dependencies"]
    assert any(dep.startswith("scikit-image") for dep in extras["scenes"])
    assert "'.[scenes]'" in (ROOT / "README.md").read_text()
