"""Shared fixtures: a short synthetic colour-PF log per scene, written once per session."""

from __future__ import annotations

from pathlib import Path

import pytest

from trackreplay.recorder.synth.colorpf import ColorPfSceneConfig, write_colorpf_scene

FRAMES = 40  # walking frames: keeps each replay well under a second at 720x480


@pytest.fixture(scope="session")
def scene_log(tmp_path_factory):
    made: dict[str, Path] = {}

    def make(scene: str, seed: int = 0) -> Path:
        key = f"{scene}-{seed}"
        if key not in made:
            path = tmp_path_factory.mktemp("colorpf") / f"{key}.mcap"
            write_colorpf_scene(path, ColorPfSceneConfig(scene=scene, seed=seed, frames=FRAMES))
            made[key] = path
        return made[key]

    return make
