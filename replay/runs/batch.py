"""Many replays at once: logs × seeds × parameter values, one replay per Ray task.

:func:`plan` expands the cross product and checks every config before anything runs;
:func:`run_task` is one replay (trajectory, per-frame digests, summary, optional .rrd, eval
metrics where the log has ground truth) that never raises: a failure becomes its row's one-line
``error``. :func:`run_ray` runs the tasks on a local Ray (the machine's cores) or joins a cluster;
:func:`run_serial` runs the same tasks one after another in this process (the comparison the
benchmark makes, and what a machine without Ray can still do).

How logs and outputs travel:

* ``ship_logs=False`` (default): tasks open the log **by path** and write their outputs under
  ``--out`` themselves. Right for a local Ray (one machine) and for a cluster whose nodes mount the
  same storage at the same path.
* ``ship_logs=True``: the driver reads each log once and puts its bytes in Ray's object store
  (``ray.put``); a task writes them to a temporary file on its node, replays, and returns its output
  files as bytes, which the driver writes under ``--out``. For nodes without shared storage; the
  object store holds each log once (Ray spills to disk past its memory), and the driver holds one
  task's outputs at a time.

Every task's digest equals the digest of the same replay run alone (``trackreplay replay``): a task
is the same :func:`replay.engine.replay` call, in a worker process whose OpenCV threads, RNG and
message order the engine fixes as it does everywhere.
"""

from __future__ import annotations

import json
import math
import os
import socket
import tempfile
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import polars as pl

from trackreplay.recorder.interrupts import deferred_interrupts
from trackreplay.replay.core import registry
from trackreplay.replay.runs.batch_config import apply_sets
from trackreplay.replay.core.config import load_config
from trackreplay.replay.core.outputs import remove_empty, write_bytes, write_json, write_parquet, write_parquet_with
from trackreplay.schemas.errors import TrackreplayError

SINGLE_METRICS = ("coverage", "centre_error_mean", "centre_error_rmse", "precision_at_20px", "success_auc",
                  "velocity_rmse_x", "velocity_rmse_y")
# Multi-object trackers (registry's multi_object): `eval --mot`'s figures, on image boxes (IoU >= 0.5)
# and on 3-D positions (<= 1 m) where the trajectory and the truth have them.
MOT_METRICS = ("mota", "motp", "idf1", "id_switches", "hota", "mota_3d", "motp_3d", "idf1_3d", "id_switches_3d", "hota_3d")
METRICS = SINGLE_METRICS + MOT_METRICS
NOT_RUN = "not_run"
INSTALL_HINT = "pip install 'trackreplay[cluster]' (or pip install ray)"


class RayMissing(TrackreplayError):
    exit_code = 2


class BatchInterrupted(KeyboardInterrupt):
    """Ctrl-C or SIGTERM (``cause``) during a batch; ``rows`` holds the finished tasks' rows by index."""

    def __init__(self, cause: KeyboardInterrupt, rows: dict[int, dict[str, Any]]) -> None:
        super().__init__(str(cause))
        self.cause, self.rows = cause, rows


@dataclass(frozen=True)
class BatchTask:
    index: int
    log: Path
    tracker: str
    seed: int
    params: dict[str, Any] = field(default_factory=dict)  # --set key path -> value
    config: Any = None  # what the replay gets: None, a TOML path or a nested dict

    @property
    def name(self) -> str:
        parts = [f"{self.index:04d}", Path(self.log).stem, self.tracker, f"seed{self.seed}"]
        parts += [f"{k.split('.')[-1]}={v}" for k, v in self.params.items()]
        return "".join(c if c.isalnum() or c in "-_.=" else "_" for c in "-".join(parts))[:120]


@dataclass(frozen=True)
class BatchOptions:
    out: Path
    rrd: bool = False
    interpolate: str = "linear"  # gap filling of the written trajectory, as `replay --export`
    max_gap: int = 15


