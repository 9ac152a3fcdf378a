"""``trackreplay evaluate``: every tracker of a corpus manifest × seeds, started from the truth, scored.

:func:`plan` turns a :class:`~trackreplay.replay.runs.corpus.Corpus` into tasks (case × tracker ×
seed, plus the CSRT baseline on box cases); :func:`run_serial` and :func:`run_ray` run them (Ray
through ``batch``'s :func:`~trackreplay.replay.runs.batch.start_ray`: a local Ray or a cluster whose
nodes see ``--out``); :func:`run_task` is one replay through the public engine, scored with
:mod:`trackreplay.replay.analysis.metrics` (boxes, points) or CLEAR MOT/IDF1/HOTA (several objects),
and never raises: a failure is its row's one-line ``error``. :func:`cases_table` and
:func:`timings_table` are the two tables written; the first holds only what the manifest, seeds and
code decide (same inputs, same bytes), the second the clock's readings.

A single-target case is scored on the truth's frames from its first mark on (the frames before are
not the tracker's to find), against the truth object it was marked from; its track is the one with
the most positioned rows (as ``eval`` picks it).
"""

from __future__ import annotations

import contextlib
import io
import math
import sys
from collections.abc import Callable, Iterator
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

import numpy as np
import polars as pl

from trackreplay.replay.analysis.group_ground import GROUND_SCHEMA, group_ground_scores
from trackreplay.replay.analysis.metrics import BoxScores, PointScores, box_scores, point_scores
from trackreplay.replay.runs.batch import MOT_METRICS, multi_object_metrics, one_line
from trackreplay.replay.runs.case_logs import PreparedCase, prepare_case, truth_table
from trackreplay.replay.runs.corpus import Case, Corpus
from trackreplay.schemas import topics as T
from trackreplay.schemas.errors import TrackreplayError

BASELINE = "csrt"


def _scalars(cls: type) -> list[str]:
    return [f.name for f in fields(cls) if f.type in ("float", "int")]


BOX_ONLY = [c for c in _scalars(BoxScores) if c not in _scalars(PointScores)]
POINT_ONLY = [c for c in _scalars(PointScores) if c not in _scalars(BoxScores)]
COMMON = [c for c in _scalars(BoxScores) if c in _scalars(PointScores)]
COUNTS = [c for c in COMMON if c.startswith("n_")]
LISTS = {"success_curve": pl.Float64, "precision_curve": pl.Float64, "errors": pl.Float64,
         "rel_count": pl.Int64, "rel_confidence": pl.Float64, "rel_accuracy": pl.Float64}
ID_SCHEMA = {"case": pl.String, "source": pl.String, "target": pl.String, "tracker": pl.String, "seed": pl.Int64,
             "object": pl.Int64, "start": pl.String, "mark": pl.String, "log_key": pl.String, "digest": pl.String,
             "frames": pl.Int64, "status": pl.String, "error": pl.String, "notices": pl.String}
CASES_SCHEMA: dict[str, Any] = {
    **ID_SCHEMA,
    **{c: pl.Float64 for c in BOX_ONLY + POINT_ONLY},
    **{c: pl.Int64 if c in COUNTS else pl.Float64 for c in COMMON},
    **{m: pl.Int64 if m.startswith("id_switches") else pl.Float64 for m in MOT_METRICS},
    **{c: pl.List(t) for c, t in LISTS.items()},
    **GROUND_SCHEMA,
}
TIMINGS_SCHEMA = {"case": pl.String, "tracker": pl.String, "seed": pl.Int64, "frames": pl.Int64,
                  "seconds": pl.Float64, "ms_per_frame": pl.Float64, "replay_seconds": pl.Float64}


@dataclass(frozen=True)
class EvalTask:
    index: int
    case_index: int
    case: str
    tracker: str  # a registry name or BASELINE
    seed: int


@dataclass(frozen=True)
class EvalOptions:
    out: Path
    seeds: tuple[int, ...] = (0,)
    jitter: float = 0.0
    csrt_python: Path | None = None  # CSRT's venv python (None: no baseline rows)
    code: str = ""  # recorder_code(): part of each recording's cache key
    scale: tuple[float, float] | None = None  # --jitter-scale: the marks' sides times a factor drawn in [lo, hi]

    @property
    def logs(self) -> Path:
        return self.out / "logs"


def plan(corpus: Corpus, seeds: tuple[int, ...], trackers: tuple[str, ...] | None = None,
         baseline: bool = True) -> tuple[list[Case], list[EvalTask]]:
    """The cases to run (those with a tracker left after ``trackers``) and their tasks, in manifest order."""
    cases, tasks = [], []
    for case in corpus.cases:
        names = [t for t in case.trackers if trackers is None or t in trackers]
        if not names:
            continue
        if baseline and case.baseline and case.target == "box":
            names.append(BASELINE)
        for name in names:
            for seed in seeds:
                tasks.append(EvalTask(len(tasks), len(cases), case.name, name, seed))
        cases.append(case)
    return cases, tasks


