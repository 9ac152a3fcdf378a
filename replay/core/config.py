"""Tracker configs from TOML files, dicts or instances (trackers themselves do no I/O).

A tracker's config is a frozen dataclass whose fields may themselves be frozen dataclasses
(``GolfConfig(particles=ParticleConfig(...), lut=LutConfig(...))``). A TOML file gives it either
at the top level or under the tracker's table, nested the same way (``[golf]``, ``[golf.particles]``);
a dict is nested the same way too. Unknown keys are an error naming the key's full path; lists
become tuples so configs stay hashable.
"""

from __future__ import annotations

import dataclasses
import math
import tomllib
import types
import typing
from collections.abc import Mapping
from pathlib import Path
from typing import Any, TypeVar

from trackreplay.schemas.errors import TrackreplayError

C = TypeVar("C")
ConfigSource = Any  # None | a config dataclass instance | a Mapping | a TOML path (str or Path)


def _dataclass_of(hint: Any) -> type | None:
    """The dataclass a field holds (also through ``X | None``), else None."""
    if dataclasses.is_dataclass(hint) and isinstance(hint, type):
        return hint
    if typing.get_origin(hint) in (typing.Union, types.UnionType):
        inner = [a for a in typing.get_args(hint) if a is not type(None)]
        if len(inner) == 1:
            return _dataclass_of(inner[0])
    return None


def _tuples(value: Any) -> Any:
    if isinstance(value, list | tuple):
        return tuple(_tuples(v) for v in value)
    return value


def _join(prefix: str, key: str) -> str:
    return f"{prefix}.{key}" if prefix else key


SCALARS = {int: "an integer", float: "a number", bool: "true or false", str: "a string"}


def _scalar_mismatch(hint: Any, value: Any) -> str | None:
    """What a scalar field of type ``hint`` (``int``, ``float``, ``bool``, ``str``, or one of them
    ``| None``) needs, when ``value`` is not that (None: it fits, or the field is no plain scalar).
    An integer is a number; true/false is neither (TOML keeps them apart, Python does not)."""
    options = [a for a in typing.get_args(hint) if a is not type(None)] \
        if typing.get_origin(hint) in (typing.Union, types.UnionType) else [hint]
    if len(options) != 1 or options[0] not in SCALARS or value is None:
        return None
    want = options[0]
    fits = (isinstance(value, bool) if want is bool else
            isinstance(value, int | float) and not isinstance(value, bool) if want is float else
            isinstance(value, want) and not isinstance(value, bool))
    return None if fits else SCALARS[want]


def _not_finite(value: Any) -> float | None:
    """The first nan or infinity in a number or a list of them (None: none)."""
    if isinstance(value, float) and not math.isfinite(value):
        return value
    if isinstance(value, list | tuple):
        return next((v for v in value if isinstance(v, float) and not math.isfinite(v)), None)
    return None


# No parameter of ours is meaningful beyond these magnitudes (the defaults lie within 1e-3..1e3), and
# trackers turn some into sizes and counts: 1e308 or 1e-300 would end in an overflow or an allocation.
MAX_MAGNITUDE = 1e9
MIN_MAGNITUDE = 1e-9


def _out_of_range(value: Any) -> int | float | None:
    """The first finite number (in a number or a list of them) whose magnitude is beyond
    ``MAX_MAGNITUDE`` or, not zero, below ``MIN_MAGNITUDE`` (None: none)."""
    for v in value if isinstance(value, list | tuple) else (value,):
        if isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) and v != 0 \
                and not MIN_MAGNITUDE <= abs(v) <= MAX_MAGNITUDE:
            return v
    return None


