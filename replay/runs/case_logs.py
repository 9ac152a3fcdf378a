"""A corpus case's logs: the source recorded once (cached by content hash), then marked from its truth.

The recorded log is ``OUT/logs/<case>-<key>.mcap``; ``key`` hashes the source's bytes (a video, every
file of an image folder, a log), the truth file's bytes and every option that changes the log
(format, first frame, fps, scene, seed, scene options) and the recorder's own code, so a second run
over the same corpus records nothing and a changed clip, truth or recorder records again. The
marked log (``…-marks-<hash>.mcap``) is that log with the log's own marks removed and marks from
the truth added (``recorder.annotate.marks_from_truth``), shared by every tracker and seed that
starts from the same marks.

``--jitter PX`` moves each mark by an offset drawn uniformly from [-PX, PX]² by a generator seeded
with the replay's seed, the case's name and the marked frame: the same for every tracker and run,
different per seed, so the spread over seeds measures robustness to where a user draws the box.
``--jitter-scale LO:HI`` also scales each mark's sides round its centre by a factor drawn uniformly from
[LO, HI] (another draw of the same generator): how large a box the user draws.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import polars as pl

import trackreplay
import trackreplay.recorder
from trackreplay.recorder.annotate import Mark, annotate, clip_mark, marks_from_truth
from trackreplay.replay.log.frames import FrameTopics, iter_frames
from trackreplay.replay.log.groundtruth import read_groundtruth
from trackreplay.replay.log.reader import LogReader
from trackreplay.replay.runs.corpus import Case
from trackreplay.replay.runs.scenes import write_scene
from trackreplay.schemas import topics as T
from trackreplay.schemas.errors import SourceError

CHUNK = 1 << 20


@dataclass(frozen=True)
class PreparedCase:
    """A case ready to replay: its recorded log (with truth), the truth object to follow and score,
    the frames it is marked on, and the picture's size."""

    case: Case
    log: Path
    key: str  # the recording's content hash (hex)
    object: int | None  # truth id (None: every object, multi-object cases)
    start: tuple[int, ...]  # frames marked from the truth (empty: the log's own marks or none)
    size: tuple[int, int]  # width, height
    marked: tuple[tuple[int, Path, tuple[Mark, ...]], ...] = ()  # (seed, marked log, its marks) per seed

    def for_seed(self, seed: int) -> tuple[Path, tuple[Mark, ...]]:
        for s, log, marks in self.marked:
            if s == seed:
                return log, marks
        return self.log, ()


def _hash_file(h: "hashlib._Hash", path: Path) -> None:
    with open(path, "rb") as fh:
        while block := fh.read(CHUNK):
            h.update(block)


def _hash_tree(h: "hashlib._Hash", root: Path, pattern: str = "*") -> None:
    for path in sorted(p for p in root.rglob(pattern) if p.is_file()):
        h.update(str(path.relative_to(root)).encode() + b"\0")
        _hash_file(h, path)


def recorder_code() -> str:
    """Hash of the recorder's source (its readers and scenes decide the log's content)."""
    h = hashlib.sha256(trackreplay.__version__.encode())
    _hash_tree(h, Path(trackreplay.recorder.__file__).parent, "*.py")
    return h.hexdigest()


def source_key(case: Case, code: str) -> str:
    """The content hash that names the case's recorded log."""
    h = hashlib.sha256(code.encode())
    options = {"source": case.source, "synth": case.synth, "seed": case.seed, "options": list(case.synth_options),
               "fps": case.fps, "truth_format": case.truth_format, "truth_first_frame": case.truth_first_frame}
    if case.ground_plane:  # (a key only when given: the logs of cases without one keep their names)
        options["ground_plane"] = "truth" if case.ground_plane == "truth" else "file"
    h.update(json.dumps(options, sort_keys=True, default=str).encode())
    for path in case.files():
        h.update(b"\0file\0")
        _hash_tree(h, path) if path.is_dir() else _hash_file(h, path)
    return h.hexdigest()


def _safe(name: str) -> str:
    return "".join(c if c.isalnum() or c in "-_." else "_" for c in name)[:60]


def record_case(case: Case, logs: Path, code: str) -> tuple[Path, str]:
    """The case's log with its truth: recorded (or rendered) into ``logs`` unless already there."""
    key = source_key(case, code)
    if case.log is not None:
        return case.log, key
    out = logs / f"{_safe(case.name)}-{key[:16]}.mcap"
    if out.is_file():  # the writer renames NAME.partial only when complete: a file under the name is whole
        return out, key
    logs.mkdir(parents=True, exist_ok=True)
    if case.synth is not None:
        write_scene(out, case.synth, case.seed, dict(case.synth_options), f"case {case.name}")
    else:
        from trackreplay.recorder.record import record

        plane = case.ground_plane
        record(out, video=case.video, images=case.images, fps=case.fps, groundtruth=case.truth,
               gt_format=case.truth_format, gt_first_frame=case.truth_first_frame, quiet=True,
               ground_plane=plane if plane not in ("", "truth") else None, ground_plane_from_truth=plane == "truth")
    return out, key


def picture_size(log: Path) -> tuple[int, int]:
    reader = LogReader(log)
    frames = iter_frames(reader, FrameTopics.detect(reader, None, None))
    try:
        first = next(frames)
    except StopIteration:
        raise SourceError(f"{log} holds no image") from None
    finally:
        frames.close()
    height, width = first.image.shape[:2]
    return int(width), int(height)