def prepare_or_error(case: Case, opts: EvalOptions) -> PreparedCase | str:
    """:func:`prepare_case`, or the one-line reason it failed (every task of the case reports it)."""
    try:
        with contextlib.redirect_stderr(io.StringIO()):
            return prepare_case(case, opts.logs, opts.code, opts.seeds, opts.jitter, opts.scale)
    except Exception as err:  # noqa: BLE001 - a bad case is a row, never the end of the run
        return _clean(one_line(err), opts)


def _clean(message: str, opts: EvalOptions) -> str:
    return message.replace(str(opts.out), "OUT")  # the same message whatever folder the run writes to


def _first_frame(prep: PreparedCase, log: Path) -> int | None:
    if prep.start:
        return min(prep.start)
    from trackreplay.replay.log.frames import FrameTopics, read_hints
    from trackreplay.replay.log.reader import LogReader

    reader = LogReader(log)
    topics = FrameTopics.detect(reader, None, None)
    hints = read_hints(reader, topics.hints, topics.image)
    return min((h.frame for h in hints), default=None)


def _one_track(traj: pl.DataFrame) -> pl.DataFrame:
    placed = traj.filter(pl.col("x").is_not_null()).group_by("track_id").len()
    if placed.is_empty():
        return traj.head(0)
    best = placed.sort(["len", "track_id"], descending=[True, False])["track_id"][0]
    return traj.filter(pl.col("track_id") == best)


def _finite(value: Any) -> Any:
    return None if isinstance(value, float) and not math.isfinite(value) else value


def _curve(values: np.ndarray) -> list[float | None]:
    return [_finite(float(v)) for v in values]


def score(prep: PreparedCase, log: Path, traj: pl.DataFrame) -> dict[str, Any]:
    """The metrics of a replay's trajectory against the case's truth (the row's metric columns)."""
    if prep.case.target == "objects":
        from trackreplay.replay.log.groundtruth import groundtruth_with_frames
        from trackreplay.replay.log.reader import LogReader

        reader = LogReader(log)
        gt, annotated = groundtruth_with_frames(reader)
        out = {k: v for k, v in multi_object_metrics(traj, gt, annotated["frame"]).items() if k != "error"}
        if T.CAMERA_GROUND_PLANE in reader.topics() and gt["X"].drop_nulls().len():  # groups on the ground, in metres
            out |= group_ground_scores(traj, gt, annotated["frame"].to_list()).row()
        return out
    truth = truth_table(log).filter(pl.col("id") == prep.object)
    first = _first_frame(prep, log)
    if first is not None:
        truth = truth.filter(pl.col("frame") >= first)
    track = _one_track(traj)
    scores = box_scores(track, truth) if prep.case.target == "box" else point_scores(track, truth)
    rel = scores.reliability
    out: dict[str, Any] = {k: _finite(v) for k, v in scores.row().items()}
    out |= {"rel_count": [int(c) for c in rel.bin_count], "rel_confidence": _curve(rel.bin_confidence),
            "rel_accuracy": _curve(rel.bin_accuracy)}
    if isinstance(scores, BoxScores):
        out |= {"success_curve": _curve(scores.success_curve), "precision_curve": _curve(scores.precision_curve)}
    else:
        out["errors"] = _curve(scores.errors)
    return out


def _marks_text(marks) -> str:
    return ";".join(f"{m.frame}:{m.x:.2f},{m.y:.2f},{m.w:.2f},{m.h:.2f}" for m in marks)


def run_task(task: EvalTask, prep: PreparedCase | str, opts: EvalOptions) -> tuple[dict[str, Any], dict[str, Any] | None]:
    """One replay (or the CSRT baseline) of one case and seed, scored: (cases row, timings row or None)."""
    row: dict[str, Any] = {"case": task.case, "tracker": task.tracker, "seed": task.seed, "status": "ok"}
    if isinstance(prep, str):
        return row | {"status": "error", "error": prep}, None
    case = prep.case
    log, marks = prep.for_seed(task.seed)
    row |= {"source": case.source, "target": case.target, "object": prep.object, "log_key": prep.key[:16],
            "start": ",".join(map(str, prep.start)) or "log", "mark": _marks_text(marks) or None}
    try:
        with contextlib.redirect_stderr(io.StringIO()):  # notices go to the row, not the console
            if task.tracker == BASELINE:
                traj, seconds, frames = _csrt(task, prep, log, marks, opts)
                replay_seconds = None
            else:
                traj, seconds, frames, replay_seconds = _replay(task, log, row)
            row |= score(prep, log, traj)
    except Exception as err:  # noqa: BLE001 - a failing replay is a row, never the end of the run
        return row | {"status": "error", "error": _clean(one_line(err), opts)}, None
    timing = {"case": task.case, "tracker": task.tracker, "seed": task.seed, "frames": frames, "seconds": seconds,
              "ms_per_frame": 1e3 * seconds / frames if frames else None, "replay_seconds": replay_seconds}
    return row | {"frames": frames}, timing


