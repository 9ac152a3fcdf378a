"""trackreplay: record, replay deterministically, inspect in Rerun, export trajectories.

The repository's top-level folders ``schemas/ recorder/ trackers/ replay/`` install as
``trackreplay.schemas`` … ``trackreplay.replay`` (see ``[tool.setuptools.package-dir]``), so no
bare top-level module of those names is installed next to other packages.
"""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("trackreplay")
except PackageNotFoundError:  # a source tree that was never installed
    __version__ = "0+unknown"