def config_from_dict(cls: type[C], values: Mapping[str, Any], source: str = "config", prefix: str = "") -> C:
    """Build ``cls`` from ``values`` (nested mappings for nested config dataclasses).

    ``source`` names where the values came from (a file) and ``prefix`` the key path of ``values``
    there (``golf`` for a ``[golf]`` table); both only shape the error messages.
    """
    if not isinstance(values, Mapping):
        where = prefix or cls.__name__
        raise TrackreplayError(f"{source}: {where} must be a table of keys, not {type(values).__name__} {values!r}")
    fields = {f.name: f for f in dataclasses.fields(cls) if f.init}
    unknown = sorted(set(values) - set(fields))
    if unknown:
        keys = ", ".join(_join(prefix, k) for k in unknown)
        raise TrackreplayError(f"{source}: unknown key{'s' if len(unknown) > 1 else ''} {keys}; "
                               f"known: {', '.join(sorted(fields))}")
    hints = typing.get_type_hints(cls)
    clean: dict[str, Any] = {}
    for key, value in values.items():
        if (want := _scalar_mismatch(hints.get(key), value)) is not None:
            raise TrackreplayError(f"{source}: {_join(prefix, key)} must be {want}, not {value!r}")
        if (bad := _not_finite(value)) is not None:  # no parameter of ours means anything at nan or inf
            raise TrackreplayError(f"{source}: {_join(prefix, key)} must be a finite number, not {bad!r}")
        inner = _dataclass_of(hints.get(key))
        if inner is None or value is None or isinstance(value, inner):
            clean[key] = _tuples(value)
        else:  # a nested config: its table (anything else is reported there)
            clean[key] = config_from_dict(inner, value, source, _join(prefix, key))
    try:
        config = cls(**clean)
    except (TypeError, ValueError, OverflowError) as err:
        raise TrackreplayError(f"{source}: invalid {prefix or cls.__name__} ({err})") from None
    for key, value in clean.items():  # after the config's own checks, which say more where they apply
        if (big := _out_of_range(value)) is not None:
            raise TrackreplayError(f"{source}: {_join(prefix, key)} = {big!r} is out of range (a number's magnitude "
                                   f"must be 0 or between {MIN_MAGNITUDE:g} and {MAX_MAGNITUDE:g})")
    return config


MAX_TOML_LINE = 64 * 1024  # bytes, its newline included; a config line is a key and a short value
MAX_TOML_BYTES = 1024 * 1024  # a config file is a few KB; this bounds what parsing it may cost
MAX_TOML_DEPTH = 32  # tables and arrays inside one another (ours go three deep)


def _toml_text(path: Path) -> str:
    """The file's text, read a bounded line at a time: a huge line or file is refused before it is
    held (a 50 MB line cost tomllib 7 GB)."""
    lines: list[bytes] = []
    size = 0
    with open(path, "rb") as fh:
        while line := fh.readline(MAX_TOML_LINE + 1):
            if len(line) > MAX_TOML_LINE:
                raise TrackreplayError(f"{path}:{len(lines) + 1}: a line longer than {MAX_TOML_LINE} bytes; "
                                       "a config line is a key and a short value")
            size += len(line)
            if size > MAX_TOML_BYTES:
                raise TrackreplayError(f"{path}:{len(lines) + 1}: the file goes on past {MAX_TOML_BYTES} bytes; "
                                       "a config file is a few KB")
            lines.append(line)
    return b"".join(lines).decode("utf-8")


def _depth_error(path: Path, text: str) -> TrackreplayError:
    """The refusal of a file nested deeper than ``MAX_TOML_DEPTH``, at the first line that goes deeper
    (brackets counted outside strings and comments, enough to find the line)."""
    depth, quote = 0, ""
    for number, line in enumerate(text.splitlines(), start=1):
        for ch in line:
            if quote:
                quote = "" if ch == quote else quote
            elif ch in "\"'":
                quote = ch
            elif ch == "#":
                break
            elif ch in "[{":
                depth += 1
                if depth > MAX_TOML_DEPTH:
                    return TrackreplayError(f"{path}:{number}: nested more than {MAX_TOML_DEPTH} deep")
            elif ch in "]}":
                depth -= 1
    return TrackreplayError(f"{path}: nested more than {MAX_TOML_DEPTH} deep")


