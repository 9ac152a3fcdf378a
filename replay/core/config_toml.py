"""A tracker's config as commented TOML (``trackreplay config TRACKER``, replay summaries).

The comments are the ones beside each field in the config dataclasses' source (the only place the
defaults are explained), and the class docstring's first line for each table. The text reads back
with :func:`trackreplay.replay.core.config.load_config` into an equal config. Written by hand because
the standard library reads TOML but does not write it, and no writer keeps comments.
"""

from __future__ import annotations

import dataclasses
import inspect
import io
import json
import math
import tokenize
from typing import Any


def field_comments(cls: type) -> dict[str, str]:
    """``{field: comment}`` from ``name: type = value  # comment`` lines of a dataclass's source."""
    try:
        source = inspect.getsource(cls)
    except (OSError, TypeError):
        return {}
    comments: dict[str, str] = {}
    names = {f.name for f in dataclasses.fields(cls)}
    pending: str | None = None
    for tok in tokenize.generate_tokens(io.StringIO(source).readline):
        if tok.type == tokenize.NAME and tok.start[1] == 4 and tok.string in names:
            pending = tok.string
        elif tok.type == tokenize.COMMENT and pending is not None:
            comments.setdefault(pending, tok.string.lstrip("#").strip())
        elif tok.type == tokenize.NEWLINE:
            pending = None
    return comments


def _value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)  # a JSON string is a valid TOML basic string
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    raise TypeError(f"cannot write {type(value).__name__} to TOML")


def _summary(cls: type) -> str:
    doc = inspect.getdoc(cls) or ""
    return doc.strip().split("\n")[0] if doc else ""


def config_toml(config: Any, table: str) -> str:
    """``config`` (a dataclass instance) under ``[table]``, nested dataclasses as sub-tables, with comments.

    A field whose value is None is written commented out (TOML has no null): leaving it out keeps the default.
    """
    out: list[str] = []

    def write(obj: Any, name: str) -> None:
        cls = type(obj)
        comments = field_comments(cls)
        summary = _summary(cls)
        if out:
            out.append("")
        if summary:
            out.append(f"# {summary}")
        out.append(f"[{name}]")
        nested = []
        for f in dataclasses.fields(obj):
            value = getattr(obj, f.name)
            if dataclasses.is_dataclass(value):
                nested.append((f.name, value))
                continue
            comment = f"  # {comments[f.name]}" if f.name in comments else ""
            if value is None:
                out.append(f"# {f.name} ={comment or '  # (none)'}")
            else:
                out.append(f"{f.name} = {_value(value)}{comment}")
        for key, value in nested:
            write(value, f"{name}.{key}")

    write(config, table)
    return "\n".join(out) + "\n"

