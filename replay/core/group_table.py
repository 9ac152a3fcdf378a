"""The groups tracker's second table (docs/groups.md): one row per live group per frame with its
member count, 3-D velocity (m/s), 3-D extent covariance Σ (m²), EKF position sigmas (m) and, on the
frame of a merge, the groups it came from; ``position_frame`` "world" (Z up, the log's rig pose) or
"camera" (left camera) says which frame the vectors, covariances and the trajectory's X Y Z are in; keyed by (``tracker``, ``track_id``, ``frame``) like the
★ trajectory table it sits beside (``traj.parquet`` → ``traj.groups.parquet``)."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

import polars as pl

from trackreplay.replay.core import registry
from trackreplay.replay.core.engine import ReplayRequest, ReplayStep, iter_steps
from trackreplay.replay.core.trajectory import state_row, trajectory_table

GROUP_SCHEMA = {
    "tracker": pl.String, "track_id": pl.Int64, "frame": pl.Int64, "t_ns": pl.Int64, "members": pl.Int64,
    "position_frame": pl.String, "VX": pl.Float64, "VY": pl.Float64, "VZ": pl.Float64,
    "cov_xx": pl.Float64, "cov_xy": pl.Float64, "cov_xz": pl.Float64, "cov_yy": pl.Float64, "cov_yz": pl.Float64,
    "cov_zz": pl.Float64, "sigma_X": pl.Float64, "sigma_Y": pl.Float64, "sigma_Z": pl.Float64, "merged_from": pl.String,
}


def group_rows(tracker: str, step: ReplayStep) -> list[dict]:
    """The step's rows of the second table its tracker's spec declares (``extra_rows``; none: [])."""
    spec = registry.find(tracker)
    if spec is None or spec.extra_rows is None:
        return []
    return [{"tracker": tracker, "frame": step.frame.index, "t_ns": step.frame.t_ns, **r}
            for r in spec.extra_rows(step.intermediates)]


def group_table(rows: Iterable[dict]) -> pl.DataFrame:
    return pl.DataFrame(list(rows), schema=GROUP_SCHEMA).select(list(GROUP_SCHEMA)).sort(["tracker", "track_id", "frame"])


def replay_groups(req: ReplayRequest) -> tuple[pl.DataFrame, pl.DataFrame, list[ReplayStep]]:
    """Trajectory table, group table and the steps' events (for scripts; the CLI's digest comes from ``replay``)."""
    rows, extra, events = [], [], []
    steps = iter_steps(req)
    try:
        for step in steps:
            rows.extend(state_row(req.tracker, step.frame.index, step.frame.t_ns, s) for s in step.states)
            extra.extend(group_rows(req.tracker, step))
            for e in step.intermediates.events:  # (the group tracker's intermediates)
                events.append((step.frame.index, e))
    finally:
        steps.close()
    return trajectory_table(rows), group_table(extra), events


def write_group_table(table: pl.DataFrame, trajectory_path: Path) -> Path:
    out = trajectory_path.with_name(trajectory_path.stem + ".groups.parquet")
    table.write_parquet(out)
    return out
