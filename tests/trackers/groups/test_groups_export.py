"""`replay --export` of a groups replay writes the second table beside the trajectory (TRAJ.groups.parquet)."""

from __future__ import annotations

from pathlib import Path

import polars as pl

from trackreplay.replay.cli.main import main as cli
from trackreplay.replay.core.group_table import GROUP_SCHEMA

GOLDEN = Path(__file__).parents[2] / "golden" / "groups-crossing-320x240.mcap"


def test_export_writes_the_group_table_keyed_like_the_trajectory(tmp_path: Path) -> None:
    out = tmp_path / "traj.parquet"
    assert cli(["replay", str(GOLDEN), "--tracker", "groups", "--export", str(out), "--interpolate", "none", "--quiet"]) == 0
    traj = pl.read_parquet(out)
    table = pl.read_parquet(tmp_path / "traj.groups.parquet")
    assert dict(table.schema) == GROUP_SCHEMA
    key = ["tracker", "track_id", "frame"]
    assert table.select(key).is_unique().all()
    # one row per live group per frame: exactly the trajectory's rows that are not "lost"
    live = traj.filter(pl.col("status") != "lost").select(key).sort(key)
    assert table.height > 0 and table.select(key).sort(key).equals(live)
    assert (table["tracker"] == "groups").all() and (table["members"] >= 0).all() and (table["cov_zz"] > 0).all()
    assert table.join(traj, on=key).filter(pl.col("t_ns") != pl.col("t_ns_right")).height == 0


def test_export_of_another_tracker_writes_no_group_table(tmp_path: Path) -> None:
    out = tmp_path / "traj.csv"
    log = Path(__file__).parents[2] / "golden" / "flow-sim1-24f.mcap"
    assert cli(["replay", str(log), "--tracker", "flow", "--export", str(out), "--quiet"]) == 0
    assert out.is_file() and not (tmp_path / "traj.groups.parquet").exists()
