"""trackreplay diff: first diverging frame and field, from live runs and from summaries' sidecars."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from trackreplay.replay.cli.main import main
from trackreplay.replay.core.digest import ReplayDigest, _frame_path, leaf_values
from trackreplay.replay.analysis.diff import RunSpec, diff_runs, sidecar_path
from trackreplay.replay.core.engine import ReplayRequest, iter_steps, replay

GOLDEN = Path(__file__).resolve().parents[2] / "golden"
GOLF = GOLDEN / "golf-teeshot-640x360.mcap"


def _outputs(req: ReplayRequest) -> list[tuple[int, dict]]:
    return [(s.frame.index, {_frame_path(p): v for p, v in leaf_values((s.intermediates, s.states)) if p != "len"})
            for s in iter_steps(req)]


def _same(a, b) -> bool:
    if isinstance(a, str) or a is None or isinstance(b, str) or b is None:
        return a == b
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and np.array_equal(a, b, equal_nan=a.dtype.kind == "f")


def test_per_frame_recording_leaves_the_digest_unchanged(short_sim: Path) -> None:
    plain, recorded = ReplayDigest(), ReplayDigest(per_frame=True)
    result = replay(ReplayRequest(log=short_sim, tracker="flow", frame_digests=True))
    assert replay(ReplayRequest(log=short_sim, tracker="flow")).frame_digests is None  # only when asked
    for step in iter_steps(ReplayRequest(log=short_sim, tracker="flow")):
        plain.add_frame(step.frame.index, (step.intermediates, step.states))
        recorded.add_frame(step.frame.index, (step.intermediates, step.states))
    assert plain.finish(result.trajectory) == recorded.finish(result.trajectory) == result.digest
    assert len(result.frame_digests) == result.frames
    assert result.frame_digests.table()["frame"].unique().len() == result.frames


def test_identical_runs(short_sim: Path, capsys: pytest.CaptureFixture) -> None:
    assert main(["diff", str(short_sim), str(short_sim), "--tracker", "flow"]) == 0
    digest = replay(ReplayRequest(log=short_sim, tracker="flow")).digest
    assert capsys.readouterr().out.strip() == f"identical: 12 frames, digest {digest}"


def test_a_perturbed_config_is_pinpointed() -> None:
    """golf with max_predicted_frames=1 reports a miss as lost earlier (and its confidence, calibrated on
    the misses over lost_after, differs from the first miss): the diff must name the first frame that
    differs and its fields, and everything before it must really be equal."""
    a = RunSpec(GOLF, "golf")
    b = RunSpec(GOLF, "golf", config={"max_predicted_frames": 1})
    result = diff_runs(a, b)
    assert not result.identical and result.frame is not None
    out_a = _outputs(ReplayRequest(log=GOLF, tracker="golf"))
    out_b = _outputs(ReplayRequest(log=GOLF, tracker="golf", config=b.config))
    first = next(i for (i, va), (_, vb) in zip(out_a, out_b) if va.keys() != vb.keys() or not all(_same(va[k], vb[k]) for k in va))
    assert result.frame == first
    va, vb = out_a[first][1], out_b[first][1]
    differing = [k for k in va if not _same(va[k], vb.get(k))]
    assert [f.field for f in result.fields][:len(differing)] == differing
    # the first frame that differs is the first miss: the reported confidence's evidence counts misses
    # over lost_after (trackers/golf/calibration.py); the status differs on the next miss, predicted vs lost
    assert differing == ["intermediates.evidence.misses", "states.0.confidence"]
    later = next(i for (i, va), (_, vb) in zip(out_a, out_b) if va.get("states.0.status") != vb.get("states.0.status"))
    assert later > first and (out_a[later][1]["states.0.status"], out_b[later][1]["states.0.status"]) == ("predicted", "lost")
    assert result.trajectory_diverges and result.trajectory_equal_until == first - 1
    assert result.report().startswith(f"frame {first}: ")


def test_a_different_seed_via_the_cli_exits_non_zero(capsys: pytest.CaptureFixture) -> None:
    assert main(["diff", str(GOLF), str(GOLF), "--tracker", "golf", "--b", "seed=1"]) == 1
    first = capsys.readouterr().out.splitlines()[0]
    assert first.startswith("frame 0: ") and "max |Δ|" in first


def test_summaries_and_their_sidecars(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    expected = replay(ReplayRequest(log=GOLF, tracker="golf")).digest
    a, b, c = tmp_path / "a.json", tmp_path / "b.json", tmp_path / "c.json"
    assert main(["replay", str(GOLF), "--tracker", "golf", "--quiet", "--summary", str(a)]) == 0
    assert main(["replay", str(GOLF), "--tracker", "golf", "--quiet", "--summary", str(c)]) == 0
    assert main(["replay", str(GOLF), "--tracker", "golf", "--quiet", "--seed", "1", "--summary", str(b)]) == 0
    summary = json.loads(a.read_text())
    assert summary["digest"] == expected  # the sidecar leaves the digest alone
    assert summary["frame_digests"] == sidecar_path(a).name and sidecar_path(a).exists()
    assert summary["config"]["particles"]["n"] == 1000
    capsys.readouterr()
    assert main(["diff", str(a), str(c)]) == 0
    assert capsys.readouterr().out.startswith("identical: 60 frames")
    assert main(["diff", str(a), str(b)]) == 1
    report = capsys.readouterr().out
    assert report.startswith("frame 0: ") and "states.0.vx differ, max |Δ|" in report  # small fields keep values
    # a summary against a live run of the same log
    assert main(["diff", str(b), str(GOLF), "--tracker", "golf", "--b", "seed=1"]) == 0


def test_a_summary_without_sidecar_is_a_clear_error(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    s = tmp_path / "s.json"
    s.write_text(json.dumps({"digest": "00", "frames": 1}))
    assert main(["diff", str(s), str(s)]) == 2
    assert "no per-frame digests" in capsys.readouterr().err
    assert main(["diff", str(tmp_path / "x.txt"), str(s)]) == 2


@pytest.mark.parametrize("extra, message", [
    (["--tracker", "golf"], "--tracker applies only to a .mcap operand (a log replayed here), and neither"),
    (["--seed", "3"], "--seed applies only to a .mcap operand"),
    (["--set", "golf.particles.n=5"], "--set applies only to a .mcap operand"),
    (["--config", "c.toml"], "--config applies only to a .mcap operand"),
    (["--a", "seed=1"], "--a seed=1 applies only to a .mcap operand (a log replayed here), and A.json is a replay summary"),
    (["--b", "particles.n=5"], "--b particles.n=5 applies only to a .mcap operand (a log replayed here), and B.json is a"),
])
def test_run_options_on_summaries_are_refused(extra, message, short_sim: Path, tmp_path: Path, capsys) -> None:
    """A review: they were silently ignored when an operand is a summary."""
    a, b = tmp_path / "A.json", tmp_path / "B.json"
    for s in (a, b):
        assert main(["replay", str(short_sim), "--summary", str(s), "--quiet"]) == 0
    capsys.readouterr()
    assert main(["diff", str(a), str(b), *extra]) == 2
    err = capsys.readouterr().err.replace(str(tmp_path) + "/", "")
    assert err.count("\n") == 1 and message in err
    # one side a log: the options apply to it
    assert main(["diff", str(a), str(short_sim), "--b", "seed=0"]) == 0


def test_summaries_of_different_trackers_or_logs_say_so_first(short_sim: Path, tmp_path: Path, capsys) -> None:
    flow, golf = tmp_path / "flow.json", tmp_path / "golf.json"
    assert main(["replay", str(short_sim), "--summary", str(flow), "--quiet"]) == 0
    assert main(["replay", str(GOLF), "--tracker", "golf", "--summary", str(golf), "--quiet"]) == 0
    capsys.readouterr()
    assert main(["diff", str(flow), str(golf)]) == 1
    assert capsys.readouterr().out.splitlines()[0] == (
        "A and B replay a different tracker (flow vs golf) and log (short.mcap vs golf-teeshot-640x360.mcap)")
    assert main(["diff", str(flow), str(GOLF), "--tracker", "golf"]) == 1
    assert capsys.readouterr().out.startswith("A and B replay a different tracker (flow vs golf) and log")
    assert main(["diff", str(flow), str(short_sim)]) == 0
    assert capsys.readouterr().out.startswith("identical: 12 frames")


def test_a_seed_opencv_cannot_take_is_one_sentence(short_sim: Path, capsys) -> None:
    assert main(["diff", str(short_sim), str(short_sim), "--b", f"seed={10**40}"]) == 2
    assert capsys.readouterr().err.strip() == (f"trackreplay: error: seed {10**40} is not a valid seed: give an integer "
                                               f"from 0 to 2147483647 (OpenCV's random generator takes a 32-bit int)")


def test_a_key_given_twice_is_refused_as_batch_refuses_it(short_sim: Path, capsys) -> None:
    """A review: ``--set flow.q=1 --set q=2`` ran with the last one; batch refuses the same input."""
    assert main(["diff", str(short_sim), str(short_sim), "--tracker", "flow", "--set", "flow.q=1", "--set", "q=2"]) == 2
    assert "--set q given twice (as flow.q)" in capsys.readouterr().err


def test_a_seed_or_config_given_two_ways_is_refused(short_sim: Path, capsys) -> None:
    """A review: ``--seed 1 --set seed=2`` ran seed 2 without a word; a side's repeat names its side."""
    assert main(["diff", str(short_sim), str(short_sim), "--seed", "1", "--set", "seed=2"]) == 2
    assert "--seed and --set seed=... both give the seed" in capsys.readouterr().err
    assert main(["diff", str(short_sim), str(short_sim), "--b", "seed=1", "--b", "seed=2"]) == 2
    assert "--b seed given twice" in capsys.readouterr().err


