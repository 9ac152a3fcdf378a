"""MOTChallenge files for ``eval``: a tracker's result ``.txt`` as a trajectory table, and a
sequence folder (``SEQ/gt/gt.txt`` + ``SEQ/seqinfo.ini``, the layout MOTChallenge and TrackEval use)
as ground truth.

Frames and pixels are 1-based in these files and 0-based here (``x = bb_left - 1 + w/2``, frame
``f - 1``), the inverse of ``replay.core.export.write_mot``. A result row carries no status: each is a
box the tracker reports, so each is ``measured`` (its ``conf`` becomes ``confidence`` when it lies in
[0, 1]). Truth rows whose ``conf`` flag is 0 are not scored. A 9-column truth (MOT16/17/20:
``…,conf,class,visibility``) is read as TrackEval reads it: only class 1 (pedestrian) is scored,
and a tracker box matched (IoU > 0.5, one Hungarian assignment per frame over all truth boxes) to a
distractor (person on vehicle, static person, distractor, reflection; MOT20 also non-MOT vehicle)
is removed before scoring, neither a hit nor a false positive. A 10-column truth
(``…,conf,x,y,z``, MOT15 and ``trackreplay export``) gives world positions, -1 meaning none.
``tests/replay/analysis/test_mot_files.py`` holds TrackEval 1.3.0's scores of a MOT17 sequence with
every kind of row (``mot17_toy/``) and matches them.
"""

from __future__ import annotations

import configparser
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import polars as pl
from scipy.optimize import linear_sum_assignment

from trackreplay.replay.analysis.mot import iou_similarity
from trackreplay.replay.core.trajectory import SCHEMA, canonical_order, conform
from trackreplay.replay.log.groundtruth import GT_SCHEMA
from trackreplay.schemas.errors import TrackreplayError

PEDESTRIAN = 1
DISTRACTORS = frozenset({2, 7, 8, 12})  # person on vehicle, static person, distractor, reflection
MOT20_DISTRACTORS = DISTRACTORS | {6}  # and non-MOT vehicle
MATCH_IOU = 0.5
_NAMES = ("frame", "id", "bb_left", "bb_top", "bb_width", "bb_height", "conf", "x", "y", "z")


@dataclass(frozen=True)
class MotSequence:
    """A MOTChallenge sequence's truth: ``gt`` (``GT_SCHEMA`` without ``t_ns``), the annotated frames
    (every frame of the sequence when ``seqinfo.ini`` gives its length, else those with a truth row),
    and the truth boxes not scored (``unscored``: frame, x, y, w, h (centre and size), ``distractor``),
    which a 9-column truth's tracker boxes are matched against with the scored ones."""

    name: str
    gt: pl.DataFrame
    frames: pl.Series
    unscored: pl.DataFrame
    length: int | None


def _rows(path: Path) -> list[tuple[int, list[float]]]:
    """(line number, numbers) of a comma- (or space-) separated MOTChallenge file; a bad cell names its line."""
    if not path.is_file():
        raise TrackreplayError(f"{path} does not exist")
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as err:
        raise TrackreplayError(f"{path} cannot be read as text ({err})") from None
    out = []
    for lineno, line in enumerate(text.splitlines(), 1):
        if not line.strip():
            continue
        cells = [c for c in (line.split(",") if "," in line else line.split())]
        if len(cells) < 6:
            raise TrackreplayError(f"{path}:{lineno}: expected frame,id,bb_left,bb_top,bb_width,bb_height[,conf,...], "
                                   f"got {len(cells)} column(s)")
        values = []
        for cell, name in zip(cells, _NAMES + ("col",) * len(cells)):
            try:
                v = float(cell)
            except ValueError:
                raise TrackreplayError(f"{path}:{lineno}: {name} {cell.strip()!r} is not a number") from None
            values.append(v)
        frame, oid = values[0], values[1]
        if not math.isfinite(frame) or frame != int(frame) or frame < 1:
            raise TrackreplayError(f"{path}:{lineno}: frame {cells[0].strip()!r} is not a 1-based frame number")
        if not math.isfinite(oid) or oid != int(oid):
            raise TrackreplayError(f"{path}:{lineno}: id {cells[1].strip()!r} is not an integer")
        left, top, w, h = values[2:6]
        if not all(math.isfinite(v) for v in (left, top, w, h)) or w <= 0 or h <= 0:
            raise TrackreplayError(f"{path}:{lineno}: box {left:g},{top:g},{w:g},{h:g} is not a finite box of positive size")
        out.append((lineno, values))
    if not out:
        raise TrackreplayError(f"{path} holds no rows")
    return out


