"""Ctrl-C and SIGTERM wait for the log write under way: a log is cut between records, never in one."""

from __future__ import annotations

from pathlib import Path

import pytest
from mcap.reader import make_reader

from trackreplay.recorder.interrupts import deferred_interrupts, interrupt
from trackreplay.recorder.writer import LogWriter
from trackreplay.schemas import topics
from trackreplay.schemas.records import GroundTruthFrame


def test_an_interrupt_outside_a_section_is_raised_at_once() -> None:
    with pytest.raises(KeyboardInterrupt):
        interrupt(KeyboardInterrupt())


def test_an_interrupt_inside_a_section_waits_for_its_end() -> None:
    done = []
    with pytest.raises(KeyboardInterrupt):
        with deferred_interrupts():
            with deferred_interrupts():
                interrupt(KeyboardInterrupt())
                done.append("inner")
            done.append("outer")  # nested: only the outermost end raises
    assert done == ["inner", "outer"]
    with deferred_interrupts():  # nothing pending afterwards
        done.append("again")
    assert done[-1] == "again"


def write_until_interrupted(out: Path, monkeypatch) -> int:
    """Messages written before an interrupt that arrives while the second chunk is being compressed
    (as a signal handler raises it: half-way through the writer's chunk bookkeeping)."""
    import mcap.writer

    real = mcap.writer.zstandard.compress
    chunks = []

    def compress_interrupted(data: bytes) -> bytes:
        chunks.append(1)
        if len(chunks) == 2:
            interrupt(KeyboardInterrupt())
        return real(data)

    monkeypatch.setattr(mcap.writer.zstandard, "compress", compress_interrupted)
    writer = LogWriter(out, flush_every=3)
    written = 0
    with pytest.raises(KeyboardInterrupt):
        for i in range(100):
            writer.write(topics.GROUNDTRUTH, GroundTruthFrame(i, i * 1000, ()).to_pb(), i * 1000)
            written += 1
    writer.close()
    monkeypatch.setattr(mcap.writer.zstandard, "compress", real)
    return written


def messages_in(path: Path) -> int:
    with open(path, "rb") as fh:
        reader = make_reader(fh)
        assert reader.get_summary() is not None
        return sum(1 for _ in reader.iter_messages())


def test_an_interrupt_in_the_middle_of_closing_a_chunk_leaves_a_readable_log(tmp_path: Path, monkeypatch) -> None:
    """The chunk is finished first, then the interrupt is raised; closing gives a log whose every
    message reads (the 6th write's chunk is out before its KeyboardInterrupt)."""
    assert write_until_interrupted(tmp_path / "cut.mcap", monkeypatch) == 5
    assert messages_in(tmp_path / "cut.mcap") == 6


def test_without_the_deferral_the_same_interrupt_breaks_the_log(tmp_path: Path, monkeypatch) -> None:
    """The test above can fail: raised where it arrives, the same interrupt leaves a log that does not read whole."""
    from contextlib import nullcontext

    import trackreplay.recorder.writer as writer_module

    monkeypatch.setattr(writer_module, "deferred_interrupts", nullcontext)
    write_until_interrupted(tmp_path / "broken.mcap", monkeypatch)
    with pytest.raises(Exception):
        assert messages_in(tmp_path / "broken.mcap") == 6


def test_a_section_in_another_thread_neither_delays_nor_takes_the_interrupt() -> None:
    import threading

    inside, release, seen = threading.Event(), threading.Event(), []

    def worker() -> None:
        try:
            with deferred_interrupts():
                inside.set()
                release.wait(10)
        except BaseException as exc:  # the main thread's interrupt must not surface here
            seen.append(exc)

    thread = threading.Thread(target=worker)
    thread.start()
    inside.wait(10)
    try:
        with pytest.raises(KeyboardInterrupt):
            interrupt(KeyboardInterrupt())  # the main thread is in no section: raised at once
    finally:
        release.set()
        thread.join(10)
    assert seen == []
