"""Tracker names -> their declared :class:`~trackreplay.trackers.base.TrackerSpec`.

The project's trackers are listed by package (each exports ``SPEC``) and imported on first use; a
third-party tracker is added with :func:`register`. :func:`get` returns the spec with its Rerun view
imported (a spec may name it as a dotted module, since trackers do not import the replay's views).
"""

from __future__ import annotations

import dataclasses
import importlib

from trackreplay.schemas.errors import TrackreplayError
from trackreplay.trackers.base import TrackerSpec

_BUILT_IN: dict[str, str] = {name: f"trackreplay.trackers.{name}" for name in ("flow", "golf", "groups", "colorpf")}
_REGISTERED: dict[str, TrackerSpec] = {}
NAMES: tuple[str, ...] = tuple(_BUILT_IN)


def register(spec: TrackerSpec) -> None:
    """Add a tracker: ``replay``, ``smooth``, ``export`` and the Rerun sink then run it by its name.
    Registering the same spec again does nothing; another spec under a taken name is refused."""
    global NAMES
    if not isinstance(spec, TrackerSpec):
        raise TrackreplayError(f"register takes a TrackerSpec, not {type(spec).__name__}")
    if spec.name in _BUILT_IN or _REGISTERED.get(spec.name, spec) is not spec:
        raise TrackreplayError(f"a tracker named {spec.name!r} is already registered")
    if spec.name not in _REGISTERED:
        _REGISTERED[spec.name] = spec
        NAMES = (*NAMES, spec.name)


def unregister(name: str) -> None:
    """Remove a tracker :func:`register` added (the project's own stay)."""
    global NAMES
    if _REGISTERED.pop(name, None) is not None:
        NAMES = tuple(n for n in NAMES if n != name)


def find(name: str) -> TrackerSpec | None:
    """The declared spec of ``name`` (its view not imported), or None for a name nothing registered."""
    if name in _REGISTERED:
        return _REGISTERED[name]
    if name in _BUILT_IN:
        return importlib.import_module(_BUILT_IN[name]).SPEC
    return None


def get(name: str) -> TrackerSpec:
    """The spec of ``name`` with its view imported; an unknown name is refused with the list."""
    spec = find(name)
    if spec is None:
        raise TrackreplayError(f"unknown tracker {name!r}; available: {', '.join(NAMES)}")
    if isinstance(spec.view, str):
        spec = dataclasses.replace(spec, view=importlib.import_module(spec.view))
    return spec
