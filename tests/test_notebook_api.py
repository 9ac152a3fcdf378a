"""The notebook API beyond ``replay_log``: ``open_log`` (frames, truth, marks), ``evaluate`` (a log's
truth or a corpus manifest), ``smooth`` and ``export``, each agreeing with the command it stands for."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import polars as pl
import pytest

import trackreplay
from trackreplay.replay.cli.main import main
from trackreplay.schemas.errors import LogError, TrackreplayError

GOLDEN = Path(__file__).parent / "golden"
LOG = GOLDEN / "flow-sim1-24f.mcap"
GROUPS = GOLDEN / "groups-crossing-320x240.mcap"


@pytest.fixture(scope="module")
def flow() -> trackreplay.ReplayResult:
    return trackreplay.replay_log(LOG, "flow")


def test_the_new_functions_are_on_the_package() -> None:
    assert {"open_log", "evaluate", "smooth", "export"} <= set(dir(trackreplay))
    for name in ("open_log", "evaluate", "smooth", "export"):
        assert getattr(trackreplay, name).__doc__


def test_open_log_gives_frames_as_arrays_by_index_slice_and_iteration(tmp_path: Path) -> None:
    from trackreplay.replay.cli.commands.frame import frame_image
    from trackreplay.replay.log.reader import LogReader

    log = trackreplay.open_log(LOG)
    assert len(log.frames) == 24 and log.image_topic == "/camera/image"
    reader = LogReader(LOG)
    for i in (0, 7, 23):
        np.testing.assert_array_equal(log.frames[i], frame_image(reader, "/camera/image", i))
    np.testing.assert_array_equal(log.frames[-1], log.frames[23])
    sliced = log.frames[5:8]
    assert len(sliced) == 3 and all(np.array_equal(a, log.frames[5 + k]) for k, a in enumerate(sliced))
    every = list(log.frames)
    assert len(every) == 24 and every[0].dtype == np.uint8 and every[0].shape == (256, 256)
    assert [f for f, _, _ in log.frames.items()] == list(range(24))
    with pytest.raises(IndexError):
        log.frames[24]
    bundles = list(log.bundles())
    assert [b.index for b in bundles] == list(range(24)) and bundles[0].hints


def test_open_log_truth_marks_topics_and_times() -> None:
    log = trackreplay.open_log(LOG)
    assert isinstance(log.truth, pl.DataFrame) and log.truth.height == 24
    assert log.truth.filter(pl.col("frame") == 0).select("x", "y").row(0) == (148.0, 128.0)
    assert log.marks.rows() == [(0, 0, "target", 148.0, 128.0, 13.0, 13.0)]
    assert set(log.topics["topic"]) == {"/annotations/init", "/camera/image", "/groundtruth/objects"}
    assert log.times["frame"].to_list() == list(range(24)) and log.times["t_ns"][1] > 0
    assert log.info()["messages"] == 24 + 24 + 1


def test_open_log_of_a_stereo_log_and_of_a_log_without_truth_or_marks(tmp_path: Path) -> None:
    stereo = trackreplay.open_log(GROUPS)
    assert stereo.image_topic == "/stereo/left/image"
    first = next(stereo.bundles())
    assert first.right is not None and first.right.shape == stereo.frames[0].shape
    assert stereo.truth_table("/groundtruth/groups").height > 0 and stereo.truth["Z"].drop_nulls().len() > 0
    bare = tmp_path / "bare.mcap"
    assert main(["filter", str(LOG), str(bare), "--topic", "/camera/image"]) == 0
    log = trackreplay.open_log(bare)
    assert log.truth.is_empty() and log.marks.is_empty() and len(log.frames) == 24
    with pytest.raises(LogError, match="no topic /nowhere"):
        trackreplay.open_log(LOG, image_topic="/nowhere")


def test_evaluate_a_log_matches_the_eval_command(flow, tmp_path: Path) -> None:
    traj, metrics = tmp_path / "t.parquet", tmp_path / "m.json"
    flow.trajectory.write_parquet(traj)
    assert main(["eval", str(traj), str(LOG), "--json", str(metrics)]) == 0
    expected = json.loads(metrics.read_text())
    for given in (flow, flow.trajectory, traj, str(traj)):
        row = trackreplay.evaluate(LOG, given).row(0, named=True)
        assert row == pytest.approx(expected)
    assert trackreplay.evaluate(LOG, tracker="flow").row(0, named=True) == pytest.approx(expected)
    with pytest.raises(TrackreplayError, match="either a trajectory or a tracker"):
        trackreplay.evaluate(LOG)


def test_evaluate_mot_gives_one_row_per_space(tmp_path: Path) -> None:
    result = trackreplay.replay_log(GROUPS, "groups")
    table = trackreplay.evaluate(GROUPS, result, mot=True)
    assert table["space"].to_list() == ["image", "3d"]
    traj, metrics = tmp_path / "t.parquet", tmp_path / "m.json"
    result.trajectory.write_parquet(traj)
    assert main(["eval", str(traj), str(GROUPS), "--mot", "--json", str(metrics)]) == 0
    expected = json.loads(metrics.read_text())
    for row in table.iter_rows(named=True):
        space = row.pop("space")
        hota_alpha = row.pop("hota_alpha")
        assert hota_alpha == pytest.approx(expected["hota"][space].pop("hota_alpha"))
        assert row == pytest.approx({**expected[space], **expected["hota"][space]})


def test_evaluate_refuses_a_trajectory_of_another_log(flow) -> None:
    shifted = flow.trajectory.with_columns(pl.col("t_ns") + 1)
    with pytest.raises(TrackreplayError, match="was not replayed from this log"):
        trackreplay.evaluate(LOG, shifted)


SUITE = """
[corpus]
name = "notebook"

