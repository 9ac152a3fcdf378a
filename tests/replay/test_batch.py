"""trackreplay batch: logs × seeds × --set values on a local Ray; every digest equals a serial replay."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import polars as pl
import pytest

from trackreplay.replay.batch import BatchOptions, RayMissing, plan, run_ray
from trackreplay.replay.batch_config import apply_sets, grid, parse_seeds, parse_set
from trackreplay.replay.cli import main
from trackreplay.replay.engine import ReplayRequest, replay
from trackreplay.schemas.errors import TrackreplayError

GOLF = Path(__file__).resolve().parents[1] / "golden" / "golf-teeshot-640x360.mcap"


def test_seeds_sets_and_grid() -> None:
    assert parse_seeds("0-3,7,2") == [0, 1, 2, 3, 7]
    assert parse_set("golf.particles.n=500,1000") == ("golf.particles.n", [500, 1000])
    assert parse_set("sigmas=[1.0,0.0],[2.0]") == ("sigmas", [[1.0, 0.0], [2.0]])
    assert parse_set("mode=ptz") == ("mode", ["ptz"])
    assert grid(["a=1,2", "b=x,y"]) == [{"a": 1, "b": "x"}, {"a": 1, "b": "y"}, {"a": 2, "b": "x"}, {"a": 2, "b": "y"}]
    assert apply_sets("golf", {"particles": {"n": 10, "x": 1}}, {"golf.particles.n": 500, "lut.bins": 8}) == {
        "particles": {"n": 500, "x": 1}, "lut": {"bins": 8}}
    for bad in ("3-1", "a"):
        with pytest.raises(TrackreplayError):
            parse_seeds(bad)
    with pytest.raises(TrackreplayError, match="particles.nope"):  # checked once, before anything runs
        plan([GOLF], "golf", [0], grid(["golf.particles.nope=1"]))


@pytest.fixture(scope="module")
def local_ray():
    ray = pytest.importorskip("ray")
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    yield ray
    ray.shutdown()


def test_batch_digests_equal_serial_replays_and_a_bad_log_fails_in_its_row(local_ray, tmp_path: Path, capsys) -> None:
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(b"not an mcap file")
    out = tmp_path / "out"
    code = main(["batch", str(GOLF), str(bad), "--tracker", "golf", "--seeds", "0-1", "--set", "golf.particles.n=300,600",
                 "--out", str(out), "--quiet"])
    assert code == 1  # one log failed; the others finished
    table = pl.read_parquet(out / "summary.parquet")
    assert table.height == 8
    assert {"log", "tracker", "seed", "golf.particles.n", "digest", "frames", "seconds", "status", "error",
            "centre_error_mean"} <= set(table.columns)
    good = table.filter(pl.col("status") == "ok")
    assert good.height == 4 and set(good["log"]) == {str(GOLF)}
    for seed, n, digest, frames in good.select("seed", "golf.particles.n", "digest", "frames").iter_rows():
        serial = replay(ReplayRequest(log=GOLF, tracker="golf", seed=seed, config={"particles": {"n": n}}))
        assert (digest, frames) == (serial.digest, serial.frames)
    assert good["digest"].n_unique() == 4
    assert good["centre_error_mean"].null_count() == 0  # the golden log has ground truth
    failed = table.filter(pl.col("status") == "error")
    assert failed.height == 4 and all("bad.mcap" in e and "\n" not in e for e in failed["error"])
    printed = capsys.readouterr().out
    assert "error: " in printed and "4 of 8 replays done" in printed
    task = out / "tasks" / good["task"][0]
    assert {"trajectory.parquet", "summary.json", "summary.frames.parquet"} <= {p.name for p in task.iterdir()}
    assert json.loads((task / "summary.json").read_text())["digest"] == good["digest"][0]


def test_shipped_logs_come_back_as_files(local_ray, short_sim: Path, tmp_path: Path) -> None:
    tasks = plan([short_sim], "flow", [0, 1], [])
    rows = run_ray(tasks, BatchOptions(out=tmp_path), ship_logs=True)
    digest = replay(ReplayRequest(log=short_sim, tracker="flow")).digest
    assert [r["digest"] for r in rows] == [digest, digest]
    assert all((tmp_path / "tasks" / t.name / "trajectory.parquet").exists() for t in tasks)
    assert not any(p.suffix == ".mcap" for p in tmp_path.rglob("*"))  # the shipped copy stays on the worker


def test_without_ray_batch_says_how_to_install_it(monkeypatch, short_sim: Path, tmp_path: Path, capsys) -> None:
    monkeypatch.setitem(sys.modules, "ray", None)  # import ray -> ImportError
    assert main(["batch", str(short_sim), "--out", str(tmp_path)]) == RayMissing.exit_code
    err = capsys.readouterr().err
    assert "pip install 'trackreplay[cluster]'" in err and "--serial" in err
    assert main(["batch", str(short_sim), "--out", str(tmp_path), "--serial", "--quiet"]) == 0


def test_a_replay_that_lost_frames_is_not_ok(tmp_path: Path) -> None:
    """`replay` exits 7 when damage cost frames; a batch row says so (status frames_lost, why in error)
    instead of "ok" (found by a review)."""
    from trackreplay.replay.batch import run_task

    from mcap.reader import make_reader

    short_sim = GOLF.parent / "flow-sim1-24f.mcap"  # two chunks: the second is damaged
    data = bytearray(short_sim.read_bytes())
    with open(short_sim, "rb") as fh:
        chunk = make_reader(fh).get_summary().chunk_indexes[1]
    data[chunk.chunk_start_offset + chunk.chunk_length // 2] ^= 0x5A
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(bytes(data))
    (task,) = plan([bad], "flow", [0], [])
    row = run_task(task, BatchOptions(out=tmp_path / "out"))
    assert row["status"] == "frames_lost" and row["frames_lost"] > 0
    assert "could not be read" in row["error"] and "recover" in row["error"]
    (good,) = plan([short_sim], "flow", [0], [])
    assert run_task(good, BatchOptions(out=tmp_path / "out2"))["status"] == "ok"


def test_a_parameter_given_as_300_0_and_400_is_a_number_column() -> None:
    from trackreplay.replay.batch import summary_table

    tasks = plan([GOLF], "golf", [0], grid(["golf.search.max_px=300.0,400"]))
    table = summary_table([{"status": "ok"}, {"status": "ok"}], tasks)
    assert table["golf.search.max_px"].dtype == pl.Float64 and table["golf.search.max_px"].to_list() == [300.0, 400.0]


def test_an_out_folder_with_an_earlier_batch_is_refused(short_sim: Path, tmp_path: Path, capsys) -> None:
    """A review reran a batch into the same --out: the old task folders stayed beside the new ones,
    contradicting the new summary."""
    out = tmp_path / "out"
    assert main(["batch", str(short_sim), "--out", str(out), "--serial", "--quiet"]) == 0
    capsys.readouterr()
    assert main(["batch", str(short_sim), "--out", str(out), "--serial", "--quiet"]) == 2
    assert "holds an earlier batch's results (summary.parquet); give an empty or new folder" in capsys.readouterr().err
