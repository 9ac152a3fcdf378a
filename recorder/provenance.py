"""Where a log came from: a metadata record every log we write carries (``info`` shows it).

``trackreplay.provenance`` holds the tool and its version, the command line (when the log is written
by the CLI) and, per source file, its name, size and SHA-256 (an image folder: the SHA-256 of its
sorted file names and sizes, which says whether the folder changed without reading every image twice).
"""

from __future__ import annotations

import contextvars
import hashlib
from importlib.metadata import PackageNotFoundError, version
from collections.abc import Mapping
from pathlib import Path

RECORD_NAME = "trackreplay.provenance"
# Set by the CLI around a verb: the command line that is writing.
command_line: contextvars.ContextVar[str | None] = contextvars.ContextVar("trackreplay_command_line", default=None)


def describe_source(path: Path) -> str:
    """``name sha256:HEX N bytes`` for a file; ``name/ listing-sha256:HEX N files`` for a folder."""
    path = Path(path)
    if path.is_dir():
        h = hashlib.sha256()
        files = sorted(p for p in path.iterdir() if p.is_file())
        for p in files:
            h.update(f"{p.name}\0{p.stat().st_size}\n".encode())
        return f"{path.name}/ listing-sha256:{h.hexdigest()} {len(files)} files"
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return f"{path.name} sha256:{h.hexdigest()} {path.stat().st_size} bytes"


def _version() -> str:
    # From the installed distribution, as trackreplay.__version__ does (the package root is not imported
    # here: it reaches into replay, which recorder must not).
    try:
        return version("trackreplay")
    except PackageNotFoundError:
        return "0+unknown"


def provenance(sources: Mapping[str, Path | str | None] | None = None, **extra: str) -> dict[str, str]:
    """The provenance record's key/value pairs (all strings, as MCAP metadata requires)."""
    record = {"tool": "trackreplay", "version": _version()}
    cli = command_line.get()
    if cli is not None:
        record["command_line"] = cli
    for role, path in sorted((sources or {}).items()):
        if path is not None:
            record[f"source.{role}"] = describe_source(Path(path))
    record.update({k: str(v) for k, v in sorted(extra.items())})
    return record
