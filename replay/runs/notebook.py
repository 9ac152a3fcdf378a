"""The notebook API's functions above the core floor: ``evaluate`` (a trajectory against a log's truth,
or a whole corpus manifest) and ``smooth``, each a DataFrame in and a DataFrame out, through the
same code as ``trackreplay eval``, ``evaluate`` and ``smooth`` (README "Python API"). The rest of
the API (``replay_log``, ``open_log``, ``export``) is :mod:`trackreplay.replay.core.api`.
"""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Any

import polars as pl

from trackreplay.replay.analysis.eval import check_frames, evaluate as evaluate_track
from trackreplay.replay.analysis.mot import MAX_DISTANCE_M, hota_metrics, mot_metrics, three_d_missing
from trackreplay.replay.analysis.smooth import SmoothConfig, log_context, smooth_trajectory
from trackreplay.replay.core.api import replay_log
from trackreplay.replay.core.config import ConfigSource
from trackreplay.replay.core.engine import ReplayResult
from trackreplay.replay.core.export import read_trajectory
from trackreplay.replay.log.frames import image_times
from trackreplay.replay.log.groundtruth import groundtruth_with_frames
from trackreplay.replay.log.reader import LogReader
from trackreplay.schemas import topics as T
from trackreplay.schemas.errors import TrackreplayError

Trajectory = pl.DataFrame | ReplayResult | str | Path


def _table(trajectory: Trajectory) -> pl.DataFrame:
    if isinstance(trajectory, ReplayResult):
        return trajectory.trajectory
    if isinstance(trajectory, pl.DataFrame):
        return trajectory
    return read_trajectory(trajectory)


def evaluate(source: str | Path, trajectory: Trajectory | None = None, *, tracker: str | None = None,
             config: ConfigSource = None, seed: int = 0, mot: bool = False, track_id: int | None = None,
             gt_id: int | None = None, gt_topic: str = T.GROUNDTRUTH, image_topic: str | None = None,
             max_distance_m: float = MAX_DISTANCE_M, seeds: tuple[int, ...] = (0,),
             trackers: tuple[str, ...] | None = None, out: str | Path | None = None) -> pl.DataFrame:
    """The metrics table as a Polars DataFrame.

    A log (``.mcap``) with ground truth: ``trajectory`` (a DataFrame, a :func:`replay_log` result or
    a ``.parquet``/``.csv`` path) or ``tracker`` (replayed here with ``config`` and ``seed``) is
    scored against it as ``trackreplay eval`` does: one row of centre error, IoU / success AUC and
    velocity error for one track against one truth object (``track_id``: default the longest
    track; ``gt_id``: the object seen most); with ``mot`` one row per space (image boxes, and 3-D
    positions where both sides have them) of CLEAR MOT, IDF1 and HOTA over every track.

    A corpus manifest (``.toml``, docs/evaluate.md): every case × tracker (``trackers``) × ``seeds``,
    recorded into ``out`` (default a temporary folder) and scored as ``trackreplay evaluate
    --serial --no-baseline`` does; the rows of its ``cases.parquet``. Cases whose files are absent
    are left out.
    """
    if Path(source).suffix.lower() == ".toml":
        return _evaluate_corpus(Path(source), seeds, trackers, out)
    if (trajectory is None) == (tracker is None):
        raise TrackreplayError("evaluate a log: give either a trajectory or a tracker to replay, not both or neither")
    traj = replay_log(source, tracker, config=config, seed=seed, image_topic=image_topic).trajectory \
        if tracker is not None else _table(trajectory)
    reader = LogReader(source)
    gt, annotated = groundtruth_with_frames(reader, gt_topic)
    check_frames(traj, "the trajectory", image_times(reader, image_topic), annotated, str(source))
    if not mot:
        summary, _ = evaluate_track(traj, gt, track_id=track_id, gt_id=gt_id)
        return pl.DataFrame([summary.as_dict()])
    return pl.DataFrame(_mot_rows(traj, gt, annotated["frame"], max_distance_m))


def _mot_rows(traj: pl.DataFrame, gt: pl.DataFrame, frames: pl.Series, max_distance_m: float) -> list[dict[str, Any]]:
    """``eval --mot``'s blocks as rows: image boxes, then 3-D positions where both sides have them."""
    rows = [{"space": "image", **mot_metrics(traj, gt, space="image", frames=frames).as_dict(),
             **hota_metrics(traj, gt, space="image", frames=frames).as_dict()}]
    if three_d_missing(traj, gt) is None:
        rows.append({"space": "3d",
                     **mot_metrics(traj, gt, space="3d", max_distance_m=max_distance_m, frames=frames).as_dict(),
                     **hota_metrics(traj, gt, space="3d", max_distance_m=max_distance_m, frames=frames).as_dict()})
    return rows


def _evaluate_corpus(manifest: Path, seeds: tuple[int, ...], trackers: tuple[str, ...] | None,
                     out: str | Path | None) -> pl.DataFrame:
    import dataclasses

    from trackreplay.replay.runs.case_logs import recorder_code
    from trackreplay.replay.runs.corpus import load_corpus
    from trackreplay.replay.runs.evaluate import EvalOptions, cases_table, plan, run_serial

    corpus = load_corpus(manifest)
    present = dataclasses.replace(corpus, cases=tuple(c for c in corpus.cases if c.missing() is None))
    cases, tasks = plan(present, tuple(seeds), trackers, baseline=False)
    if not tasks:
        raise TrackreplayError(f"{manifest}: no case to run" + (f" with trackers {', '.join(trackers)}" if trackers else ""))
    with tempfile.TemporaryDirectory(prefix="trackreplay-evaluate-") as scratch:
        folder = Path(out if out is not None else scratch).resolve()
        folder.mkdir(parents=True, exist_ok=True)
        return cases_table(run_serial(cases, tasks, EvalOptions(folder, tuple(seeds), code=recorder_code())))


def smooth(trajectory: Trajectory, log: str | Path, *, max_gap: int = 15) -> pl.DataFrame:
    """The trajectory smoothed over the whole log (offline RTS), as ``trackreplay smooth`` writes it.

    ``trajectory``: a DataFrame (not gap-filled), a ``.parquet``/``.csv`` path, or a
    :func:`replay_log` result (then its tracker's config as replayed too, and its raw measurements
    when it was replayed with ``observations=True``, as ``replay --smooth`` does). ``log``: the log it
    was replayed from (frame times; PTZ cameras for lines of sight). Gaps of at most ``max_gap``
    frames are filled; the result has each value's ``*_std`` and a ``fill`` column.
    """
    table, observations, configs = _table(trajectory), None, None
    if isinstance(trajectory, ReplayResult):
        observations, configs = trajectory.observations, {trajectory.tracker: trajectory.config}
    times, cameras = log_context(log)
    check_frames(table, "the trajectory", times, pl.DataFrame(schema={"frame": pl.Int64, "t_ns": pl.Int64}), str(log))
    out, _ = smooth_trajectory(table, SmoothConfig(max_gap=max_gap), frame_times=times, cameras=cameras,
                               observations=observations, configs=configs)
    return out