def plan(logs: Iterable[Path], tracker: str, seeds: Iterable[int], grid: list[dict[str, Any]],
         config: Path | None = None) -> list[BatchTask]:
    """The cross product logs × seeds × parameter combinations; every config is checked here."""
    entry = registry.get(tracker)
    configs = []
    for params in grid or [{}]:
        merged = apply_sets(tracker, config, params) if params else config
        load_config(entry.config_cls, merged, table=tracker)  # an unknown key or bad value fails now, once
        configs.append((params, merged))
    tasks = []
    for log in logs:
        for seed in seeds:
            for params, merged in configs:
                tasks.append(BatchTask(len(tasks), Path(log).resolve(), tracker, seed, params, merged))
    return tasks


def one_line(err: BaseException) -> str:
    """The error as one sentence: its own message for a TrackreplayError, else prefixed with its type."""
    text = str(err) if isinstance(err, TrackreplayError) else f"{type(err).__name__}: {err}"
    return " ".join(text.split()) or type(err).__name__


def _has_groundtruth(log: Path) -> bool:
    from trackreplay.replay.log.reader import LogReader
    from trackreplay.schemas import topics as T

    return T.GROUNDTRUTH in LogReader(log).topics()


def run_task(task: BatchTask, opts: BatchOptions, log_bytes: bytes | None = None) -> dict[str, Any]:
    """One replay; returns its summary row. With ``log_bytes`` (a shipped log) the outputs come back
    in the row's ``files`` (name -> bytes) instead of being written under ``opts.out``."""
    from trackreplay.replay.analysis.diff import sidecar_path
    from trackreplay.replay.core.engine import ReplayRequest, replay
    from trackreplay.replay.core.export import fill_gaps

    row: dict[str, Any] = {"task": task.name, "log": str(task.log), "tracker": task.tracker, "seed": task.seed,
                           "params": json.dumps(task.params, sort_keys=True), "status": "ok", "error": None,
                           "digest": None, "frames": None, "frames_lost": None, "seconds": None,
                           "node": socket.gethostname(),
                           **{m: None for m in METRICS}}
    shipped = log_bytes is not None
    tmp = tempfile.TemporaryDirectory(prefix="trackreplay-task-") if shipped else None
    started = time.perf_counter()
    out = Path(tmp.name) if shipped else opts.out / "tasks" / task.name
    try:
        out.mkdir(parents=True, exist_ok=True)
        log = task.log
        if shipped:
            log = out / task.log.name
            log.write_bytes(log_bytes)
        result = replay(ReplayRequest(log=log, tracker=task.tracker, config=task.config, seed=task.seed,
                                      rrd=out / "replay.rrd" if opts.rrd else None, frame_digests=True))
        row.update(digest=result.digest, frames=result.frames, frames_lost=len(result.report.lost),
                   seconds=round(result.seconds, 4))
        table = result.trajectory if opts.interpolate == "none" else fill_gaps(result.trajectory, opts.interpolate, opts.max_gap)
        write_parquet(table, out / "trajectory.parquet")
        summary = result.summary(task.log) | {"params": task.params}
        summary["frame_digests"] = sidecar_path(out / "summary.json").name
        # the per-frame digests' spill file copied row group by row group, not read back whole (issue 33)
        write_parquet_with(sidecar_path(out / "summary.json"), result.frame_digests.write_table)
        write_json(out / "summary.json", summary)
        if result.report.lost:  # as `replay` exits 7: the run finished, but not over the whole log
            lost = [f.index for f in result.report.lost]
            row.update(status="frames_lost", error=f"{len(lost)} frame(s) could not be read (frames {lost[0]}-{lost[-1]}: "
                                                  f"{result.report.lost[0].reason}); `trackreplay recover` salvages the log")
        if _has_groundtruth(log):
            metrics = _metrics(table, log, registry.get(task.tracker).multi_object)
            if "error" in metrics and row["status"] == "ok":
                row["error"] = metrics["error"]
            row.update({k: v for k, v in metrics.items() if k != "error"})
        if shipped:
            row["files"] = {p.name: p.read_bytes() for p in out.iterdir() if p != log}
    except BaseException as err:  # noqa: BLE001 - a task reports, it never takes the batch down
        if isinstance(err, KeyboardInterrupt):
            raise
        message = one_line(err)
        if shipped:  # name the log as the user knows it, not the task's temporary copy
            message = message.replace(str(out / task.log.name), str(task.log))
        row.update(status="error", error=message)
        if not shipped:
            remove_empty([out])  # a log that failed at once leaves no empty task folder behind
    finally:
        row["task_seconds"] = round(time.perf_counter() - started, 4)  # replay + outputs + eval, in the task
        if tmp is not None:
            tmp.cleanup()
    return row


