"""Parameter grids for ``trackreplay batch`` and ``diff``: seeds, ``--set key=v1,v2`` and config merging.

Values are TOML values (``500``, ``0.5``, ``true``, ``"ptz"``, ``[1.0, 0.0]``); a bare word that is
not TOML is a string. A key path may start with the tracker's table name (``golf.particles.n``)
or not (``particles.n``). The merged config is checked by :func:`replay.config.load_config`, so an
unknown key is an error naming its full path before any replay starts.
"""

from __future__ import annotations

import copy
import itertools
import tomllib
from pathlib import Path
from typing import Any

from trackreplay.replay.core.config import read_toml, tracker_table
from trackreplay.replay.core.engine import check_seed
from trackreplay.schemas.errors import TrackreplayError


def parse_value(text: str) -> Any:
    text = text.strip()
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


def _split_values(text: str) -> list[str]:
    """Split on commas outside brackets and quotes: ``1,2`` -> 2 values, ``[1,2],[3,4]`` -> 2 values."""
    parts, depth, quote, cur = [], 0, "", []
    for ch in text:
        if quote:
            quote = "" if ch == quote else quote
        elif ch in "\"'":
            quote = ch
        elif ch in "[{":
            depth += 1
        elif ch in "]}":
            depth -= 1
        elif ch == "," and depth == 0:
            parts.append("".join(cur))
            cur = []
            continue
        cur.append(ch)
    parts.append("".join(cur))
    return parts


def parse_assignment(text: str) -> tuple[str, Any]:
    """``key=value`` -> (key, parsed value)."""
    key, eq, value = text.partition("=")
    if not eq or not key.strip():
        raise TrackreplayError(f"--set {text!r}: expected KEY=VALUE, e.g. golf.particles.n=500")
    return key.strip(), parse_value(value)


def parse_set(text: str) -> tuple[str, list[Any]]:
    """``golf.particles.n=500,1000`` -> ("golf.particles.n", [500, 1000])."""
    key, eq, values = text.partition("=")
    parts = _split_values(values)
    if not eq or not key.strip() or not all(p.strip() for p in parts):  # `n=,` or `n=1,,2`: a value is missing
        raise TrackreplayError(f"--set {text!r}: expected KEY=V1[,V2...], e.g. golf.particles.n=500,1000")
    return key.strip(), [parse_value(v) for v in parts]


MAX_SEEDS = 100_000  # a typo like 0-2147483647 would build 2^31 tasks (and hang) before saying anything


def parse_seeds(text: str) -> list[int]:
    """``0-9``, ``1,5,7`` or ``0-3,10`` -> the seeds in order, without repeats."""
    seeds: list[int] = []
    seen: set[int] = set()
    for part in _split_values(text):
        lo, dash, hi = part.strip().partition("-")
        try:
            lo_n, hi_n = int(lo), int(hi) if dash else int(lo)
        except ValueError:
            raise TrackreplayError(f"--seeds {text!r}: expected N, N-M or a comma list of them") from None
        if hi_n < lo_n:
            raise TrackreplayError(f"--seeds {text!r}: range {part} is empty")
        for bound in (lo_n, hi_n):
            check_seed(bound, f"--seeds {text!r}: seed")
        if hi_n - lo_n + 1 > MAX_SEEDS:  # (before the range is built)
            raise TrackreplayError(f"--seeds {text!r}: more than {MAX_SEEDS} seeds; give a smaller range")
        fresh = [s for s in range(lo_n, hi_n + 1) if s not in seen]
        seen.update(fresh)
        seeds += fresh
        if len(seeds) > MAX_SEEDS:  # repeats of seeds already given are no new seeds
            raise TrackreplayError(f"--seeds {text!r}: more than {MAX_SEEDS} seeds; give a smaller range")
    if not seeds:
        raise TrackreplayError(f"--seeds {text!r}: no seeds")
    return seeds


def key_path(tracker: str | None, key: str) -> list[str]:
    """A ``--set`` key as a path in the tracker's table: ``golf.particles.n`` -> [particles, n]."""
    path = key.split(".")
    return path[1:] if tracker is not None and len(path) > 1 and path[0] == tracker else path


def grid(sets: list[str], tracker: str | None = None) -> list[dict[str, Any]]:
    """The cross product of ``--set`` options: one dict (key path -> value) per combination. A key
    given twice, in any spelling (``golf.particles.n`` and ``particles.n`` for golf), is refused."""
    parsed = [parse_set(s) for s in sets]
    keys = [k for k, _ in parsed]
    refuse_repeats(keys, tracker, "list its values once, comma-separated")
    return [dict(zip(keys, combo)) for combo in itertools.product(*(v for _, v in parsed))]


def refuse_repeats(keys: list[str], tracker: str | None, advice: str, option: str = "--set") -> None:
    """Refuse a key given twice, in any spelling (``golf.particles.n`` and ``particles.n`` for golf)."""
    seen: dict[str, str] = {}
    for key in keys:
        norm = ".".join(key_path(tracker, key))
        if norm in seen:
            same = f" (as {seen[norm]})" if seen[norm] != key else ""
            raise TrackreplayError(f"{option} {key} given twice{same}; {advice}")
        seen[norm] = key


def apply_sets(tracker: str, base: str | Path | dict | None, sets: dict[str, Any]) -> dict[str, Any]:
    """The tracker's config as a nested dict: ``base`` (TOML path, dict or None) with ``sets`` applied."""
    if base is None:
        config: dict[str, Any] = {}
    elif isinstance(base, dict):
        config = copy.deepcopy(base)
    else:
        config = copy.deepcopy(tracker_table(read_toml(base), tracker, base))
    for key, value in sets.items():
        path = key_path(tracker, key)
        node = config
        for i, part in enumerate(path[:-1]):
            child = node.setdefault(part, {})
            if not isinstance(child, dict):
                raise TrackreplayError(f"--set {key}: {'.'.join(path[:i + 1])} is a value, not a table")
            node = child
        node[path[-1]] = value
    return config
