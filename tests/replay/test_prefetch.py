import pytest

from trackreplay.replay.prefetch import prefetch


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
