"""Small output files (JSON, Parquet tables, bytes) written as ``NAME.partial`` and renamed when complete.

Thin wrappers over :func:`trackreplay.recorder.atomic.replace_when_done`, so an interrupted or failed
write never leaves a truncated file under the name asked for.
"""

from __future__ import annotations

import json
from pathlib import Path
from collections.abc import Callable
from typing import Any, BinaryIO

import polars as pl

from trackreplay.recorder.atomic import replace_when_done
from trackreplay.schemas.errors import OutputError


def write_bytes(path: Path, data: bytes) -> Path:
    with replace_when_done(path) as fh:
        fh.write(data)
    return path


def write_json(path: Path, data: Any, **kwargs: Any) -> Path:
    """``data`` as indented JSON with a final newline (``kwargs`` go to :func:`json.dumps`)."""
    return write_bytes(path, (json.dumps(data, indent=2, **kwargs) + "\n").encode())


def write_parquet(table: pl.DataFrame, path: Path) -> Path:
    return write_parquet_with(path, table.write_parquet)


def write_parquet_with(path: Path, write: Callable[[BinaryIO], None]) -> Path:
    """A Parquet file that ``write`` writes to an open file (e.g. row group by row group, from a spill)."""
    import pyarrow as pa

    try:
        with replace_when_done(path) as fh:
            write(fh)
    except (pl.exceptions.PolarsError, pa.ArrowException) as err:  # polars reports a full disk as ComputeError
        raise OutputError(f"cannot write {path} ({_first_line(err)})") from None
    return path


def _first_line(err: Exception) -> str:
    lines = [line.strip() for line in str(err).splitlines() if line.strip()]
    return lines[0] if lines else type(err).__name__


def remove_empty(folders: list[Path]) -> None:
    """Remove each folder that is empty, in the order given (deepest first: folders created and left unused)."""
    for folder in folders:
        try:
            folder.rmdir()
        except OSError:  # not empty, or gone: leave it
            pass
