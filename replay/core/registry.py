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
# Other names a user may give: the golf tracker follows any small fast ball (badminton, tennis, a ball in
# a hand-held clip), so ``ball`` names it too. An alias is resolved where a name comes in
# (:func:`canonical`): the trajectory, the config table ([golf]), the seed stream and the digest are the
# tracker's own name's.
ALIASES: dict[str, str] = {"ball": "golf"}


def register(spec: TrackerSpec) -> None:
    """Add a tracker: ``replay``, ``smooth``, ``export`` and the Rerun sink then run it by its name.
    Registering the same spec again does nothing; another spec under a taken name is refused."""
    global NAMES
    if not isinstance(spec, TrackerSpec):
        raise TrackreplayError(f"register takes a TrackerSpec, not {type(spec).__name__}")
    if spec.name in _BUILT_IN or spec.name in ALIASES or _REGISTERED.get(spec.name, spec) is not spec:
        raise TrackreplayError(f"a tracker named {spec.name!r} is already registered")
    if spec.name not in _REGISTERED:
        _REGISTERED[spec.name] = spec
        NAMES = (*NAMES, spec.name)


def unregister(name: str) -> None:
    """Remove a tracker :func:`register` added (the project's own stay)."""
    global NAMES
    if _REGISTERED.pop(name, None) is not None:
        NAMES = tuple(n for n in NAMES if n != name)


def canonical(name: str) -> str:
    """The tracker's own name for ``name`` (an alias resolved; any other name as given)."""
    return ALIASES.get(name, name)


def known(name: str) -> bool:
    """``name`` is a tracker's name or an alias of one."""
    return canonical(name) in NAMES


def find(name: str) -> TrackerSpec | None:
    """The declared spec of ``name`` or of the tracker it is an alias of (its view not imported), or
    None for a name nothing registered."""
    name = canonical(name)
    if name in _REGISTERED:
        return _REGISTERED[name]
    if name in _BUILT_IN:
        return importlib.import_module(_BUILT_IN[name]).SPEC
    return None


def get(name: str) -> TrackerSpec:
    """The spec of ``name`` with its view imported; an unknown name is refused with the list."""
    spec = find(name)
    if spec is None:
        raise TrackreplayError(f"unknown tracker {name!r}; available: {', '.join(NAMES)} ({aliases_text()})")
    if isinstance(spec.view, str):
        spec = dataclasses.replace(spec, view=importlib.import_module(spec.view))
    return spec


def aliases_text() -> str:
    """The aliases as a user reads them: ``ball = golf``."""
    return ", ".join(f"{alias} = {name}" for alias, name in ALIASES.items())
