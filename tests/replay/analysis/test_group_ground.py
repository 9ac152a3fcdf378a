"""Group truth from people's world tracks and the group scores on the ground (replay/analysis/group_ground.py)."""

import numpy as np
import polars as pl
import pytest

from trackreplay.replay.analysis.group_ground import GroupRule, derive_groups, group_events, group_ground_scores, together

FPS = 10.0


def _truth(tracks: dict[int, np.ndarray], first: int = 0) -> pl.DataFrame:
    """Rows frame, t_ns, id, X, Y, visible from (T, 2) ground tracks (NaN: absent)."""
    rows = [(first + f, int((first + f) * 1e9 / FPS), pid, float(x), float(y), True)
            for pid, xy in tracks.items() for f, (x, y) in enumerate(xy) if np.isfinite(x)]
    return pl.DataFrame(rows, schema={"frame": pl.Int64, "t_ns": pl.Int64, "id": pl.Int64, "X": pl.Float64,
                                      "Y": pl.Float64, "visible": pl.Boolean}, orient="row")


def _walk(start, velocity, frames: int = 60) -> np.ndarray:
    t = np.arange(frames)[:, None] / FPS
    return np.asarray(start, float) + t * np.asarray(velocity, float)


def _scene() -> dict[int, np.ndarray]:
    """1 and 2 walk side by side 1 m apart; 3 walks towards them and joins them (at 1 m/s, the same
    velocity) from frame 30; 4 walks alone far away."""
    three = _walk([0.0, 1.8], [1.0, 0.0])  # beside the pair (0.8 m from 2) from frame 30 on
    three[:30, 1] = np.linspace(-3.0, 1.8, 30)  # before: crossing towards them at 1.6 m/s in Y
    return {1: _walk([0, 0], [1, 0]), 2: _walk([0, 1], [1, 0]), 3: three, 4: _walk([20, 20], [-1, 0])}


def test_links_need_one_second_and_short_gaps_are_closed() -> None:
    rule = GroupRule(min_duration_s=1.0, gap_s=0.5)
    link = np.array([True] * 6 + [False] * 3 + [True] * 6 + [False] * 10 + [True] * 5)
    out = together(link, FPS, rule)
    assert out[:15].all()  # 6 + a 3-frame gap (<= 0.5 s) + 6: one run of 1.5 s
    assert not out[15:].any()  # 5 frames: 0.5 s, not together


def test_the_rule_finds_the_pair_the_joiner_and_the_loner() -> None:
    groups = derive_groups(_truth(_scene()), GroupRule())
    at = {f: dict(zip(g["id"].to_list(), g["group"].to_list())) for (f,), g in groups.group_by(["frame"])}
    assert at[5][1] == at[5][2] != at[5][3] and at[5][4] not in (at[5][1], at[5][3])
    assert at[55][1] == at[55][2] == at[55][3] != at[55][4]
    # 3 joins once its velocity has matched theirs for a second (the velocity is a 1 s slope): within 1.5 s
    events = group_events(groups)
    merges = [(f, parts) for kind, f, parts in events if kind == "merge"]
    assert len(merges) == 1 and 30 <= merges[0][0] <= 45 and sorted(map(sorted, merges[0][1])) == [[1, 2], [3]]
    assert not [e for e in events if e[0] == "split"]


def test_the_scores_of_a_tracker_that_holds_the_groups_and_one_of_a_tracker_that_sees_nothing_right() -> None:
    truth = _truth(_scene())
    groups = derive_groups(truth)
    centres = groups.group_by("frame", "group").agg(pl.col("X").mean(), pl.col("Y").mean()).sort("frame", "group")
    perfect = centres.select("frame", pl.col("group").alias("track_id"), "X", "Y", pl.lit("measured").alias("status"))
    s = group_ground_scores(perfect, truth)
    assert s.person_coverage == 1.0 and s.wrong_rate == 0.0 and s.people == 4 and s.people_at_goal == 4
    assert s.group_mota == pytest.approx(1.0) and s.group_idf1 == pytest.approx(1.0)
    assert s.merges == 1 and s.merges_found == 1 and s.truth_groups == 2  # {1, 2} and {1, 2, 3}
    between = perfect.with_columns(pl.lit(10.0).alias("X"), pl.lit(10.0).alias("Y"))  # inside the area, nobody there
    bad = group_ground_scores(between, truth)
    assert bad.person_coverage == 0.0 and bad.wrong_rate == 1.0 and bad.merges_found == 0 and bad.group_mota < 0
    far = perfect.with_columns(pl.col("X") + 50.0)  # beyond where the truth labels anyone: not scored
    away = group_ground_scores(far, truth)
    assert away.outside_rows == far.height and away.measured_rows == 0 and np.isnan(away.wrong_rate)
    assert away.person_coverage == 0.0 and away.group_mota == 0.0  # every group missed, no false positive
    predicted = group_ground_scores(perfect.with_columns(pl.lit("predicted").alias("status")), truth)
    assert predicted.person_coverage == 0.0 and predicted.measured_rows == 0  # coverage counts measured rows only
