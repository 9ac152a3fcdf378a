"""Golden logs: committed inputs whose replay digest and trajectory must not move unless a change says so."""

import json
from pathlib import Path

import numpy as np
import polars as pl
import pytest

from trackreplay.replay.core.engine import ReplayRequest, replay
from trackreplay.replay.core.trajectory import FLOAT_COLUMNS

GOLDEN = Path(__file__).parent / "golden"
EXPECTED = json.loads((GOLDEN / "expected.json").read_text())


@pytest.mark.parametrize("tracker", sorted(EXPECTED))
def test_golden_replay(tracker: str) -> None:
    case = EXPECTED[tracker]
    result = replay(ReplayRequest(log=GOLDEN / case["log"], tracker=tracker, seed=case["seed"]))
    golden = pl.read_parquet(GOLDEN / f"{tracker}.trajectory.parquet")
    assert result.frames == case["frames"]
    # The trajectory first: when it holds, a digest change is in the intermediates only.
    assert result.trajectory.select("frame", "track_id", "status").equals(golden.select("frame", "track_id", "status"))
    for column in FLOAT_COLUMNS:
        ours, theirs = result.trajectory[column].to_numpy(), golden[column].to_numpy()
        np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-6, equal_nan=True, err_msg=f"{tracker}: column {column}")
    assert result.digest == case["digest"], (
        f"{tracker} replay of {case['log']} changed; if intended, run python tests/golden/regenerate.py and say why"
    )


def test_golden_groups_log_tracks_two_groups_in_the_world_frame() -> None:
    """The groups golden exercises more than one group (the association between groups, and the
    merge gate on a pair), and its rows are in the world frame the log's rig pose gives."""
    golden = pl.read_parquet(GOLDEN / "groups.trajectory.parquet")
    measured = golden.filter(pl.col("status") == "measured").group_by("track_id").len()
    assert measured.filter(pl.col("len") >= 10).height >= 2, measured
    both = golden.filter(pl.col("status") == "measured").group_by("frame").len().filter(pl.col("len") >= 2)
    assert both.height >= 10
    assert golden.filter(pl.col("status") == "measured")["Z"].median() == pytest.approx(1.19, abs=0.4)  # torso height, Z up
