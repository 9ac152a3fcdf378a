"""Synthetic scenes as corpus sources: ``synth = "golf-teeshot"`` in a manifest is ``trackreplay synth``
with the scene's config fields given as ``synth_options`` (each scene writes its own truth and marks)."""

from __future__ import annotations

from dataclasses import fields
from pathlib import Path
from typing import Any

from trackreplay.recorder.synth.colorpf import SCENES as COLORPF_SCENES
from trackreplay.recorder.synth.flow_sims import SCENES as FLOW_SCENES
from trackreplay.recorder.synth.golf.scene import SCENE as GOLF_SCENE
from trackreplay.recorder.synth.groups.scene import SCENES as GROUP_SCENES
from trackreplay.schemas.errors import SourceError

SCENE_NAMES = (*FLOW_SCENES, GOLF_SCENE, *COLORPF_SCENES, *GROUP_SCENES)


def _config_cls(scene: str) -> type:
    if scene in FLOW_SCENES:
        from trackreplay.recorder.synth.flow_sims import FlowSimConfig

        return FlowSimConfig
    if scene == GOLF_SCENE:
        from trackreplay.recorder.synth.golf.scene import GolfSceneConfig

        return GolfSceneConfig
    if scene in COLORPF_SCENES:
        from trackreplay.recorder.synth.colorpf import ColorPfSceneConfig

        return ColorPfSceneConfig
    from trackreplay.recorder.synth.groups.scene import GroupSceneConfig

    return GroupSceneConfig


def scene_config(scene: str, seed: int, options: dict[str, Any], where: str) -> Any:
    """The scene's config dataclass; an unknown option is refused with the ones the scene takes."""
    if scene not in SCENE_NAMES:
        raise SourceError(f"{where}: synth {scene!r} is not a scene; scenes: {', '.join(SCENE_NAMES)}")
    cls = _config_cls(scene)
    known = tuple(f.name for f in fields(cls) if f.name not in ("scene", "seed"))
    unknown = sorted(set(options) - set(known))
    if unknown:
        raise SourceError(f"{where}: synth_options {', '.join(unknown)} are not settings of {scene}; "
                          f"it takes: {', '.join(known)}")
    values = {k: tuple(v) if isinstance(v, list) else v for k, v in options.items()}
    if "scene" in {f.name for f in fields(cls)}:
        values["scene"] = scene
    try:
        cfg = cls(seed=seed, **values)
        if hasattr(cfg, "validate"):
            cfg.validate()
    except (TypeError, ValueError) as err:
        raise SourceError(f"{where}: synth_options of {scene}: {err}") from None
    return cfg


def write_scene(out: Path, scene: str, seed: int, options: dict[str, Any], where: str) -> None:
    """Render the scene to ``out`` (as ``trackreplay synth SCENE OUT --seed SEED`` with the options)."""
    cfg = scene_config(scene, seed, options, where)
    if scene in FLOW_SCENES:
        from trackreplay.recorder.synth.flow_sims import write_flow_sim

        write_flow_sim(out, cfg)
    elif scene == GOLF_SCENE:
        from trackreplay.recorder.synth.golf.scene import write_golf_teeshot

        write_golf_teeshot(out, cfg)
    elif scene in COLORPF_SCENES:
        from trackreplay.recorder.synth.colorpf import write_colorpf_scene

        write_colorpf_scene(out, cfg)
    else:
        from trackreplay.recorder.synth.groups.scene import write_group_scene

        write_group_scene(out, cfg)
