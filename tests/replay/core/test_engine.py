"""The replay loop as an iterator: what replay() consumes, prepare always called, early exit."""

from __future__ import annotations

import dataclasses
import threading
from operator import attrgetter
from pathlib import Path

import pytest

from trackreplay.replay.core import registry
from trackreplay.replay.core.digest import ReplayDigest
from trackreplay.replay.core.engine import ReplayRequest, ReplayStep, iter_steps, replay
from trackreplay.replay.core.trajectory import state_row, trajectory_table
from trackreplay.trackers.base import TrackerBase
from trackreplay.trackers.flow.tracker import FlowTracker


def test_steps_rebuild_exactly_what_replay_returns(short_sim: Path) -> None:
    req = ReplayRequest(log=short_sim, tracker="flow")
    digest, rows, indices = ReplayDigest(), [], []
    for step in iter_steps(req):
        assert isinstance(step, ReplayStep) and isinstance(step.states, tuple)
        indices.append(step.frame.index)
        digest.add_frame(step.frame.index, (step.intermediates, step.states))
        rows += [state_row("flow", step.frame.index, step.frame.t_ns, s) for s in step.states]
    table = trajectory_table(rows)
    result = replay(req)
    assert indices == list(range(result.frames))
    assert table.equals(result.trajectory)
    assert digest.finish(table) == result.digest


