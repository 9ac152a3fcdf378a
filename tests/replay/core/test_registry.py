"""The tracker registry: ``ball`` is another name for the golf tracker, resolved where a name comes
in, so a replay by either name is the same replay (seed stream, config table, digest)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest
from trackreplay.replay.cli.main import main
from trackreplay.replay.core import registry
from trackreplay.replay.core.engine import ReplayRequest
from trackreplay.replay.runs.corpus import parse_case
from trackreplay.schemas.errors import SourceError, TrackreplayError


def test_ball_is_the_golf_tracker() -> None:
    assert registry.canonical("ball") == "golf" and registry.canonical("flow") == "flow"
    assert registry.get("ball").tracker_cls is registry.get("golf").tracker_cls
    assert registry.known("ball") and not registry.known("tennis")
    assert ReplayRequest(log=Path("x.mcap"), tracker="ball").tracker == "golf"
    with pytest.raises(TrackreplayError, match="unknown tracker 'tennis'.*ball = golf"):
        registry.get("tennis")


def test_a_tracker_cannot_be_registered_under_an_alias() -> None:
    spec = dataclasses.replace(registry.get("golf"), name="ball")
    with pytest.raises(TrackreplayError, match="already registered"):
        registry.register(spec)
    assert "ball" not in registry.NAMES


def test_a_replay_named_ball_is_the_golf_replay(golf_short: Path, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    digests = []
    for name in ("golf", "ball"):
        assert main(["replay", str(golf_short), "--tracker", name, "--end", "0.4", "--set", "golf.max_predicted_frames=3",
                     "--summary", str(tmp_path / f"{name}.json")]) == 0
        out = capsys.readouterr().out
        assert out.startswith("golf: ")  # the tracker's own name, whichever was given
        digests.append(out.split("digest ")[-1].strip())
    assert digests[0] == digests[1]


def test_a_corpus_case_may_name_ball(tmp_path: Path) -> None:
    case = parse_case({"name": "c", "video": "v.mp4", "truth": "t.csv", "truth_format": "points", "trackers": ["ball", "golf"]},
                      tmp_path, "case c")
    assert case.trackers == ("golf",)
    with pytest.raises(SourceError, match="ball = golf"):
        parse_case({"name": "c", "video": "v.mp4", "truth": "t.csv", "truth_format": "points", "trackers": ["tennis"]},
                   tmp_path, "case c")