def _metrics(table: pl.DataFrame, log: Path, multi_object: bool = False) -> dict[str, Any]:
    """The eval metrics of the task's trajectory: single-object (``eval``) or, for a tracker of many
    objects, multi-object (``eval --mot``); ``error`` says why there are none."""
    from trackreplay.replay.analysis.eval import evaluate
    from trackreplay.replay.log.groundtruth import groundtruth_with_frames
    from trackreplay.replay.log.reader import LogReader

    try:
        gt, annotated = groundtruth_with_frames(LogReader(log))
        if multi_object:
            return multi_object_metrics(table, gt, annotated["frame"])
        summary, _ = evaluate(table, gt)
    except TrackreplayError as err:  # e.g. a trajectory with no positioned rows: no metrics (why, in the row), not a failure
        return {"error": f"no metrics: {err}"}
    values = summary.as_dict()
    return {m: values[m] for m in SINGLE_METRICS}


def multi_object_metrics(table: pl.DataFrame, gt: pl.DataFrame, frames: pl.Series) -> dict[str, Any]:
    """MOTA, MOTP, IDF1, ID switches and HOTA as `eval --mot` gives them; the 3-D ones only where both
    sides have X, Y, Z (else None, and why in ``error`` when nothing else is missing)."""
    from trackreplay.replay.analysis.mot import hota_metrics, mot_metrics, three_d_missing

    out: dict[str, Any] = {}
    spaces = [("", "image")]
    why_not = three_d_missing(table, gt)
    if why_not is None:
        spaces.append(("_3d", "3d"))
    else:
        out["error"] = f"no 3-D metrics: {why_not}"
    for suffix, space in spaces:
        mot = mot_metrics(table, gt, space=space, frames=frames)
        out |= {f"mota{suffix}": mot.mota, f"motp{suffix}": mot.motp, f"idf1{suffix}": mot.idf1,
                f"id_switches{suffix}": mot.id_switches,
                f"hota{suffix}": hota_metrics(table, gt, space=space, frames=frames).hota}
    # undefined (MOTP with no match): null, as `eval --mot --json` writes it
    return {k: None if isinstance(v, float) and not math.isfinite(v) else v for k, v in out.items()}


def _write_files(row: dict[str, Any], opts: BatchOptions) -> dict[str, Any]:
    files = row.pop("files", None)
    if files:
        out = opts.out / "tasks" / row["task"]
        out.mkdir(parents=True, exist_ok=True)
        for name, data in files.items():
            write_bytes(out / name, data)
    return row


def _error_row(task: BatchTask, err: BaseException) -> dict[str, Any]:
    return {"task": task.name, "log": str(task.log), "tracker": task.tracker, "seed": task.seed,
            "params": json.dumps(task.params, sort_keys=True), "status": "error", "error": one_line(err)}


def not_run_row(task: BatchTask) -> dict[str, Any]:
    """The row of a task an interrupt stopped before it finished."""
    return {"task": task.name, "log": str(task.log), "tracker": task.tracker, "seed": task.seed,
            "params": json.dumps(task.params, sort_keys=True), "status": NOT_RUN,
            "error": "the batch was interrupted before this replay finished"}


def _progress(total: int, enabled: bool):
    from tqdm import tqdm

    return tqdm(total=total, disable=not enabled, unit="replay", desc="batch", leave=False)


def run_serial(tasks: list[BatchTask], opts: BatchOptions, progress: bool = False) -> list[dict[str, Any]]:
    """The tasks one after another in this process; an interrupt raises :class:`BatchInterrupted`."""
    rows: dict[int, dict[str, Any]] = {}
    with _progress(len(tasks), progress) as bar:
        try:
            for task in tasks:
                rows[task.index] = run_task(task, opts)
                bar.update()
        except BatchInterrupted:
            raise
        except KeyboardInterrupt as err:
            raise BatchInterrupted(err, rows) from None
    return [rows[t.index] for t in tasks]


