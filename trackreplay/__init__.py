"""trackreplay: record, replay deterministically, inspect in Rerun, export trajectories.

The repository's top-level folders ``schemas/ recorder/ trackers/ replay/`` install as
``trackreplay.schemas`` … ``trackreplay.replay`` (``package_dir`` in ``setup.py``), so no bare
top-level module of those names is installed next to other packages.

Python API (imported on first use, so ``import trackreplay`` stays light)::

    result = trackreplay.replay_log("clip.mcap", "flow", config={"fov": 41})
    result.trajectory, result.digest
    for step in trackreplay.iter_steps(trackreplay.ReplayRequest(log="clip.mcap", tracker="flow")):
        step.frame, step.states, step.intermediates
    log = trackreplay.open_log("clip.mcap")
    log.frames[0], log.truth, log.marks
    trackreplay.evaluate("clip.mcap", result)            # the metrics as a DataFrame (or a corpus .toml)
    trackreplay.export(trackreplay.smooth(result, "clip.mcap"), "smooth.parquet")
"""

from __future__ import annotations

from importlib import import_module
from importlib.metadata import PackageNotFoundError, version
from typing import Any

try:
    __version__ = version("trackreplay")
except PackageNotFoundError:  # a source tree that was never installed
    __version__ = "0+unknown"

_API = {
    "replay_log": "trackreplay.replay.core.api",
    "iter_steps": "trackreplay.replay.core.engine",
    "ReplayRequest": "trackreplay.replay.core.engine",
    "ReplayResult": "trackreplay.replay.core.engine",
    "ReplayStep": "trackreplay.replay.core.engine",
    "open_log": "trackreplay.replay.core.api",
    "OpenedLog": "trackreplay.replay.core.api",
    "export": "trackreplay.replay.core.api",
    "evaluate": "trackreplay.replay.runs.notebook",
    "smooth": "trackreplay.replay.runs.notebook",
}
__all__ = ["__version__", *_API]


def __getattr__(name: str) -> Any:
    if name in _API:
        return getattr(import_module(_API[name]), name)
    raise AttributeError(f"module 'trackreplay' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(__all__)