def truth_table(log: Path) -> pl.DataFrame:
    return read_groundtruth(LogReader(log))


def chosen_object(truth: pl.DataFrame, case: Case) -> int | None:
    """The truth object a single-target case follows: the case's ``object``, else the one placed on
    the most frames (ties: the lowest id), as ``eval`` picks it."""
    if case.target == "objects":
        return None
    ids = set(truth["id"].unique().to_list())
    if case.object is not None:
        if case.object not in ids:
            raise SourceError(f"case {case.name}: the truth has no object {case.object} (its ids: "
                              f"{', '.join(map(str, sorted(ids))) or 'none'})")
        return case.object
    placed = truth.filter(pl.col("x").is_not_null() & pl.col("visible").fill_null(True))
    counts = placed.group_by("id").len().sort(["len", "id"], descending=[True, False])
    if counts.is_empty():
        raise SourceError(f"case {case.name}: the truth places no object on any frame")
    return int(counts["id"][0])


def prepare_case(case: Case, logs: Path, code: str, seeds: tuple[int, ...], jitter: float,
                 scale: tuple[float, float] | None = None) -> PreparedCase:
    """Record the case (cached), find what to start from and write the marked log of every seed."""
    log, key = record_case(case, logs, code)
    reader = LogReader(log)
    if T.GROUNDTRUTH not in reader.topics():
        raise SourceError(f"case {case.name}: {log} has no ground truth ({T.GROUNDTRUTH}) to score against")
    obj = chosen_object(truth_table(log), case)
    start = case.start
    if case.target != "objects" and case.marks == "truth" and not start:
        start = (marks_from_truth(log, None, case.mark_size, case.label, [obj])[0].frame,)
    if case.marks == "log" or case.target == "objects":
        start = ()
    prep = PreparedCase(case, log, key, obj, start, picture_size(log))
    marked = []
    for seed in seeds:
        marks = case_marks(prep, seed, jitter, scale)
        marked.append((seed, marked_log(prep, marks, logs), tuple(marks)))
    return dataclasses.replace(prep, marked=tuple(marked))


def jitter_offset(case: str, seed: int, frame: int, jitter: float) -> tuple[float, float]:
    """The deterministic offset (px) of the mark on ``frame`` for ``seed``: uniform in [-jitter, jitter]²."""
    if jitter <= 0:
        return 0.0, 0.0
    rng = np.random.default_rng(np.random.SeedSequence([seed, zlib.crc32(case.encode()), frame]))
    dx, dy = rng.uniform(-jitter, jitter, 2)
    return float(dx), float(dy)


def jitter_factor(case: str, seed: int, frame: int, scale: tuple[float, float] | None) -> float:
    """The deterministic factor on the sides of the mark on ``frame`` for ``seed``: uniform in ``scale``
    (``(lo, hi)``; None: 1), drawn after :func:`jitter_offset`'s offset from the same generator."""
    if scale is None:
        return 1.0
    rng = np.random.default_rng(np.random.SeedSequence([seed, zlib.crc32(case.encode()), frame]))
    rng.uniform(-1.0, 1.0, 2)  # the offset's draw: the factor does not change where the box is moved to
    return float(rng.uniform(scale[0], scale[1]))


def case_marks(prep: PreparedCase, seed: int, jitter: float, scale: tuple[float, float] | None = None) -> list[Mark]:
    """The marks a replay of ``prep`` with ``seed`` starts from (empty: the log's own, or none needed):
    each moved by :func:`jitter_offset` and its sides scaled round its centre by :func:`jitter_factor`."""
    case = prep.case
    marks = []
    for frame in prep.start:
        (mark,) = marks_from_truth(prep.log, frame, case.mark_size, case.label, [prep.object])
        dx, dy = jitter_offset(case.name, seed, frame, jitter)
        k = jitter_factor(case.name, seed, frame, scale)
        w, h = mark.w * k, mark.h * k
        x, y = mark.x + dx + (mark.w - w) / 2, mark.y + dy + (mark.h - h) / 2
        marks.append(clip_mark(dataclasses.replace(mark, x=x, y=y, w=w, h=h), *prep.size))
    return marks


def marked_log(prep: PreparedCase, marks: list[Mark], logs: Path) -> Path:
    """``prep.log`` with ``marks`` as its only marks (cached by the marks' values); the log itself
    when there is nothing to mark."""
    if not marks:
        return prep.log
    text = json.dumps([(m.frame, m.x, m.y, m.w, m.h, m.label) for m in marks])
    out = logs / f"{prep.log.stem}-marks-{hashlib.sha256(text.encode()).hexdigest()[:12]}.mcap"
    if out.is_file():
        return out
    logs.mkdir(parents=True, exist_ok=True)
    src = prep.log
    topics = LogReader(src).topics()
    if T.ANNOTATIONS_INIT in topics:  # the log's own marks would start the tracker elsewhere
        from trackreplay.recorder.filter import filter_log

        src = logs / f"{prep.log.stem}-unmarked.mcap"
        if not src.is_file():
            filter_log(prep.log, src, [t for t in topics if t != T.ANNOTATIONS_INIT])
    annotate(src, out, marks)
    return out
