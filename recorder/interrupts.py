"""Interrupts that wait for a write to finish.

Ctrl-C and SIGTERM stop a recording by raising in the main thread, between any two bytecodes. Raised
in the middle of closing a chunk, the writer's ``finish`` then wrote its summary after half a chunk:
a log whose summary reads but whose messages end in a truncated record. The CLI's handlers call
:func:`interrupt`; inside :func:`deferred_interrupts` (every write of :class:`~.writer.LogWriter`)
the exception is kept and raised when the section ends, so a log is cut between records, never in one.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from contextlib import contextmanager

_depth = 0
_pending: BaseException | None = None


@contextmanager
def deferred_interrupts() -> Iterator[None]:
    """A section an interrupt may not cut: :func:`interrupt`'s exception is raised at its end. Only
    the main thread's sections count: Python runs signal handlers there, and a log written by
    another thread neither delays the main thread's interrupt nor has it raised in its own thread."""
    global _depth, _pending
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    _depth += 1
    try:
        yield
    finally:
        _depth -= 1
        if _depth == 0 and _pending is not None:
            pending, _pending = _pending, None
            raise pending


def interrupt(exc: BaseException) -> None:
    """Raise ``exc`` now, or, inside :func:`deferred_interrupts`, when the section ends (the first one
    kept: a second Ctrl-C while a chunk is written does not cut it either)."""
    global _pending
    if _depth:
        if _pending is None:
            _pending = exc
        return
    raise exc