def test_prepare_is_part_of_the_protocol_and_always_called(short_sim: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    assert TrackerBase.prepare(FlowTracker.__new__(FlowTracker), [(None, ())]) is None  # the documented no-op
    seen: list[list] = []

    class Recording(FlowTracker):
        def prepare(self, marked) -> None:
            seen.append(list(marked))

    spec = dataclasses.replace(registry.get("flow"), tracker_cls=Recording)
    monkeypatch.setattr(registry, "get", lambda name: spec)
    steps = iter_steps(ReplayRequest(log=short_sim, tracker="flow"))
    assert len(seen) == 1  # on construction, before any step
    (image, regions), = seen[0]  # the sim marks its target in frame 0
    assert image.shape == (256, 256) and [r.frame for r in regions] == [0]
    steps.close()


def test_leaving_the_loop_early_stops_the_reader_thread(short_sim: Path) -> None:
    steps = iter_steps(ReplayRequest(log=short_sim, tracker="flow", prefetch=2))
    first = next(steps)
    assert first.frame.index == 0
    steps.close()
    assert not any(t.name == "trackreplay-prefetch" and t.is_alive() for t in threading.enumerate())


def test_a_bad_config_fails_before_the_first_step(short_sim: Path) -> None:
    from trackreplay.schemas.errors import TrackreplayError

    with pytest.raises(TrackreplayError, match="unknown key fovv"):
        iter_steps(ReplayRequest(log=short_sim, tracker="flow", config={"fovv": 3}))


def test_notices_are_hashed_into_the_digest_printed_once_and_returned(short_sim: Path, monkeypatch: pytest.MonkeyPatch,
                                                                      capsys: pytest.CaptureFixture) -> None:
    from dataclasses import dataclass
    from typing import Any

    @dataclass(frozen=True)
    class Noted:
        inner: Any
        notice: str

    def run(text: str):
        class Noting(FlowTracker):
            def step(self, frame):
                states = super().step(frame)
                self.intermediates = Noted(self.intermediates, text if frame.index >= 2 else "")
                return states

        # the spec declares where a notice is read (flow's own intermediates have none)
        spec = dataclasses.replace(registry.get("flow"), tracker_cls=Noting, notice=attrgetter("notice"))
        monkeypatch.setattr(registry, "get", lambda name: spec)
        result = replay(ReplayRequest(log=short_sim, tracker="flow"))
        monkeypatch.undo()
        return result

    a, b = run("mode A"), run("mode B")
    assert a.notices == ("mode A",) and b.notices == ("mode B",)
    assert capsys.readouterr().err.count("trackreplay: flow: mode A") == 1
    assert a.trajectory.equals(b.trajectory) and a.digest != b.digest
    assert a.summary(short_sim)["notices"] == ["mode A"]


def test_a_mark_outside_the_replayed_window_starts_nothing(tmp_path) -> None:
    """A review replayed a log marked on frame 0 from --start 1.5: the colour PF put frame 0's box on
    frame 45 and reported 75 rows measured at confidence 1. Marks outside --start/--end are not used
    now, and the replay says so."""
    from pathlib import Path

    from trackreplay.replay.core.engine import ReplayRequest, replay

    from trackreplay.replay.cli.main import main as cli
    from trackreplay.schemas.errors import LogError

    log = Path(__file__).resolve().parents[2] / "golden" / "colorpf-approach-320x240.mcap"  # marked on frame 8
    whole = replay(ReplayRequest(log=log, tracker="colorpf"))
    assert (whole.trajectory["status"] == "measured").sum() > 0
    with pytest.raises(LogError, match=r"marks none on the frames replayed \(--start/--end\)"):
        replay(ReplayRequest(log=log, tracker="colorpf", start_s=0.5))  # its only mark is before the window
    twice = tmp_path / "twice.mcap"  # a second mark, on frame 30 (1.0 s), after the window below
    assert cli(["annotate", str(log), "--frame", "30", "--box", "150,70,14,40", "--out", str(twice)]) == 0
    early = replay(ReplayRequest(log=twice, tracker="colorpf", end_s=0.9))
    assert (early.trajectory["status"] == "measured").sum() > 0
    assert any("1 of the log's 2 mark(s) are on frames outside --start/--end and are not used" in n for n in early.notices)


@pytest.mark.parametrize("kwargs, message", [
    ({"start_s": 1.0, "end_s": 0.5}, "end_s 0.5 must be after start_s 1"),
    ({"start_s": -5.0}, "start_s must be a finite number of seconds >= 0"),
    ({"start_s": float("nan")}, "start_s must be a finite number"),
    ({"seed": -1}, "seed -1 is not a valid seed: give an integer from 0 to 2147483647"),
    ({"seed": "1"}, "seed '1' is not a valid seed"),
    ({"seed": 2**31}, "seed 2147483648 is not a valid seed: give an integer from 0 to 2147483647"),  # cv2's C int
])
def test_the_python_api_checks_what_the_cli_parser_checks(kwargs, message) -> None:
    """A review found replay_log(start_s=1, end_s=0.5) returning 0 frames and seed=-1 failing deep in numpy."""
    from pathlib import Path

    from trackreplay.replay.core.api import replay_log
    from trackreplay.schemas.errors import TrackreplayError

    log = Path(__file__).resolve().parents[2] / "golden" / "flow-sim1-24f.mcap"
    with pytest.raises(TrackreplayError, match=message):
        replay_log(log, "flow", **kwargs)


@pytest.mark.parametrize("tracker, message", [
    ("colorpf", "the colorpf tracker starts only from a marked box and the log marks none; mark one with"),
    ("golf", "the golf tracker starts only from a marked box and the log marks none; mark one with"),
    ("groups", "the groups tracker needs a calibrated stereo pair"),
])
def test_a_replay_its_tracker_cannot_start_on_is_refused(tracker, message, capsys, tmp_path) -> None:
    """Before: exit 0 with a trajectory of no row and a notice ("nothing is tracked") that a script
    running many replays never reads. Now bad input: one sentence naming the log, exit 2, before any
    frame is decoded."""
    from pathlib import Path

    from trackreplay.replay.cli.main import main as cli

    golden = Path(__file__).resolve().parents[2] / "golden" / "flow-sim1-24f.mcap"
    log = tmp_path / "unmarked.mcap"  # its images alone: no mark, no stereo pair
    assert cli(["filter", str(golden), str(log), "--topic", "/camera/image"]) == 0
    capsys.readouterr()
    assert cli(["replay", str(log), "--tracker", tracker, "--quiet"]) == 2
    err = capsys.readouterr().err
    assert f"trackreplay: error: {log}: {message}" in err and err.count("\n") == 1


def test_the_tracker_s_own_time_is_counted_apart_from_the_replay_s(short_sim: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """``step_seconds`` is the time inside the tracker's step alone (what evaluate sets beside CSRT's update calls)."""
    import time as clock

    class Slow(FlowTracker):
        def step(self, frame):
            clock.sleep(0.01)
            return super().step(frame)

    spec = dataclasses.replace(registry.get("flow"), tracker_cls=Slow)
    monkeypatch.setattr(registry, "get", lambda name: spec)
    result = replay(ReplayRequest(log=short_sim, tracker="flow"))
    assert result.frames * 0.01 <= result.step_seconds <= result.seconds
    monkeypatch.undo()
    plain = replay(ReplayRequest(log=short_sim, tracker="flow"))
    assert plain.digest == result.digest  # a slower step changes nothing the replay writes
