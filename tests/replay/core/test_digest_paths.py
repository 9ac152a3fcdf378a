"""The digest's one-update-per-frame path (``_collect``: float64 arrays rounded together) feeds the
sha256 exactly the bytes of the recursive ``_feed`` (which per-frame recording still uses)."""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from trackreplay.replay.core.digest import ReplayDigest, _feed
from trackreplay.replay.core.engine import ReplayRequest, iter_steps

GOLDEN = Path(__file__).resolve().parents[2] / "golden"


@dataclass
class _Pair:
    a: object
    b: object


def _both(index: int, value: object) -> tuple[str, str]:
    ref = hashlib.sha256(b"trackreplay-digest-v2")
    _feed(ref, f"frame{index}", value)
    fast = ReplayDigest()
    fast.add_frame(index, value)
    return ref.hexdigest(), fast._h.hexdigest()


def test_edge_values_hash_as_the_recursive_feed() -> None:
    values = [np.float64(3.0), np.array(2.5), np.zeros((0, 3)), np.arange(6.0).reshape(2, 3)[:, ::2],
              np.array([np.nan, -0.0, 1e-10, -1e-10, 1e-9, 9.9999999e-10, 1e40, -np.inf, 3.4e38, 3.5e38]),
              np.array([1.0, 2.0], dtype=">f8"), np.array([1.5, 1e-10], dtype=np.float32), np.array([1 + 2j]),
              [1, (2.0, None)], {"b": 1.0, "a": [np.ones(3)]}, _Pair(_Pair(1, 2.0), np.ones(2)), True, "x", 1e300,
              float("nan"), -0.0, np.int64(7), np.arange(4), (), []]
    for value in values:
        a, b = _both(0, [value, np.linspace(0.0, 1.0, 5), value, 0.5])
        assert a == b, repr(value)


def test_golden_golf_frames_hash_as_the_recursive_feed() -> None:
    for step in iter_steps(ReplayRequest(log=GOLDEN / "golf-teeshot-640x360.mcap", tracker="golf")):
        a, b = _both(step.frame.index, (step.intermediates, step.states))
        assert a == b, step.frame.index


class _Text(str):
    pass


def test_fast_branches_hash_as_the_recursive_feed() -> None:
    """A dataclass met again (its fields read without the general dispatch), strings in it and in
    tuples, and look-alikes that must take the general path (a str subclass, numpy scalars)."""
    pair = _Pair("s", ("a", "b", _Text("c"), 2.0))
    for value in ([pair, pair, _Pair(np.float64(1.5), _Text("x")), _Pair(True, None)],
                  (_Pair(_Pair("a", 1.0), [("x", "y"), "z"]), "", ("",))):
        for index in (0, 1):
            a, b = _both(index, value)
            assert a == b, repr(value)
