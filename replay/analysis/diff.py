"""The first frame where two replays diverge, and which intermediate differs there.

Two replays are compared frame by frame through their per-field hashes (``digest.FrameDigests``,
recorded by every replay and written beside a summary as ``<summary>.frames.parquet``), so a
golden summary from last month and a run from today can be compared without the old code. When
both sides can be replayed here (two (log, tracker, seed, config) runs), the values themselves are
compared too, giving max |Δ| for every differing field; from a sidecar, max |Δ| is given for fields
small enough to be stored with their values (≤ ``SMALL`` elements: track states, filter states,
velocities; ``digest.SMALL``), and a hash mismatch alone for larger ones (images, particle clouds).
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import polars as pl

from trackreplay.replay.core.digest import SMALL, FrameDigests, leaf_values, portable_floats
from trackreplay.schemas.errors import TrackreplayError

SIDECAR_SUFFIX = ".frames.parquet"
_MISSING = object()


@dataclass(frozen=True)
class FieldDiff:
    field: str
    max_abs_delta: float | None = None  # None: not numeric, or values not at hand
    note: str = ""  # "shape (3,) vs (4,)", "'ptz' vs 'image'", "only in A", …

    def describe(self) -> str:
        name = self.field.removeprefix("intermediates.")
        if self.note:
            return f"{name} differ ({self.note})"
        if self.max_abs_delta is not None:
            return f"{name} differ, max |Δ| {self.max_abs_delta:.2g}"
        return f"{name} differ"


@dataclass(frozen=True)
class Divergence:
    """Where two replays part; ``frame`` None means they are identical."""

    frames_a: int
    frames_b: int
    frame: int | None = None
    fields: tuple[FieldDiff, ...] = ()
    trajectory_equal_until: int | None = None  # last frame whose track states are equal (-1: none)
    trajectory_diverges: bool = False
    digests: tuple[str | None, str | None] = (None, None)
    notes: tuple[str, ...] = field(default_factory=tuple)
    trajectory_name: str = "trajectory"  # what was compared for it (an .rrd holds the tracks as drawn)

    @property
    def identical(self) -> bool:
        return self.frame is None and self.frames_a == self.frames_b and (
            None in self.digests or self.digests[0] == self.digests[1])

    def report(self) -> str:
        if self.identical:
            digest = f", digest {self.digests[0]}" if self.digests[0] else ""
            return f"identical: {self.frames_a} frames{digest}"
        if self.frame is None:
            if self.frames_a != self.frames_b:
                head = f"equal over the first {min(self.frames_a, self.frames_b)} frames, then A has {self.frames_a} frames, B {self.frames_b}"
            else:
                head = f"per-frame outputs equal over {self.frames_a} frames, but the digests differ"
            return "\n".join([head, *self.notes])
        first = self.fields[0].describe() if self.fields else "outputs differ"
        if not self.trajectory_diverges:
            traj = f"{self.trajectory_name} equal in all {min(self.frames_a, self.frames_b)} frames"
        elif self.trajectory_equal_until is not None and self.trajectory_equal_until >= 0:
            traj = f"{self.trajectory_name} equal up to frame {self.trajectory_equal_until}"
        else:
            traj = f"{self.trajectory_name} differs from the start"
        more = f" (and {len(self.fields) - 1} more field{'s' if len(self.fields) > 2 else ''})" if len(self.fields) > 1 else ""
        where = "static data" if self.frame == "static" else f"frame {self.frame}"
        lines = [f"{where}: {first}{more}; {traj}"]
        lines += [f"  {f.describe()}" for f in self.fields[1:]]
        lines += list(self.notes)
        return "\n".join(lines)


# --- values -------------------------------------------------------------------------------------

def compare_values(a: Any, b: Any) -> tuple[float | None, str]:
    """(max |Δ|, note) of two leaf values as hashed (floats rounded as the digest rounds them)."""
    if isinstance(a, str) or isinstance(b, str) or a is None or b is None:
        return None, f"{_short(a)} vs {_short(b)}"
    x, y = np.asarray(a), np.asarray(b)
    if x.shape != y.shape:
        return None, f"shape {x.shape} vs {y.shape}"
    if x.dtype.kind not in "biufc" or y.dtype.kind not in "biufc":
        return None, ""
    if x.dtype.kind in "fc" or y.dtype.kind in "fc":
        x = portable_floats(np.real(x)).astype(np.float64)
        y = portable_floats(np.real(y)).astype(np.float64)
    else:
        x, y = x.astype(np.float64), y.astype(np.float64)
    nan_x, nan_y = np.isnan(x), np.isnan(y)
    both = ~nan_x & ~nan_y
    delta = float(np.max(np.abs(x[both] - y[both]))) if both.any() else 0.0
    nan_mismatch = int(np.count_nonzero(nan_x != nan_y))
    return delta, (f"{nan_mismatch} NaN where the other has a value, else max |Δ| {delta:.2g}" if nan_mismatch else "")


def _short(v: Any) -> str:
    text = repr(v)
    return text if len(text) <= 40 else text[:37] + "..."


# --- comparing two recordings ---------------------------------------------------------------------


@dataclass
class Recording:
    """One side of a diff: per-frame hashes, optionally values of small fields, and its final digest."""

    frames: FrameDigests
    digest: str | None = None
    values: dict[tuple[int, str], Any] = field(default_factory=dict)  # (frame, field) -> value, where kept
    label: str = ""


def diff_recordings(a: Recording, b: Recording) -> Divergence:
    """First frame whose per-field hashes differ, the differing fields, and how long the trajectory agrees."""
    n = min(len(a.frames), len(b.frames))
    first: int | None = None
    fields: list[FieldDiff] = []
    traj_until: int | None = None
    traj_diverges = False
    for i in range(n):
        fa, fb = a.frames.fields(i), b.frames.fields(i)
        frame = a.frames.frames[i]
        if b.frames.frames[i] != frame:
            return Divergence(len(a.frames), len(b.frames), frame, (FieldDiff("frame index", None, f"{frame} vs {b.frames.frames[i]}"),),
                              traj_until, True, (a.digest, b.digest))
        if fa == fb:
            if not traj_diverges:
                traj_until = frame
            continue
        if first is None:
            first = frame
            for name in list(fa) + [k for k in fb if k not in fa]:
                if fa.get(name) == fb.get(name):
                    continue
                if name not in fa or name not in fb:
                    fields.append(FieldDiff(name, None, "only in A" if name in fa else "only in B"))
                    continue
                va = a.values.get((frame, name), a.frames.values(i).get(name, _MISSING))
                vb = b.values.get((frame, name), b.frames.values(i).get(name, _MISSING))
                if va is not _MISSING and vb is not _MISSING:
                    delta, note = compare_values(va, vb)
                    fields.append(FieldDiff(name, delta, note))
                else:
                    fields.append(FieldDiff(name))
        if any(k.startswith("states") and fa.get(k) != fb.get(k) for k in set(fa) | set(fb)):
            traj_diverges = True
            break
        traj_until = frame
    if first is None and traj_until is None and n:
        traj_until = a.frames.frames[n - 1]
    return Divergence(len(a.frames), len(b.frames), first, tuple(fields), traj_until if first is not None else None,
                      traj_diverges, (a.digest, b.digest))


# --- sources: summaries with their sidecar, and live runs -----------------------------------------


def sidecar_path(summary: Path) -> Path:
    return summary.with_name(summary.name.removesuffix(".json") + SIDECAR_SUFFIX)


def write_sidecar(frames: FrameDigests, path: Path) -> Path:
    from trackreplay.replay.core.outputs import write_parquet_with

    path.parent.mkdir(parents=True, exist_ok=True)
    return write_parquet_with(path, frames.write_table)  # a spilled replay's row groups one at a time


def read_sidecar(path: Path) -> FrameDigests:
    """The per-frame digests of a sidecar, read a block of frames at a time as ``diff`` asks for them
    (:meth:`FrameDigests.from_file`); a file that does not read so is read whole, which names its defect."""
    if path.is_file() and (frames := FrameDigests.from_file(path)) is not None:
        return frames
    try:
        table = pl.read_parquet(path)
    except FileNotFoundError:
        raise TrackreplayError(f"{path} does not exist (the per-frame digests written beside a summary)") from None
    except Exception as err:  # polars raises ComputeError and friends for a file that is not Parquet
        raise TrackreplayError(f"{path} is not a per-frame digest table ({type(err).__name__})") from None
    missing = {"frame", "field", "hash"} - set(table.columns)
    if missing:
        raise TrackreplayError(f"{path} is not a per-frame digest table (no column {', '.join(sorted(missing))})")
    return FrameDigests.from_table(table)


def load_summary(path: Path) -> tuple[dict[str, Any], Recording]:
    try:
        summary = json.loads(path.read_text())
    except FileNotFoundError:
        raise TrackreplayError(f"{path} does not exist") from None
    except (UnicodeDecodeError, json.JSONDecodeError) as err:
        raise TrackreplayError(f"{path} is not a replay summary (JSON: {err})") from None
    if not isinstance(summary, dict) or "digest" not in summary:
        raise TrackreplayError(f"{path} is not a replay summary (no digest)")
    side = summary.get("frame_digests")
    side_path = (path.parent / side) if side else sidecar_path(path)
    if not side_path.exists():
        raise TrackreplayError(f"{path} has no per-frame digests ({side_path} is missing); write it with "
                               f"trackreplay replay --summary, or diff two runs of the log")
    return summary, Recording(read_sidecar(side_path), summary.get("digest"), label=str(path))


@dataclass(frozen=True)
class RunSpec:
    log: Path
    tracker: str
    seed: int = 0
    config: Any = None  # None, a dict nested like the config, or a TOML path


def record_run(spec: RunSpec) -> Iterator[tuple[int, Any, str | None]]:
    """Replay ``spec`` one frame at a time: (frame index, (intermediates, states), None), then
    (-1, None, digest) once the log is done."""
    from trackreplay.replay.core.digest import ReplayDigest
    from trackreplay.replay.core.engine import ReplayRequest, iter_steps
    from trackreplay.replay.core.trajectory import state_row, trajectory_table

    steps = iter_steps(ReplayRequest(log=spec.log, tracker=spec.tracker, config=spec.config, seed=spec.seed))
    digest, rows = ReplayDigest(), []
    try:
        for step in steps:
            outputs = (step.intermediates, step.states)
            digest.add_frame(step.frame.index, outputs)
            rows.extend(state_row(spec.tracker, step.frame.index, step.frame.t_ns, s) for s in step.states)
            yield step.frame.index, outputs, None
    finally:
        steps.close()
    digest.add_lost([(x.topic, x.index, x.t_ns) for x in steps.report.lost])  # as replay() does
    yield -1, None, digest.finish(trajectory_table(rows))


def diff_runs(a: RunSpec, b: RunSpec) -> Divergence:
    """Replay both in lock step, record their per-field hashes, and keep the values of the first
    frame where they differ (so every differing field gets its max |Δ|)."""
    from trackreplay.replay.core.digest import ReplayDigest, _frame_path

    sides = [Recording(FrameDigests(), label=str(a.log)), Recording(FrameDigests(), label=str(b.log))]
    hashers = [ReplayDigest(per_frame=True), ReplayDigest(per_frame=True)]
    runs = [record_run(a), record_run(b)]
    kept = False
    done = [False, False]
    while not all(done):
        items = []
        for k in (0, 1):
            item = None if done[k] else next(runs[k])
            if item is not None and item[0] < 0:
                sides[k].digest, done[k], item = item[2], True, None
            items.append(item)
        for k, item in enumerate(items):
            if item is not None:
                hashers[k].add_frame(item[0], item[1])
        if not kept and all(items) and hashers[0].frames.fields(-1) != hashers[1].frames.fields(-1):
            kept = True  # the first differing frame: keep both sides' values
            for k, item in enumerate(items):
                sides[k].values = {(item[0], _frame_path(p)): v for p, v in leaf_values(item[1]) if p != "len"}
    for k in (0, 1):
        sides[k].frames = hashers[k].frames
    return diff_recordings(*sides)


def recording_of_run(spec: RunSpec) -> Recording:
    """One replay of ``spec`` as a Recording (per-frame hashes, kept small values, digest)."""
    from trackreplay.replay.core.engine import ReplayRequest, replay

    result = replay(ReplayRequest(log=spec.log, tracker=spec.tracker, config=spec.config, seed=spec.seed,
                                  frame_digests=True))
    return Recording(result.frame_digests, result.digest, label=str(spec.log))


def load_side(text: str) -> tuple[str, Any]:
    """What one operand of ``trackreplay diff`` is: ("summary", path), ("rrd", path) or ("log", path)."""
    path = Path(text)
    if path.suffix == ".json":
        return "summary", path
    if path.suffix == ".rrd":
        return "rrd", path
    if path.suffix == ".mcap":
        return "log", path
    raise TrackreplayError(f"{path}: diff compares two replay summaries (.json), two .rrd files, or two runs of a log (.mcap)")