def _unique(path: Path, rows: list[tuple[int, list[float]]]) -> None:
    seen: dict[tuple[int, int], int] = {}
    for lineno, v in rows:
        key = (int(v[0]), int(v[1]))
        if key in seen:
            raise TrackreplayError(f"{path}:{lineno}: id {key[1]} appears a second time in frame {key[0]} "
                                   f"(first on line {seen[key]})")
        seen[key] = lineno


def _world(v: list[float]) -> tuple[float | None, float | None, float | None]:
    if len(v) >= 10 and not (v[7] == v[8] == v[9] == -1):
        return v[7], v[8], v[9]
    return None, None, None


def read_mot_result(path: str | Path, tracker: str | None = None) -> pl.DataFrame:
    """A MOTChallenge result (``frame,id,bb_left,bb_top,bb_width,bb_height,conf[,x,y,z]``) as the
    trajectory table: every row ``measured``; ``tracker`` defaults to the file's stem."""
    path = Path(path)
    rows = _rows(path)
    _unique(path, rows)
    name = tracker or path.stem
    records = []
    for _, v in rows:
        w, h = v[4], v[5]
        conf = v[6] if len(v) >= 7 and 0.0 <= v[6] <= 1.0 else None
        X, Y, Z = _world(v)
        records.append({"tracker": name, "track_id": int(v[1]), "frame": int(v[0]) - 1, "t_ns": None,
                        "x": v[2] - 1 + w / 2, "y": v[3] - 1 + h / 2, "w": w, "h": h, "X": X, "Y": Y, "Z": Z,
                        "status": "measured", "confidence": conf})
    df = pl.DataFrame(records, schema={k: SCHEMA[k] for k in records[0]})
    df = df.with_columns(*(pl.lit(None, dtype=t).alias(c) for c, t in SCHEMA.items() if c not in df.columns))
    return canonical_order(conform(df, str(path), lambda i: f"line {rows[i][0]}"))


def sequence_paths(path: str | Path) -> tuple[Path, Path | None]:
    """``gt.txt`` and ``seqinfo.ini`` (None when absent) of a sequence folder (``SEQ/gt/gt.txt``), or
    of a ``gt.txt`` given directly (its ``seqinfo.ini`` two folders up, as in ``SEQ/gt/gt.txt``, or beside it)."""
    path = Path(path)
    if path.is_dir():
        gt = path / "gt" / "gt.txt"
        if not gt.is_file():
            raise TrackreplayError(f"{path} is neither a log nor a MOTChallenge sequence folder (no gt/gt.txt in it)")
        info = path / "seqinfo.ini"
    else:
        gt = path
        info = next((p for p in (path.parent.parent / "seqinfo.ini", path.parent / "seqinfo.ini") if p.is_file()),
                    path.parent / "seqinfo.ini")
    return gt, (info if info.is_file() else None)


def read_seqinfo(path: Path) -> dict[str, str]:
    """``[Sequence]`` of a ``seqinfo.ini`` (name, seqLength, frameRate, imWidth, imHeight …), keys as written."""
    parser = configparser.ConfigParser()
    parser.optionxform = str  # keep seqLength's capitals
    try:
        parser.read_string(path.read_text(encoding="utf-8"), source=str(path))
    except (configparser.Error, OSError, UnicodeDecodeError) as err:
        raise TrackreplayError(f"{path} is not a readable seqinfo.ini ({str(err).splitlines()[0]})") from None
    if not parser.has_section("Sequence"):
        raise TrackreplayError(f"{path} has no [Sequence] section")
    return dict(parser["Sequence"])