@pytest.mark.slow  # two replays of the short simulation (~8 s on 2 loaded cores)
def test_a_batch_task_writes_its_sidecar_without_reading_the_digests_whole(short_sim: Path, tmp_path: Path,
                                                                           monkeypatch) -> None:
    """Issue 33: a batch task copies the per-frame digests to its sidecar a row group at a time (a spilled
    replay's spill file as it is), never as one table; `diff` reads the same digests from it."""
    import polars as pl

    from trackreplay.replay.analysis.diff import read_sidecar
    from trackreplay.replay.core.digest import FrameDigests
    from trackreplay.replay.runs.batch import BatchOptions, plan, run_task

    whole = replay(ReplayRequest(log=short_sim, tracker="flow", frame_digests=True)).frame_digests.table()

    def refuse(self):
        raise AssertionError("the per-frame digests were read whole")

    monkeypatch.setattr(FrameDigests, "table", refuse)
    (task,) = plan([short_sim], "flow", [0], [])
    row = run_task(task, BatchOptions(out=tmp_path))
    assert row["status"] == "ok", row["error"]
    side = sidecar_path(tmp_path / "tasks" / task.name / "summary.json")
    assert pl.read_parquet(side).equals(whole)
    assert read_sidecar(side).frames == FrameDigests.from_table(whole).frames