def import_ray():
    try:
        import ray
    except ImportError:
        raise RayMissing(f"trackreplay batch runs its replays on Ray, which is not installed here: {INSTALL_HINT}; "
                         f"--serial runs them one by one in this process instead") from None
    return ray


def start_ray(address: str | None, workers: int | None) -> bool:
    """Start a local Ray (``address`` None: ``workers`` or all cores) or join a cluster; True when we
    started or joined it here (and so must shut it down)."""
    import logging

    ray = import_ray()
    if ray.is_initialized():
        return False
    kwargs: dict[str, Any] = {"include_dashboard": False, "log_to_driver": False, "logging_level": logging.WARNING}
    if address is None:
        kwargs["num_cpus"] = workers or os.cpu_count() or 1
    else:
        kwargs["address"] = address
        # Ray >= 2.5x clusters use token authentication by default; a driver joining one does not
        # switch it on by itself (measured with 2.60: "InvalidAuthToken"), so do it when a token is at hand.
        if "RAY_AUTH_MODE" not in os.environ and (os.environ.get("RAY_AUTH_TOKEN") or os.environ.get("RAY_AUTH_TOKEN_PATH")
                                                  or (Path.home() / ".ray" / "auth_token").exists()):
            os.environ["RAY_AUTH_MODE"] = "token"
    try:
        ray.init(**kwargs)
    except ValueError as err:  # "Invalid address format: nonsense"
        raise TrackreplayError(f"--address {address}: cannot join a Ray cluster there ({err}); give auto, HOST:PORT "
                               f"or ray://HOST:10001") from None
    except (ConnectionError, SystemExit) as err:  # SystemExit: Ray gives up on a GCS that never answers
        raise TrackreplayError(f"cannot join the Ray cluster at {address} ({one_line(err)}); a cluster with token "
                               f"authentication needs its token here (~/.ray/auth_token or RAY_AUTH_TOKEN)") from None
    return True


def run_ray(tasks: list[BatchTask], opts: BatchOptions, *, address: str | None = None, workers: int | None = None,
            ship_logs: bool = False, progress: bool = False,
            on_row: Callable[[dict[str, Any]], None] | None = None) -> list[dict[str, Any]]:
    """Run every task as one Ray task (1 CPU each); rows in task order."""
    ray = import_ray()
    started_here = start_ray(address, workers)
    refs: dict[Any, BatchTask] = {}
    rows: dict[int, dict[str, Any]] = {}
    try:
        remote = ray.remote(num_cpus=1, max_retries=0)(run_task)
        shipped: dict[Path, Any] = {}
        if ship_logs:
            for log in dict.fromkeys(t.log for t in tasks):
                try:
                    shipped[log] = ray.put(log.read_bytes())
                except OSError as err:
                    shipped[log] = None
                    print(f"trackreplay: warning: cannot read {log} ({err.strerror}); its tasks fail", flush=True)
        for task in tasks:
            if ship_logs and shipped.get(task.log) is None:
                rows[task.index] = _error_row(task, TrackreplayError(f"cannot read {task.log}"))
                continue
            refs[remote.remote(task, opts, shipped[task.log] if ship_logs else None)] = task
        with _progress(len(tasks), progress) as bar:
            bar.update(len(rows))
            pending = list(refs)
            while pending:
                ready, pending = ray.wait(pending, num_returns=1)
                for ref in ready:
                    task = refs[ref]
                    try:
                        row = _write_files(ray.get(ref), opts)
                    except ray.exceptions.RayError as err:  # the worker died (memory, signal): its row says so
                        row = _error_row(task, err)
                    rows[task.index] = row
                    if on_row is not None:
                        on_row(row)
                    bar.update()
        return [rows[t.index] for t in tasks]
    except KeyboardInterrupt as err:
        if not started_here:  # a cluster of others: ask its tasks to stop (a local Ray is shut down below).
            for ref, task in refs.items():  # Not forced: force-cancelling while the driver winds down crashed
                if task.index not in rows:  # Ray's core worker (a review, 2 runs in 13).
                    try:
                        ray.cancel(ref)
                    except Exception:  # noqa: BLE001 - a task that ended meanwhile
                        pass
        raise BatchInterrupted(err, rows) from None
    finally:
        if started_here:
            try:
                with deferred_interrupts():  # a Ctrl-C during the shutdown (1-2 s) keeps what finished
                    ray.shutdown()
            except KeyboardInterrupt as err:
                raise BatchInterrupted(err, rows) from None


