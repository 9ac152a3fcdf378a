"""Issue 33, defect 1, for every writer: each writes a temporary file of its own, and a failed write
removes only that file, never the final name (another run's finished output) or another writer's file."""

from pathlib import Path

import pytest

from trackreplay.recorder.atomic import replace_when_done
from trackreplay.recorder.record import record
from trackreplay.recorder.writer import LogWriter
from trackreplay.schemas.errors import TrackreplayError


def test_a_failed_write_keeps_the_finished_file_and_another_writers_partial(tmp_path: Path) -> None:
    out = tmp_path / "x.json"
    out.write_bytes(b"finished")
    other = tmp_path / "x.json.partial"
    other.write_bytes(b"another process, still writing")
    with pytest.raises(RuntimeError), replace_when_done(out) as fh:
        fh.write(b"half")
        raise RuntimeError("cut short")
    assert out.read_bytes() == b"finished" and other.read_bytes() == b"another process, still writing"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.json", "x.json.partial"]
    with replace_when_done(out) as fh:
        fh.write(b"new")
    assert out.read_bytes() == b"new" and other.read_bytes() == b"another process, still writing"


def test_a_recording_never_truncates_a_leftover_partial_log(tmp_path: Path) -> None:
    """A crashed recording's NAME.partial is what `recover` needs: a second recording of the same name
    writes beside it."""
    out = tmp_path / "a.mcap"
    leftover = tmp_path / "a.mcap.partial"
    leftover.write_bytes(b"\x89MCAP0\r\n the flushed chunks of a crashed recording")
    with LogWriter(out) as log:
        assert log.partial != leftover
    assert out.stat().st_size > 0 and leftover.read_bytes().startswith(b"\x89MCAP0\r\n the flushed")


def test_a_broken_source_keeps_an_earlier_log_of_the_same_name(tmp_path: Path, make_images) -> None:
    folder = make_images(tmp_path / "img", 4)
    (folder / "frame2.jpg").write_bytes(b"\xff\xd8\xff not a jpeg")
    out = tmp_path / "out.mcap"
    out.write_bytes(b"an earlier, finished log")
    with pytest.raises(TrackreplayError):
        record(out, images=folder, fps=10, encoding="png", quiet=True)
    assert out.read_bytes() == b"an earlier, finished log"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["img", "out.mcap"]
