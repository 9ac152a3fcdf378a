"""Golden logs: committed inputs whose replay digest must not move unless a change says so."""

import json
from pathlib import Path

import pytest

from replay.engine import ReplayRequest, replay

GOLDEN = Path(__file__).parent / "golden"
EXPECTED = json.loads((GOLDEN / "expected.json").read_text())


@pytest.mark.parametrize("tracker", sorted(EXPECTED))
def test_golden_digest(tracker: str) -> None:
    case = EXPECTED[tracker]
    result = replay(ReplayRequest(log=GOLDEN / case["log"], tracker=tracker, seed=case["seed"]))
    assert result.frames == case["frames"]
    assert result.digest == case["digest"], (
        f"{tracker} replay of {case['log']} changed; if intended, run python tests/golden/regenerate.py and say why"
    )
