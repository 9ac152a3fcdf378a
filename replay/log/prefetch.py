"""Read and decode ahead in one background thread while the tracker works on the current frame.

Order is untouched (one producer, one FIFO), so results do not change; image decoding releases
the GIL, so on two cores reading overlaps tracking.
"""

from __future__ import annotations

import atexit
import queue
import threading
from collections.abc import Iterator
from typing import TypeVar

T = TypeVar("T")
_END = object()
_RUNNING: dict[threading.Thread, threading.Event] = {}  # live workers and their stop events


@atexit.register
def _stop_workers() -> None:
    """At interpreter exit, stop the workers of generators left unfinished (a script that breaks out
    of ``iter_steps`` and ends): a daemon thread killed inside a decode aborted the process
    (``terminate called without an active exception``, exit 134)."""
    for worker, stop in list(_RUNNING.items()):
        stop.set()
        worker.join(timeout=5)


class _Failure:
    def __init__(self, err: BaseException) -> None:
        self.err = err


def prefetch(items: Iterator[T], depth: int = 4) -> Iterator[T]:
    """Yield ``items`` in order, produced up to ``depth`` ahead by a worker thread.

    An exception in the producer is re-raised in the consumer at the position it happened,
    after every item produced before it.
    """
    if depth <= 0:
        yield from items
        return
    buffer: queue.Queue = queue.Queue(maxsize=depth)
    stop = threading.Event()

    def put(item) -> bool:
        """Hand ``item`` over unless the consumer has stopped (a full queue then waits no longer)."""
        while not stop.is_set():
            try:
                buffer.put(item, timeout=0.1)
                return True
            except queue.Full:
                continue
        return False

    def produce() -> None:
        try:
            for item in items:
                if not put(item):
                    return
            put(_END)
        except BaseException as err:  # handed to the consumer, raised there
            put(_Failure(err))

    worker = threading.Thread(target=produce, name="trackreplay-prefetch", daemon=True)
    _RUNNING[worker] = stop
    worker.start()
    try:
        while True:
            item = buffer.get()
            if item is _END:
                return
            if isinstance(item, _Failure):
                raise item.err
            yield item
    finally:
        stop.set()
        worker.join(timeout=5)
        _RUNNING.pop(worker, None)
