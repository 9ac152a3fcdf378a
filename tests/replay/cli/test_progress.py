"""Progress of the long steps (`synth` scenes, `flight`'s fit) on stderr: only on a terminal, never
with --quiet, and never changing what is written."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from trackreplay.replay.cli.commands import synth
from trackreplay.replay.cli.main import main

GOLDEN = Path(__file__).resolve().parents[2] / "golden"


def test_the_bar_follows_the_writer_and_is_absent_when_disabled(capsys: pytest.CaptureFixture) -> None:
    with synth.progress_bar("groups-crossing", False) as progress:
        assert progress is None
    assert capsys.readouterr().err == ""
    with synth.progress_bar("groups-crossing", True) as progress:
        for done in range(1, 11):
            progress(done, 10)
    err = capsys.readouterr().err
    assert "groups-crossing" in err and "frame" in err


def test_a_scene_holds_the_same_messages_with_and_without_progress(tmp_path: Path, capsys: pytest.CaptureFixture,
                                                             monkeypatch: pytest.MonkeyPatch) -> None:
    args = ["synth", "colorpf-approach", "--frames", "3"]
    (tmp_path / "quiet").mkdir()
    (tmp_path / "shown").mkdir()
    assert main([*args, str(tmp_path / "quiet" / "scene.mcap"), "--quiet"]) == 0
    assert capsys.readouterr().err.startswith("wrote ")  # no bar: stderr is not a terminal here
    monkeypatch.setattr(synth, "_shows_progress", lambda args: True)
    assert main([*args, str(tmp_path / "shown" / "scene.mcap")]) == 0
    assert "colorpf-approach" in capsys.readouterr().err.split("wrote ")[0]
    assert _messages(tmp_path / "quiet" / "scene.mcap") == _messages(tmp_path / "shown" / "scene.mcap")


def _messages(path: Path) -> list[tuple[str, int, bytes]]:
    """Every message of a log (the file's header holds the time it was written)."""
    from trackreplay.replay.log.reader import LogReader

    reader = LogReader(path)
    return [(m.topic, m.log_time, m.data) for m in reader.messages(reader.topics())]


def test_flight_says_each_stage_on_a_terminal_and_prints_the_same_fit(capsys: pytest.CaptureFixture,
                                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    args = ["flight", str(GOLDEN / "golf.trajectory.parquet"), str(GOLDEN / "golf-teeshot-640x360.mcap")]
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    assert main(args) == 0
    shown = capsys.readouterr()
    stages = [line for line in shown.err.splitlines() if line.startswith("trackreplay: flight: ")]
    said = ("launch velocity", "every parameter", "uncertainty", "jackknife")
    assert stages == [f"trackreplay: flight: fitting: {s}" for s in said]
    assert main([*args, "--quiet"]) == 0
    quiet = capsys.readouterr()
    assert "trackreplay: flight:" not in quiet.err and quiet.out == shown.out
