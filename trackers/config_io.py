"""Loading frozen-dataclass tracker configs from TOML or dicts, rejecting unknown keys."""

from __future__ import annotations

import dataclasses
import tomllib
from pathlib import Path
from typing import Any, TypeVar

from trackreplay.schemas.errors import TrackreplayError

C = TypeVar("C")


def config_from_dict(cls: type[C], values: dict[str, Any], source: str = "config") -> C:
    """Build ``cls`` from ``values``; lists become tuples so the config stays hashable."""
    names = {f.name for f in dataclasses.fields(cls)}
    unknown = sorted(set(values) - names)
    if unknown:
        raise TrackreplayError(
            f"{source}: unknown {cls.__name__} key(s) {', '.join(unknown)}; known keys: {', '.join(sorted(names))}"
        )
    clean = {k: tuple(v) if isinstance(v, list) else v for k, v in values.items()}
    try:
        return cls(**clean)
    except (TypeError, ValueError) as err:
        raise TrackreplayError(f"{source}: invalid {cls.__name__} ({err})") from None


def config_from_toml(cls: type[C], path: str | Path, table: str | None = None) -> C:
    """Read ``path`` (optionally its ``[table]``) into ``cls``."""
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text())
    except FileNotFoundError:
        raise TrackreplayError(f"{path} does not exist") from None
    except tomllib.TOMLDecodeError as err:
        raise TrackreplayError(f"{path} is not valid TOML ({err})") from None
    if table is not None and isinstance(data.get(table), dict):
        data = data[table]
    return config_from_dict(cls, data, str(path))


def config_to_dict(config: Any) -> dict[str, Any]:
    return {k: list(v) if isinstance(v, tuple) else v for k, v in dataclasses.asdict(config).items()}