[[case]]
name = "square"
synth = "flow-sim1"
synth_options = { frames = 6 }
trackers = ["flow"]
"""


def test_evaluate_a_corpus_manifest_gives_the_cases_table(tmp_path: Path) -> None:
    suite = tmp_path / "suite.toml"
    suite.write_text(SUITE)
    table = trackreplay.evaluate(suite, seeds=(0, 1), out=tmp_path / "out")
    assert table.select("case", "tracker", "seed", "status").rows() == [("square", "flow", 0, "ok"), ("square", "flow", 1, "ok")]
    assert (tmp_path / "out" / "logs").is_dir()
    assert main(["evaluate", str(suite), "--out", str(tmp_path / "cli"), "--seeds", "0-1", "--serial", "--no-baseline",
                 "--quiet"]) == 0
    assert table.equals(pl.read_parquet(tmp_path / "cli" / "cases.parquet"))
    assert trackreplay.evaluate(suite).height == 1  # a temporary folder when no out is given


def test_smooth_matches_the_smooth_command(flow, tmp_path: Path) -> None:
    traj, out = tmp_path / "t.parquet", tmp_path / "s.parquet"
    flow.trajectory.write_parquet(traj)
    assert main(["smooth", str(traj), str(LOG), "--out", str(out)]) == 0
    ours = trackreplay.smooth(flow.trajectory, LOG)
    assert ours.equals(pl.read_parquet(out))
    assert {"x_std", "fill"} <= set(ours.columns) and ours.height == 24
    # a result with the trackers' raw measurements smooths as `replay --smooth` does
    from trackreplay.replay.core.engine import ReplayRequest, replay

    raw = replay(ReplayRequest(log=LOG, tracker="flow", observations=True))
    assert main(["replay", str(LOG), "--tracker", "flow", "--quiet", "--export", str(tmp_path / "r.parquet"), "--smooth"]) == 0
    assert trackreplay.smooth(raw, LOG).equals(pl.read_parquet(tmp_path / "r.parquet"))
    with pytest.raises(TrackreplayError, match="was not replayed from this log"):
        trackreplay.smooth(flow.trajectory.with_columns(pl.col("t_ns") + 1), LOG)


def test_export_matches_the_export_command_and_keeps_smoothing_columns(flow, tmp_path: Path) -> None:
    gappy = flow.trajectory.filter(~pl.col("frame").is_in([5, 6]))
    source, cli = tmp_path / "gappy.parquet", tmp_path / "cli.csv"
    gappy.write_parquet(source)
    assert main(["export", str(source), str(cli)]) == 0
    written = trackreplay.export(gappy, tmp_path / "api.csv")
    assert (tmp_path / "api.csv").read_bytes() == cli.read_bytes()
    assert written.filter(pl.col("frame").is_in([5, 6]))["status"].to_list() == ["interpolated"] * 2
    kept = trackreplay.export(gappy, tmp_path / "none.parquet", interpolate="none")
    assert kept.height == 22
    smoothed = trackreplay.smooth(flow, LOG)
    trackreplay.export(smoothed, tmp_path / "s.parquet")
    assert pl.read_parquet(tmp_path / "s.parquet").equals(smoothed)  # (its gaps are filled: nothing added)
    mot = tmp_path / "t.txt"
    trackreplay.export(flow, mot)
    assert mot.read_text().splitlines()[0].startswith("1,1,")
    with pytest.raises(TrackreplayError, match="unknown trajectory format"):
        trackreplay.export(flow, tmp_path / "t.json")


def test_a_damaged_chunk_costs_only_its_frames(tmp_path: Path) -> None:
    """Iteration skips the frames a damaged chunk held (``items`` keeps the others' numbers); asking for
    one of them by index is a one-sentence error."""
    from mcap.reader import make_reader

    with open(LOG, "rb") as fh:
        summary = make_reader(fh).get_summary()
    chunk = sorted(summary.chunk_indexes, key=lambda c: c.chunk_start_offset)[1]
    data = bytearray(LOG.read_bytes())
    data[chunk.chunk_start_offset + chunk.chunk_length // 2] ^= 0x04
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(bytes(data))
    log = trackreplay.open_log(bad)
    kept = [frame for frame, _, _ in log.frames.items()]
    lost = sorted(set(range(24)) - set(kept))
    assert lost and len(list(log.frames)) == len(kept)
    np.testing.assert_array_equal(log.frames[kept[-1]], trackreplay.open_log(LOG).frames[kept[-1]])
    with pytest.raises(LogError, match=f"frame {lost[0]} on /camera/image is lost"):
        log.frames[lost[0]]