def _replay(task: EvalTask, log: Path, row: dict[str, Any]) -> tuple[pl.DataFrame, float, int, float]:
    """The replay's trajectory, the time in the tracker's steps (what CSRT's update calls are timed against),
    its frames and the whole replay's time (reading and decoding too)."""
    from trackreplay.replay.core.engine import ReplayRequest, replay

    result = replay(ReplayRequest(log=log, tracker=task.tracker, seed=task.seed))
    row |= {"digest": result.digest, "notices": " | ".join(result.notices) or None}
    return result.trajectory, result.step_seconds, result.frames, result.seconds


def _csrt(task: EvalTask, prep: PreparedCase, log: Path, marks, opts: EvalOptions) -> tuple[pl.DataFrame, float, int]:
    from trackreplay.replay.runs.csrt import csrt_track

    if opts.csrt_python is None:
        raise TrackreplayError("the CSRT baseline is not available here")
    if not marks:
        raise TrackreplayError(f"case {prep.case.name} marks nothing from its truth to start CSRT from")
    traj, times = csrt_track(opts.csrt_python, log, marks[0])
    return traj, float(sum(times)), len(times)


def _bar(total: int, enabled: bool):
    from tqdm import tqdm

    return tqdm(total=total, disable=not enabled, unit="replay", desc="evaluate", leave=False)


Rows = list[tuple[dict[str, Any], dict[str, Any] | None]]


def prepared_replays(corpus: Corpus, opts: EvalOptions) -> Iterator[tuple[str, int, Path, pl.DataFrame]]:
    """``(case name, seed, marked log, the followed object's truth rows)`` for every case of ``corpus``
    and seed of ``opts`` that can be prepared, as ``evaluate`` marks them (a case that cannot: one line on
    stderr, skipped). For scripts that replay a corpus themselves (a confidence calibration's rows)."""
    for case in corpus.cases:
        prep = prepare_or_error(case, opts)
        if isinstance(prep, str):
            print(f"{case.name}: skipped ({prep})", file=sys.stderr)
            continue
        for seed in opts.seeds:
            log, _ = prep.for_seed(seed)
            yield case.name, seed, log, truth_table(log).filter(pl.col("id") == prep.object)


def run_serial(cases: list[Case], tasks: list[EvalTask], opts: EvalOptions, progress: bool = False) -> Rows:
    """Every task in this process, case by case (each case recorded once, before its replays)."""
    done: dict[int, tuple] = {}
    with _bar(len(tasks), progress) as bar:
        for i, case in enumerate(cases):
            mine = [t for t in tasks if t.case_index == i]
            if not mine:
                continue
            prep = prepare_or_error(case, opts)
            for task in mine:
                done[task.index] = run_task(task, prep, opts)
                bar.update()
    return [done[t.index] for t in tasks]


def run_ray(cases: list[Case], tasks: list[EvalTask], opts: EvalOptions, *, address: str | None = None,
            workers: int | None = None, progress: bool = False,
            on_row: Callable[[dict[str, Any]], None] | None = None) -> Rows:
    """Each case's recording as one Ray task, each replay as another that waits for it; rows in task order."""
    from trackreplay.recorder.interrupts import deferred_interrupts
    from trackreplay.replay.runs.batch import import_ray, start_ray

    ray = import_ray()
    started_here = start_ray(address, workers)
    done: dict[int, tuple] = {}
    try:
        prepare = ray.remote(num_cpus=1, max_retries=0)(prepare_or_error)
        replay_one = ray.remote(num_cpus=1, max_retries=0)(run_task)
        preps = {i: prepare.remote(case, opts) for i, case in enumerate(cases)}
        refs = {replay_one.remote(t, preps[t.case_index], opts): t for t in tasks}
        with _bar(len(tasks), progress) as bar:
            pending = list(refs)
            while pending:
                ready, pending = ray.wait(pending, num_returns=1)
                for ref in ready:
                    task = refs[ref]
                    try:
                        done[task.index] = ray.get(ref)
                    except ray.exceptions.RayError as err:  # a worker died (memory, signal): its row says so
                        done[task.index] = ({"case": task.case, "tracker": task.tracker, "seed": task.seed,
                                             "status": "error", "error": one_line(err)}, None)
                    if on_row is not None:
                        on_row(done[task.index][0])
                    bar.update()
    finally:
        if started_here:
            with deferred_interrupts():
                ray.shutdown()
    return [done[t.index] for t in tasks]


def cases_table(rows: Rows) -> pl.DataFrame:
    """One row per case × tracker × seed, every column in :data:`CASES_SCHEMA` (deterministic)."""
    data = {c: [r.get(c) for r, _ in rows] for c in CASES_SCHEMA}
    return pl.DataFrame([pl.Series(c, v, dtype=CASES_SCHEMA[c]) for c, v in data.items()])


def timings_table(rows: Rows) -> pl.DataFrame:
    timed = [t for _, t in rows if t is not None]
    return pl.DataFrame({c: [t[c] for t in timed] for c in TIMINGS_SCHEMA}, schema=TIMINGS_SCHEMA)
