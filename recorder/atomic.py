"""Write an output file under a temporary name and give it its final name only when complete.

A crash, a full disk or Ctrl-C then never leaves a half-written file under the name the user asked
for; an existing file of that name is replaced only by a complete new one.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import BinaryIO

from trackreplay.schemas.errors import OutputError


def partial_path(path: Path) -> Path:
    """Where ``path`` is written until it is complete: ``NAME.partial`` beside it."""
    return path.with_name(path.name + ".partial")


@contextmanager
def replace_when_done(path: str | Path, *, keep_partial: bool = False) -> Iterator[BinaryIO]:
    """A binary file at ``partial_path(path)``, renamed to ``path`` when the block ends without error.

    On an error the partial file is removed, unless ``keep_partial`` (a log that ``recover`` can salvage).
    """
    path = Path(path)
    tmp = partial_path(path)
    try:
        fh = open(tmp, "wb")
    except OSError as err:
        raise OutputError(f"cannot write {path} ({err.strerror})") from None
    try:
        yield fh
        fh.flush()
        os.fsync(fh.fileno())
    except BaseException as err:
        try:
            fh.close()
        except OSError:
            pass  # the unwritten tail is lost either way
        if not keep_partial:
            tmp.unlink(missing_ok=True)
        if isinstance(err, OSError):
            raise OutputError(f"cannot write {path} ({err.strerror or err})") from None
        raise
    fh.close()
    os.replace(tmp, path)