def _depth(value: Any) -> int:
    """How deep tables and arrays nest in a parsed value (iteratively: no recursion limit to meet)."""
    deepest, stack = 0, [(value, 0)]
    while stack:
        item, level = stack.pop()
        children = item.values() if isinstance(item, dict) else item if isinstance(item, list) else None
        if children is not None:
            deepest = max(deepest, level + 1)
            stack.extend((child, level + 1) for child in children)
    return deepest


def read_toml(path: str | Path) -> dict[str, Any]:
    """A TOML file's tables; a missing, malformed, huge or deeply nested file is a one-sentence error."""
    path = Path(path)
    try:
        text = _toml_text(path)
        data = tomllib.loads(text)
    except FileNotFoundError:
        raise TrackreplayError(f"{path} does not exist") from None
    except IsADirectoryError:
        raise TrackreplayError(f"{path} is a directory, not a TOML file") from None
    except UnicodeDecodeError:
        raise TrackreplayError(f"{path} is not a text (TOML) file") from None
    except tomllib.TOMLDecodeError as err:
        raise TrackreplayError(f"{path} is not valid TOML ({err})") from None
    except RecursionError:
        raise _depth_error(path, text) from None
    if _depth(data) > MAX_TOML_DEPTH:
        raise _depth_error(path, text)
    return data


def config_from_toml(cls: type[C], path: str | Path, table: str | None = None) -> C:
    """Read ``path`` into ``cls``: its ``[table]`` (with sub-tables) when present, else the top level."""
    data = read_toml(path)
    if table is not None:  # (its [table], or the top level unless that configures another tracker)
        return config_from_dict(cls, tracker_table(data, table, path), str(path),
                                table if isinstance(data.get(table), dict) else "")
    return config_from_dict(cls, data, str(path))


def tracker_table(data: dict, table: str, path: str | Path) -> dict:
    """A TOML file's ``[table]`` when it has one (else the whole file); anything beside that table
    is refused: a review's [flow] table beside [groups] was silently ignored (also by ``batch --set``)."""
    if not isinstance(data.get(table), dict):
        from trackreplay.replay.core import registry  # (the names of the trackers, registered ones too)

        configured = sorted(k for k, v in data.items() if k in registry.NAMES and isinstance(v, dict))
        if configured:  # (a [golf] table read as the flow tracker's keys said "unknown key golf")
            raise TrackreplayError(f"{path}: this file configures {', '.join(configured)}, not the {table} tracker; "
                                   f"give --tracker {configured[0]} or a file with a [{table}] table")
        return data
    others = sorted(k for k in data if k != table)
    if others:
        raise TrackreplayError(f"{path}: {', '.join(repr(k) for k in others)} beside the [{table}] table would be "
                               f"ignored by the {table} tracker; keep only [{table}] (and its sub-tables)")
    return data[table]


def load_config(cls: type[C], source: ConfigSource = None, table: str | None = None) -> C:
    """``cls`` from None (defaults), an instance of ``cls``, a dict, or a TOML file path."""
    if source is None:
        return cls()
    if isinstance(source, cls):
        return source
    if isinstance(source, Mapping):
        return config_from_dict(cls, source, f"{table or cls.__name__} config (--set or a dict)")
    if isinstance(source, str | Path):
        return config_from_toml(cls, source, table)
    raise TrackreplayError(f"a {cls.__name__} must be given as None, a {cls.__name__}, a dict or a TOML path, "
                           f"not {type(source).__name__}")


def config_to_dict(config: Any) -> dict[str, Any]:
    """The inverse of :func:`config_from_dict`: nested dicts, tuples as lists (TOML/JSON ready)."""

    def plain(value: Any) -> Any:
        if isinstance(value, dict):
            return {k: plain(v) for k, v in value.items()}
        if isinstance(value, list | tuple):
            return [plain(v) for v in value]
        return value

    return plain(dataclasses.asdict(config))
