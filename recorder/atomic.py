"""Write an output file under a temporary name and give it its final name only when complete.

A crash, a full disk or Ctrl-C then never leaves a half-written file under the name the user asked
for; an existing file of that name is replaced only by a complete new one. The temporary file is
created exclusively (``O_EXCL``): two processes writing one path each write their own, and a
failed write removes only the file it created, never the final name or another writer's file.
"""

from __future__ import annotations

import os
import stat
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import BinaryIO

from trackreplay.schemas.errors import OutputError


def partial_path(path: Path) -> Path:
    """Where ``path`` is written until it is complete when no other writer holds that name: ``NAME.partial``."""
    return path.with_name(path.name + ".partial")


def _candidates(path: Path) -> Iterator[Path]:
    yield partial_path(path)
    # taken (another process writing the same path, or a recording's leftover kept for `recover`)
    pid = os.getpid()
    yield path.with_name(f"{path.name}.{pid}.partial")
    for n in range(1, 1000):
        yield path.with_name(f"{path.name}.{pid}-{n}.partial")


def open_partial(path: str | Path) -> tuple[Path, BinaryIO]:
    """A new file of this process's own where ``path`` is written until complete, open for writing:
    ``NAME.partial``, or ``NAME.PID.partial`` when that name exists already (never truncated)."""
    path = Path(path)
    err: OSError | None = None
    for tmp in _candidates(path):
        try:
            return tmp, open(tmp, "xb")
        except FileExistsError as exists:
            err = exists
        except OSError as other:
            raise OutputError(f"cannot write {path} ({other.strerror})") from None
    raise OutputError(f"cannot write {path} ({err.strerror if err else 'no free temporary name'})")


def claim_partial(path: str | Path) -> Path:
    """Create (empty) this process's own temporary name for ``path`` and return it, for a library that
    opens the file by name itself (Rerun's file sink, polars)."""
    tmp, fh = open_partial(path)
    fh.close()
    return tmp


def _take_mode_and_owner(tmp: Path, original: Path) -> None:
    """Give ``tmp`` the permission bits, owner and group of ``original`` (a file replaced in place keeps
    them); an owner this process may not give (not root) stays its own."""
    st = os.stat(original)
    os.chmod(tmp, stat.S_IMODE(st.st_mode))
    if (st.st_uid, st.st_gid) != (os.stat(tmp).st_uid, os.stat(tmp).st_gid):
        try:
            os.chown(tmp, st.st_uid, st.st_gid)
        except PermissionError:
            try:
                os.chown(tmp, -1, st.st_gid)  # a group the user belongs to
            except PermissionError:
                pass


@contextmanager
def replace_when_done(path: str | Path, *, keep_partial: bool = False, in_place: bool = False) -> Iterator[BinaryIO]:
    """A binary file at :func:`open_partial`'s name, renamed to ``path`` when the block ends without error.

    On an error that file is removed, unless ``keep_partial`` (a log that ``recover`` can salvage).
    ``in_place``: ``path`` exists and is being rewritten: the new file keeps its mode and owner.
    """
    path = Path(path)
    tmp, fh = open_partial(path)
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
    if in_place:
        _take_mode_and_owner(tmp, path)
    os.replace(tmp, path)