def summary_table(rows: list[dict[str, Any]], tasks: list[BatchTask]) -> pl.DataFrame:
    """One row per task: log, tracker, seed, one column per --set key, digest, frames, seconds, metrics, status, error."""
    keys = list(dict.fromkeys(k for t in tasks for k in t.params))
    data: dict[str, list] = {c: [] for c in ("task", "log", "tracker", "seed")}
    for key in keys:
        data[key] = []
    for c in ("digest", "frames", "frames_lost", "seconds", *METRICS, "status", "error", "node", "task_seconds"):
        data[c] = []
    for row, task in zip(rows, tasks):
        for c in data:
            data[c].append(task.params.get(c) if c in keys else row.get(c))
    schema = {"task": pl.String, "log": pl.String, "tracker": pl.String, "seed": pl.Int64, "digest": pl.String,
              "frames": pl.Int64, "frames_lost": pl.Int64, "seconds": pl.Float64,
              **{m: pl.Int64 if m.startswith("id_switches") else pl.Float64 for m in METRICS}, "status": pl.String,
              "error": pl.String, "node": pl.String, "task_seconds": pl.Float64}
    columns = []
    for c, values in data.items():
        if c in schema:
            columns.append(pl.Series(c, values, dtype=schema[c]))
        else:  # a parameter: its own type when all values share one, else text
            kinds = {type(v) for v in values}
            if kinds == {int, float}:  # 3.0,4 on the command line: numbers, not text
                columns.append(pl.Series(c, [float(v) for v in values], dtype=pl.Float64))
                continue
            columns.append(pl.Series(c, values if len(kinds) == 1 and not kinds & {list, tuple, dict}
                                     else [json.dumps(v) for v in values]))
    return pl.DataFrame(columns)


SHORT = {"centre_error_mean": "ce_mean", "centre_error_rmse": "ce_rmse", "precision_at_20px": "p@20px",
         "success_auc": "auc", "velocity_rmse_x": "v_rmse_x", "velocity_rmse_y": "v_rmse_y", "coverage": "cover",
         "id_switches": "idsw", "id_switches_3d": "idsw_3d"}


def format_table(table: pl.DataFrame) -> str:
    """The printed table: one line per task, a failed task's one-line error in its row (and in full below)."""
    shown = table.with_columns(pl.col("log").map_elements(lambda s: Path(s).name, return_dtype=pl.String),
                               pl.col("digest").str.slice(0, 12),
                               pl.when(pl.col("status") == "ok").then(pl.lit("ok"))
                               .otherwise(pl.col("status").str.replace("_", " ") + pl.lit(": ") + pl.col("error")).alias("status"))
    drop = [c for c in ("task", "node", "task_seconds", "error") if c in shown.columns]
    drop += ["frames_lost"] if not (table["frames_lost"].fill_null(0) > 0).any() else []
    drop += [m for m in METRICS if shown[m].null_count() == shown.height]
    shown = shown.drop(drop).rename({k: v for k, v in SHORT.items() if k in shown.columns and k not in drop})
    with pl.Config(tbl_rows=-1, tbl_cols=-1, tbl_width_chars=250, fmt_str_lengths=70, tbl_hide_dataframe_shape=True,
                   tbl_hide_column_data_types=True, float_precision=3, tbl_formatting="ASCII_MARKDOWN"):
        text = str(shown)
    failed = table.filter(pl.col("status") != "ok")
    for task, error in failed.select("task", "error").iter_rows():
        if len(error) > 62:  # cut short in the table: in full here
            text += f"\n{task}: error: {error}"
    return text
