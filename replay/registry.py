"""Tracker names -> (config class, tracker class, Rerun view)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

from schemas.errors import TrackreplayError


@dataclass(frozen=True)
class TrackerEntry:
    name: str
    config_cls: type
    tracker_cls: type
    view: Any  # module with blueprint(name) and log(rec, frame, intermediates, states)


def _flow() -> TrackerEntry:
    from replay.views import flow as view
    from trackers.flow.config import FlowConfig
    from trackers.flow.tracker import FlowTracker

    return TrackerEntry("flow", FlowConfig, FlowTracker, view)


def _golf() -> TrackerEntry:
    from replay.views import golf as view
    from trackers.golf.config import GolfConfig
    from trackers.golf.tracker import GolfTracker

    return TrackerEntry("golf", GolfConfig, GolfTracker, view)


_ENTRIES: dict[str, Callable[[], TrackerEntry]] = {"flow": _flow, "golf": _golf}
NAMES = tuple(_ENTRIES)


def get(name: str) -> TrackerEntry:
    try:
        return _ENTRIES[name]()
    except KeyError:
        raise TrackreplayError(f"unknown tracker {name!r}; available: {', '.join(NAMES)}") from None
