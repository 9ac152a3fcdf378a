import pytest

from trackreplay.replay.log.prefetch import prefetch


def test_order_is_preserved() -> None:
    assert list(prefetch(iter(range(1000)), depth=3)) == list(range(1000))
    assert list(prefetch(iter(range(5)), depth=0)) == list(range(5))


def test_producer_error_arrives_after_the_items_before_it() -> None:
    def items():
        yield 1
        yield 2
        raise ValueError("bad frame 3")

    seen = []
    with pytest.raises(ValueError, match="bad frame 3"):
        for x in prefetch(items(), depth=2):
            seen.append(x)
    assert seen == [1, 2]


def test_consumer_stopping_early_ends_the_worker() -> None:
    gen = prefetch(iter(range(10**6)), depth=2)
    assert next(gen) == 0
    gen.close()  # must not hang


def test_a_consumer_stopping_near_the_end_ends_the_worker() -> None:
    """A review: a short source whose items were all queued left the worker blocked on handing over the
    end marker to a full queue (closing waited out the join's timeout, and the thread lived on)."""
    import threading
    import time

    gen = prefetch(iter(range(3)), depth=2)
    assert next(gen) == 0
    time.sleep(0.3)  # the worker queues 1 and 2 and reaches the end marker
    gen.close()
    assert not [t for t in threading.enumerate() if t.name == "trackreplay-prefetch" and t.is_alive()]


def test_a_replay_left_unfinished_has_its_reader_stopped_at_exit():
    """A review: breaking out of ``iter_steps`` and letting the script end killed the interpreter
    (exit 134, "terminate called without an active exception": the daemon reader thread was killed
    inside a decode). At exit the readers of unfinished generators are stopped and joined."""
    import threading
    import time

    from trackreplay.replay.log.prefetch import _stop_workers

    def endless():
        while True:
            time.sleep(0.005)  # a decode
            yield 1

    gen = prefetch(endless(), depth=2)
    assert next(gen) == 1  # the worker runs; the generator is left unfinished
    workers = [t for t in threading.enumerate() if t.name == "trackreplay-prefetch" and t.is_alive()]
    assert workers
    _stop_workers()  # what the interpreter runs at exit (atexit)
    assert not any(t.is_alive() for t in workers)