def _length(info: dict[str, str], path: Path) -> int | None:
    text = info.get("seqLength")
    if text is None:
        return None
    try:
        n = int(text)
    except ValueError:
        n = -1
    if n < 1:
        raise TrackreplayError(f"{path}: seqLength {text!r} is not a positive number of frames")
    return n


def read_mot_sequence(path: str | Path) -> MotSequence:
    """A MOTChallenge sequence folder or ``gt.txt`` as ground truth (see the module's docstring)."""
    gt_path, info_path = sequence_paths(path)
    info = read_seqinfo(info_path) if info_path else {}
    length = _length(info, info_path) if info_path else None
    rows = _rows(gt_path)
    _unique(gt_path, rows)
    classed = all(len(v) == 9 for _, v in rows)  # MOT16/17/20: conf, class, visibility
    name = info.get("name") or (gt_path.parent.parent.name if gt_path.parent.name == "gt" else gt_path.stem)
    distractor_classes = MOT20_DISTRACTORS if name.upper().startswith("MOT20") else DISTRACTORS
    truth, unscored = [], []
    for lineno, v in rows:
        frame = int(v[0]) - 1
        if length is not None and frame >= length:
            raise TrackreplayError(f"{gt_path}:{lineno}: frame {frame + 1} is beyond the sequence's {length} frames "
                                   f"({info_path})")
        box = (v[2] - 1 + v[4] / 2, v[3] - 1 + v[5] / 2, v[4], v[5])
        if (len(v) >= 7 and v[6] == 0) or (classed and int(v[7]) != PEDESTRIAN):
            unscored.append((frame, *box, classed and int(v[7]) in distractor_classes))
            continue
        truth.append((frame, int(v[1]), *box, *_world(v), None, None, True, None))
    gt = pl.DataFrame(truth, schema={k: t for k, t in GT_SCHEMA.items() if k != "t_ns"}, orient="row").sort(["id", "frame"])
    frames = pl.Series("frame", range(length) if length is not None else sorted({r[0] for r in truth}), dtype=pl.Int64)
    unscored_table = pl.DataFrame(unscored, schema={"frame": pl.Int64, **{c: pl.Float64 for c in "xywh"},
                                                    "distractor": pl.Boolean}, orient="row")
    return MotSequence(name, gt, frames, unscored_table, length)


def drop_distractor_matches(traj: pl.DataFrame, seq: MotSequence) -> tuple[pl.DataFrame, int]:
    """``traj`` without the boxes TrackEval removes (matched to a distractor; the module's docstring),
    and how many were removed."""
    if not seq.unscored["distractor"].any():
        return traj, 0
    truth = pl.concat([seq.gt.select("frame", "x", "y", "w", "h").with_columns(pl.lit(False).alias("distractor")),
                       seq.unscored])
    by_frame = {k[0]: df for k, df in truth.partition_by("frame", as_dict=True).items()}
    drop: list[tuple[int, int]] = []
    positioned = traj.filter(pl.col("x").is_not_null() & (pl.col("status") != "lost"))
    for (frame,), rows in positioned.partition_by("frame", as_dict=True).items():
        g = by_frame.get(frame)
        if g is None or not g["distractor"].any():
            continue
        corner = (pl.col("x") - pl.col("w") / 2, pl.col("y") - pl.col("h") / 2, "w", "h")
        sim = iou_similarity(g.select(*corner).to_numpy(), rows.select(*corner).to_numpy())
        sim[sim < MATCH_IOU - np.finfo(float).eps] = 0.0  # as TrackEval: threshold, then one assignment
        r, c = linear_sum_assignment(-sim)
        hit = (sim[r, c] > np.finfo(float).eps) & g["distractor"].to_numpy()[r]
        drop += [(frame, int(t)) for t in rows["track_id"].to_numpy()[c[hit]]]
    if not drop:
        return traj, 0
    gone = pl.DataFrame(drop, schema={"frame": pl.Int64, "track_id": pl.Int64}, orient="row")
    return traj.join(gone, on=["frame", "track_id"], how="anti"), len(drop)
