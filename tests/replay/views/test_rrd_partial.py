"""Issue 33, defect 1: a failed --rrd write never removes a finished file, nor another replay's partial one."""

from pathlib import Path

import pytest
import rerun.blueprint as rrb

from trackreplay.replay.views.rerun_sink import RerunSink
from trackreplay.schemas.errors import OutputError


def _failing_close(self) -> None:
    raise RuntimeError("No space left on device")


def test_a_failed_rrd_write_keeps_the_finished_file_of_the_same_name(tmp_path: Path, monkeypatch) -> None:
    out = tmp_path / "x.rrd"
    out.write_bytes(b"a finished replay's rrd")
    sink = RerunSink(out, "r", rrb.Blueprint())
    monkeypatch.setattr(RerunSink, "_close", _failing_close)
    with pytest.raises(OutputError, match="cannot write .*x.rrd"):
        sink.close()
    monkeypatch.undo()
    assert out.read_bytes() == b"a finished replay's rrd"
    assert [p.name for p in tmp_path.iterdir()] == ["x.rrd"]  # its own partial is gone


def test_two_replays_writing_one_path_each_write_their_own_partial(tmp_path: Path, monkeypatch) -> None:
    out = tmp_path / "x.rrd"
    first = RerunSink(out, "a", rrb.Blueprint())
    second = RerunSink(out, "b", rrb.Blueprint())
    assert first.partial != second.partial
    first.close()
    finished = out.read_bytes()
    monkeypatch.setattr(RerunSink, "_close", _failing_close)
    with pytest.raises(OutputError):
        second.close()
    assert out.read_bytes() == finished and not second.partial.exists()
