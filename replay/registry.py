"""Tracker names -> (config class, tracker class, Rerun view)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

from trackreplay.schemas.errors import TrackreplayError


@dataclass(frozen=True)
class TrackerEntry:
    name: str
    config_cls: type
    tracker_cls: type
    view: Any  # module with blueprint(name) and log(rec, frame, intermediates, states)
    # Tracks every object in view at once: evaluated with multi-object metrics (MOTA, IDF1), since the
    # single-object ones pair one track with one ground-truth object.
    multi_object: bool = False


def _flow() -> TrackerEntry:
    from trackreplay.replay.views import flow as view
    from trackreplay.trackers.flow.config import FlowConfig
    from trackreplay.trackers.flow.tracker import FlowTracker

    return TrackerEntry("flow", FlowConfig, FlowTracker, view)


def _golf() -> TrackerEntry:
    from trackreplay.replay.views import golf as view
    from trackreplay.trackers.golf.config import GolfConfig
    from trackreplay.trackers.golf.tracker import GolfTracker

    return TrackerEntry("golf", GolfConfig, GolfTracker, view)


def _colorpf() -> TrackerEntry:
    from trackreplay.replay.views import colorpf as view
    from trackreplay.trackers.colorpf.config import ColorPfConfig
    from trackreplay.trackers.colorpf.tracker import ColorPfTracker

    return TrackerEntry("colorpf", ColorPfConfig, ColorPfTracker, view)


def _groups() -> TrackerEntry:
    from trackreplay.replay.views import groups as view
    from trackreplay.trackers.groups.config import GroupsConfig
    from trackreplay.trackers.groups.tracker import GroupTracker

    return TrackerEntry("groups", GroupsConfig, GroupTracker, view, multi_object=True)


_ENTRIES: dict[str, Callable[[], TrackerEntry]] = {"flow": _flow, "golf": _golf, "groups": _groups, "colorpf": _colorpf}
NAMES = tuple(_ENTRIES)


def get(name: str) -> TrackerEntry:
    try:
        return _ENTRIES[name]()
    except KeyError:
        raise TrackreplayError(f"unknown tracker {name!r}; available: {', '.join(NAMES)}") from None
