"""Trajectory vs ground truth: what the tracker measured (share of frames measured within 5 and 10 px,
or with IoU >= 0.5), centre error, IoU (OTB success), velocity error.

``measured`` rows are the tracker's own sightings; ``frames tracked`` also counts the rows it
predicted and those the gap filling interpolated, so it is never the headline."""

from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import polars as pl

from trackreplay.schemas.errors import TrackreplayError
from trackreplay.replay.core.trajectory import KEY, SCHEMA, conform, frame_time_mismatches
from trackreplay.trackers.geometry.box import iou as box_iou

IOU_THRESHOLDS = np.linspace(0.0, 1.0, 21)
PRECISION_PX = 20.0
NEAR_PX = (5.0, 10.0)  # measured within these distances: the headline
RIGHT_IOU = 0.5  # a measured box is right at this IoU or more


@dataclass(frozen=True)
class EvalSummary:
    tracker: str
    track_id: int
    gt_id: int
    gt_frames: int  # frames where the object is visible with a known centre
    tracked_frames: int  # of those, frames where the track has a position
    coverage: float
    centre_error_mean: float | None
    centre_error_median: float | None
    centre_error_rmse: float | None
    precision_at_20px: float | None
    iou_mean: float | None
    success_auc: float | None
    velocity_rmse_x: float | None
    velocity_rmse_y: float | None
    velocity_error_mean: float | None
    velocity_frames: int
    measured_frames: int = 0  # visible truth frames with a measured row
    measured_within_5px: float | None = None  # share of visible truth frames with a measured row within 5 px
    measured_within_10px: float | None = None
    measured_iou_50: float | None = None  # share of visible truth frames with a measured box of IoU >= 0.5 (box truth only)

    def as_dict(self) -> dict:
        return asdict(self)


def _pick_track(traj: pl.DataFrame, track_id: int | None) -> pl.DataFrame:
    if traj.is_empty():
        raise TrackreplayError("the trajectory has no rows to evaluate")
    if track_id is None:
        counts = traj.filter(pl.col("x").is_not_null()).group_by("track_id").len().sort(["len", "track_id"], descending=[True, False])
        if counts.is_empty():
            raise TrackreplayError("the trajectory has no positioned rows to evaluate")
        track_id = int(counts["track_id"][0])
    track = traj.filter(pl.col("track_id") == track_id)
    if track.is_empty():
        raise TrackreplayError(f"the trajectory has no track {track_id}")
    return track


def _pick_gt(gt: pl.DataFrame, gt_id: int | None) -> pl.DataFrame:
    return gt.filter(pl.col("id") == _gt_id(gt, gt_id))


def _gt_id(gt: pl.DataFrame, gt_id: int | None) -> int:
    """The truth object to score against (``gt_id``, else the one placed on most frames), refused when absent."""
    if gt.is_empty():
        raise TrackreplayError("the log's ground truth holds no objects")
    if gt_id is None:
        counts = gt.filter(pl.col("x").is_not_null()).group_by("id").len().sort(["len", "id"], descending=[True, False])
        if counts.is_empty():
            raise TrackreplayError("the log's ground truth places no object on any frame (every row marks it absent)")
        gt_id = int(counts["id"][0])
    if not (gt["id"] == gt_id).any():
        raise TrackreplayError(f"the ground truth has no object {gt_id}")
    return gt_id


def _object_rows(gt: pl.DataFrame, gt_id: int) -> pl.DataFrame:
    """The object's rows by frame: a slice of ``gt`` (no copy) when it is sorted by object and frame, as
    the log's truth is read."""
    at = (gt["id"] == gt_id).arg_true()
    first, last = int(at[0]), int(at[-1])
    if last - first + 1 == at.len():
        rows = gt.slice(first, at.len())
        if rows["frame"].is_sorted():
            return rows
    return gt.filter(pl.col("id") == gt_id).sort("frame", maintain_order=True)


def object_followed(traj: pl.DataFrame, gt: pl.DataFrame, track_id: int) -> int | None:
    """The truth object ``track_id`` lies on most often: its centre inside the object's box (within
    ``NEAR_PX[1]`` of a point truth) on the most frames; None when it lies on none."""
    return _most_often(_on_counts(_track_centres(traj, track_id), gt))


def object_followed_parts(traj: pl.DataFrame, parts, track_id: int) -> int | None:
    """:func:`object_followed` with the truth of every object as ``parts()`` gives it (:func:`truth_parts`
    with no object: the log's truth a chunk at a time, a frame's objects once each): the frames each
    object has the track on it, counted chunk by chunk and added."""
    track = _track_centres(traj, track_id)
    counts: dict[int, int] = {}
    for part in parts():
        for gt_id, n in _on_counts(track, part).iter_rows():
            counts[gt_id] = counts.get(gt_id, 0) + n
    return min(counts, key=lambda i: (-counts[i], i)) if counts else None


def _track_centres(traj: pl.DataFrame, track_id: int) -> pl.DataFrame:
    return traj.filter((pl.col("track_id") == track_id) & pl.col("x").is_not_null()).select(
        "frame", pl.col("x").alias("tx"), pl.col("y").alias("ty"))


def _on_counts(track: pl.DataFrame, gt: pl.DataFrame) -> pl.DataFrame:
    """Per truth object (``id, len``), the frames the track's centre lies on it."""
    obj = gt.filter(pl.col("x").is_not_null() & pl.col("visible").fill_null(True))
    j = obj.join(track, on="frame", how="inner")
    half_w = (pl.col("w") / 2).fill_null(NEAR_PX[1])
    half_h = (pl.col("h") / 2).fill_null(NEAR_PX[1])
    on = j.filter(((pl.col("tx") - pl.col("x")).abs() <= half_w) & ((pl.col("ty") - pl.col("y")).abs() <= half_h))
    return on.group_by("id").len()


def _most_often(counts: pl.DataFrame) -> int | None:
    if counts.is_empty():
        return None
    return int(counts.sort(["len", "id"], descending=[True, False])["id"][0])


def _same_frames(track: pl.DataFrame, obj: pl.DataFrame, names: tuple[str, str] = ("the trajectory", "the ground truth")) -> None:
    """The trajectory and the ground truth number frames alike: a frame's time agrees in both (a log
    cut or recovered by a tool that did not renumber would compare each estimate with another moment)."""
    if "t_ns" not in track.columns or "t_ns" not in obj.columns:
        return
    both = _mismatches(track, obj)
    if both.height:
        f, t, g = both.row(0)
        raise TrackreplayError(f"frame {f} is at t={t} ns in {names[0]} but at t={g} ns in {names[1]} "
                               f"({both.height} frame(s) disagree): they come from different logs, or the log was cut or "
                               "recovered without renumbering its ground truth")


MATCH_ROWS = 1 << 14  # rows of a table compared with another's frame times at a time


def _mismatches(a: pl.DataFrame, b: pl.DataFrame, *, missing: bool = False, rows: int | None = None) -> pl.DataFrame:
    """:func:`~trackreplay.replay.core.trajectory.frame_time_mismatches` of ``a`` and ``b``, ``rows``
    rows of ``a`` at a time against ``b``'s rows on those frames (the join of a 200k-row table cost
    ~30 MB; issue 33): the same rows, a frame's first disagreeing row of ``a`` kept."""
    rows = rows or MATCH_ROWS
    if a.height <= rows:
        return frame_time_mismatches(a, b, missing=missing)
    parts = []
    for start in range(0, a.height, rows):
        part = a.slice(start, rows)
        lo, hi = part["frame"].min(), part["frame"].max()
        near = b.filter(pl.col("frame").cast(a.schema["frame"]).is_between(lo, hi)) if lo is not None else b.clear()
        parts.append(frame_time_mismatches(part, near, missing=missing))
    return pl.concat(parts).sort("frame", maintain_order=True).unique("frame", keep="first", maintain_order=True)


def mismatches_in_pieces(a: pl.DataFrame, b: pl.DataFrame, *, missing: bool = False) -> pl.DataFrame:
    """:func:`~trackreplay.replay.core.trajectory.frame_time_mismatches`, :data:`MATCH_ROWS` rows of ``a`` at a time."""
    return _mismatches(a, b, missing=missing)


def check_frames(traj: pl.DataFrame, traj_name: str, log_times: dict[int, int] | pl.DataFrame, annotated: pl.DataFrame,
                 log_name: str) -> None:
    """The trajectory was replayed from this log: every row's frame is one of the log's images
    (``log_times``, frame -> t_ns, or a table of ``frame, t_ns``: :func:`truth_index`) and, where the
    row's time is the frame's own (measured, predicted), at that time in the log and in its ground
    truth (``annotated``: frame, t_ns)."""
    logged = log_times if isinstance(log_times, pl.DataFrame) else pl.DataFrame(
        {"frame": list(log_times), "t_ns": list(log_times.values())}, schema={"frame": pl.Int64, "t_ns": pl.Int64})
    bad = _mismatches(traj, logged, missing=True)
    if bad.height:
        f, t, lt = bad.row(0)
        where = (f"is at t={lt} ns in {log_name}" if lt is not None
                 else f"is not one of the {len(log_times)} frames of {log_name}")
        raise TrackreplayError(f"{traj_name}: frame {f} (t={t} ns) {where} ({bad.height} frame(s) disagree): "
                               "the trajectory was not replayed from this log")
    _same_frames(traj, annotated, (traj_name, f"the ground truth of {log_name}"))


def per_frame(traj: pl.DataFrame, gt: pl.DataFrame, *, track_id: int | None = None, gt_id: int | None = None) -> pl.DataFrame:
    """One row per ground-truth frame with the estimate beside it and the errors."""
    track = _pick_track(traj, track_id)
    obj = _pick_gt(gt, gt_id)
    _same_frames(track, obj)
    return _joined(track, obj)


def _joined(track: pl.DataFrame, obj: pl.DataFrame) -> pl.DataFrame:
    """The truth object's frames with the track's row beside each and the errors, by frame."""
    est = track.select("frame", "tracker", "track_id", "status",
                       *(pl.col(c).alias(f"est_{c}") for c in ("x", "y", "w", "h", "vx", "vy")))
    joined = obj.select("frame", "id", "visible", "x", "y", "w", "h", "vx", "vy").join(est, on="frame", how="left")
    return joined.with_columns(
        (((pl.col("est_x") - pl.col("x")) ** 2 + (pl.col("est_y") - pl.col("y")) ** 2).sqrt()).alias("centre_error"),
        (pl.col("est_vx") - pl.col("vx")).alias("vx_error"),
        (pl.col("est_vy") - pl.col("vy")).alias("vy_error"),
    ).sort("frame")


def _f(v) -> float | None:
    return None if v is None or not np.isfinite(v) else float(v)



def _error_figures(ce: np.ndarray, ious_all: np.ndarray, ex: np.ndarray, ey: np.ndarray, n: int) -> dict:
    """The summary's error figures from the centre errors, the IoUs (0 where nothing was tracked),
    the velocity errors and the visible frames: one arithmetic for the whole table and the chunks."""
    return dict(
        centre_error_mean=_f(ce.mean()) if ce.size else None,
        centre_error_median=_f(np.median(ce)) if ce.size else None,
        centre_error_rmse=_f(np.sqrt(np.mean(ce**2))) if ce.size else None,
        precision_at_20px=float(np.sum(ce <= PRECISION_PX) / n) if n else None,
        iou_mean=_f(ious_all.mean()) if ious_all.size else None,
        success_auc=_f(np.mean([(ious_all > t).mean() for t in IOU_THRESHOLDS])) if ious_all.size else None,
        velocity_rmse_x=_f(np.sqrt(np.mean(ex**2))) if ex.size else None,
        velocity_rmse_y=_f(np.sqrt(np.mean(ey**2))) if ey.size else None,
        velocity_error_mean=_f(np.mean(np.hypot(ex, ey))) if ex.size else None,
        velocity_frames=int(ex.size),
    )

def evaluate(traj: pl.DataFrame, gt: pl.DataFrame, *, track_id: int | None = None, gt_id: int | None = None) -> tuple[EvalSummary, pl.DataFrame]:
    frames = per_frame(traj, gt, track_id=track_id, gt_id=gt_id)
    visible = frames.filter(pl.col("x").is_not_null() & (pl.col("visible").fill_null(True)))
    tracked = visible.filter(pl.col("est_x").is_not_null())
    ce = tracked["centre_error"].to_numpy()
    boxes = tracked.filter(pl.col("w").is_not_null() & pl.col("est_w").is_not_null())
    ious = (box_iou(boxes.select("est_x", "est_y", "est_w", "est_h").to_numpy(), boxes.select("x", "y", "w", "h").to_numpy(),
                    centred=True) if boxes.height else np.array([]))
    # A frame the tracker missed counts as IoU 0 and as beyond the precision radius (OTB convention).
    n = visible.height
    ious_all = np.concatenate([ious, np.zeros(n - ious.size)]) if n else ious
    measured = tracked.filter(pl.col("status") == "measured")
    near = [float(np.sum(measured["centre_error"].to_numpy() <= r) / n) if n else None for r in NEAR_PX]
    mboxes = boxes.filter(pl.col("status") == "measured")
    mious = (box_iou(mboxes.select("est_x", "est_y", "est_w", "est_h").to_numpy(), mboxes.select("x", "y", "w", "h").to_numpy(),
                     centred=True) if mboxes.height else np.array([]))
    n_boxes = visible.filter(pl.col("w").is_not_null()).height
    vel = tracked.filter(pl.col("vx").is_not_null() & pl.col("est_vx").is_not_null())
    ex, ey = vel["vx_error"].to_numpy(), vel["vy_error"].to_numpy()
    summary = EvalSummary(
        tracker=str(frames["tracker"].drop_nulls()[0]) if frames["tracker"].drop_nulls().len() else "",
        track_id=int(frames["track_id"].drop_nulls()[0]) if frames["track_id"].drop_nulls().len() else -1,
        gt_id=int(frames["id"][0]),
        gt_frames=n,
        tracked_frames=tracked.height,
        coverage=tracked.height / n if n else 0.0,
        **_error_figures(ce, ious_all, ex, ey, n),
        measured_frames=measured.height,
        measured_within_5px=near[0], measured_within_10px=near[1],
        measured_iou_50=float(np.sum(mious >= RIGHT_IOU) / n) if n_boxes else None,
    )
    return summary, frames


# A long log is scored this many truth frames at a time (docs/memory.md): only the counts and the
# per-frame numbers the mean and median need (8 bytes a frame each) are kept between chunks.
EVAL_CHUNK_FRAMES = 4096
CHECK_ROWS = 2048  # a trajectory file is checked this many rows at a time (larger pieces peak higher)


@dataclass
class _Running:
    """What :func:`evaluate` needs of the per-frame table, gathered a chunk of frames at a time: the
    counts, and the centre errors, IoUs and velocity errors in frame order (the same arrays as the
    whole table's, so the means and the median are the same to the bit)."""

    visible: int = 0
    tracked: int = 0
    measured: int = 0
    boxed: int = 0  # visible truth frames with a box
    near: tuple[int, int] = (0, 0)
    measured_right: int = 0  # measured boxes with IoU >= RIGHT_IOU
    tracker: str | None = None
    track_id: int | None = None
    gt_id: int | None = None
    parts: dict[str, list[np.ndarray]] | None = None

    def add(self, frames: pl.DataFrame) -> None:
        """Count one chunk of :func:`per_frame`'s rows (in frame order)."""
        parts = self.parts if self.parts is not None else {k: [] for k in ("ce", "ious", "ex", "ey")}
        self.parts = parts
        if self.tracker is None and frames["tracker"].drop_nulls().len():
            self.tracker = str(frames["tracker"].drop_nulls()[0])
        if self.track_id is None and frames["track_id"].drop_nulls().len():
            self.track_id = int(frames["track_id"].drop_nulls()[0])
        if self.gt_id is None and frames.height:
            self.gt_id = int(frames["id"][0])
        visible = frames.filter(pl.col("x").is_not_null() & (pl.col("visible").fill_null(True)))
        tracked = visible.filter(pl.col("est_x").is_not_null())
        boxes = tracked.filter(pl.col("w").is_not_null() & pl.col("est_w").is_not_null())
        measured = tracked.filter(pl.col("status") == "measured")
        mboxes = boxes.filter(pl.col("status") == "measured")
        m_err = measured["centre_error"].to_numpy()
        self.visible += visible.height
        self.tracked += tracked.height
        self.measured += measured.height
        self.boxed += visible.filter(pl.col("w").is_not_null()).height
        self.near = tuple(k + int(np.sum(m_err <= r)) for k, r in zip(self.near, NEAR_PX))  # type: ignore[assignment]
        self.measured_right += int(np.sum(_ious(mboxes) >= RIGHT_IOU))
        parts["ce"].append(tracked["centre_error"].to_numpy())
        parts["ious"].append(_ious(boxes))
        vel = tracked.filter(pl.col("vx").is_not_null() & pl.col("est_vx").is_not_null())
        parts["ex"].append(vel["vx_error"].to_numpy())
        parts["ey"].append(vel["vy_error"].to_numpy())

    def summary(self) -> EvalSummary:
        """:func:`evaluate`'s summary, with its arithmetic on the same arrays."""
        parts = self.parts or {}
        ce, ious, ex, ey = (np.concatenate(parts.get(k) or [np.array([])]) for k in ("ce", "ious", "ex", "ey"))
        n = self.visible
        ious_all = np.concatenate([ious, np.zeros(n - ious.size)]) if n else ious
        return EvalSummary(
            tracker=self.tracker or "", track_id=-1 if self.track_id is None else self.track_id,
            gt_id=int(self.gt_id if self.gt_id is not None else -1), gt_frames=n, tracked_frames=self.tracked,
            coverage=self.tracked / n if n else 0.0,
            **_error_figures(ce, ious_all, ex, ey, n), measured_frames=self.measured,
            measured_within_5px=float(self.near[0] / n) if n else None,
            measured_within_10px=float(self.near[1] / n) if n else None,
            measured_iou_50=float(self.measured_right / n) if self.boxed else None,
        )


def _ious(boxes: pl.DataFrame) -> np.ndarray:
    """IoU of each row's estimated box with its truth box (centred boxes)."""
    if not boxes.height:
        return np.array([])
    return box_iou(boxes.select("est_x", "est_y", "est_w", "est_h").to_numpy(), boxes.select("x", "y", "w", "h").to_numpy(),
                   centred=True)


def _pick_track_lazy(traj: pl.LazyFrame, track_id: int | None) -> int:
    """:func:`_pick_track`'s choice and refusals, on a lazy table (only ``track_id`` and ``x`` read)."""
    counts = traj.select("track_id", "x").group_by("track_id").agg(pl.len().alias("rows"), pl.col("x").count().alias("len"))
    counts = counts.collect()
    if counts.is_empty():
        raise TrackreplayError("the trajectory has no rows to evaluate")
    if track_id is None:
        placed = counts.filter(pl.col("len") > 0).sort(["len", "track_id"], descending=[True, False])
        if placed.is_empty():
            raise TrackreplayError("the trajectory has no positioned rows to evaluate")
        return int(placed["track_id"][0])
    if counts.filter(pl.col("track_id") == track_id).is_empty():
        raise TrackreplayError(f"the trajectory has no track {track_id}")
    return track_id


def evaluate_chunked(traj: pl.LazyFrame, gt: pl.DataFrame, *, track_id: int | None = None, gt_id: int | None = None,
                     chunk_frames: int = EVAL_CHUNK_FRAMES) -> EvalSummary:
    """:func:`evaluate`'s summary in memory flat in the log's length: the truth object's frames
    ``chunk_frames`` at a time, each with only the track's rows on those frames read (a filter the
    scan pushes down to a Parquet file)."""
    obj = _object_rows(gt, _gt_id(gt, gt_id))
    return evaluate_parts(traj, lambda: (obj.slice(start, chunk_frames) for start in range(0, obj.height, chunk_frames)),
                          track_id=track_id)


def evaluate_parts(traj: pl.LazyFrame, parts, *, track_id: int | None = None) -> EvalSummary:
    """:func:`evaluate_chunked` on the truth object's rows as ``parts()`` gives them: tables of its
    rows in frame order, one after the other (a slice of a table in memory, or read from the log a
    chunk at a time: :func:`truth_parts`)."""
    tid = _pick_track_lazy(traj, track_id)
    track = traj.filter(pl.col("track_id") == tid)
    running = _Running()
    for part in parts():
        if not part.height:
            continue
        lo, hi = part["frame"].min(), part["frame"].max()
        rows = track.filter(pl.col("frame").is_between(lo, hi)).collect()
        try:
            _same_frames(rows, part)
        except TrackreplayError:  # the whole table's sentence (the first frame and how many disagree)
            _same_frames(track.collect(), pl.concat(list(parts())))
            raise
        running.add(_joined(rows, part))
    return running.summary()


TRUTH_COLUMNS = {"frame": pl.Int64, "t_ns": pl.Int64, "id": pl.Int64, "x": pl.Float64, "y": pl.Float64, "w": pl.Float64,
                 "h": pl.Float64, "vx": pl.Float64, "vy": pl.Float64, "visible": pl.Boolean}  # what one object's score reads
_FIELDS = tuple(TRUTH_COLUMNS)[3:]  # the truth message's fields of the same names (schemas/records.py)


@dataclass(frozen=True)
class TruthIndex:
    """What scoring one object needs of a log's whole ground truth, read without keeping its rows
    (:func:`truth_index`): the annotated frames, and per object the frames that place it."""

    annotated: pl.DataFrame  # frame, t_ns of every truth message (as groundtruth_with_frames gives them)
    placed: dict[int, int]  # object id -> rows with a position
    seen: frozenset[int]  # objects placed and visible (or visibility unknown) on some frame
    ids: frozenset[int]  # every object with a row
    in_order: bool  # the messages come in increasing frame order, an object at most once in each

    def gt_id(self, gt_id: int | None) -> int:
        """:func:`_gt_id`'s choice and refusals, from the counts."""
        if not self.ids:
            raise TrackreplayError("the log's ground truth holds no objects")
        if gt_id is None:
            if not self.placed:
                raise TrackreplayError("the log's ground truth places no object on any frame (every row marks it absent)")
            gt_id = min(self.placed, key=lambda i: (-self.placed[i], i))
        if gt_id not in self.ids:
            raise TrackreplayError(f"the ground truth has no object {gt_id}")
        return gt_id


def truth_index(reader, topic: str, image_topic: str | None = None) -> tuple[TruthIndex, pl.DataFrame]:
    """One pass over the log's truth messages and its images (issue 33: a 200k-frame truth table and
    its building cost ~50 MB, the images' frame -> time dict ~20 MB; these are 16 bytes a frame and
    a count per object). Returns the index and the images' ``frame, t_ns`` (``image_topic``: as
    :func:`~trackreplay.replay.log.frames.image_times`)."""
    from array import array

    from trackreplay.replay.log.frames import choose_image_topic, require_image_topic

    reader.require(topic)
    images = image_topic or choose_image_topic(reader)
    require_image_topic(reader, images)
    frames, times, image_index, image_times = array("q"), array("q"), array("q"), array("q")
    placed: dict[int, int] = {}
    seen, ids = set(), set()
    last, in_order = None, True
    for item in reader.messages([topic, images]):
        if item.topic == images:
            if item.lost is None or item.log_time >= 0:
                image_index.append(item.index)
                image_times.append(item.log_time)
            continue
        pb = item.decode()  # read as GroundTruthFrame.from_pb reads it, only the fields needed here
        frames.append(pb.frame)
        times.append(pb.t_ns)
        objects = pb.objects
        in_order = in_order and (last is None or pb.frame > last) and len({o.id for o in objects}) == len(objects)
        last = pb.frame
        for o in objects:
            ids.add(o.id)
            if o.HasField("x"):
                placed[o.id] = placed.get(o.id, 0) + 1
                if not (o.HasField("visible") and not o.visible):
                    seen.add(o.id)
    increasing = all(a < b for a, b in zip(frames, frames[1:])) if not in_order else True
    annotated = _frame_table(frames, times)
    del frames, times
    if not increasing:  # (in increasing frame order it already is unique and sorted: no copies)
        annotated = annotated.unique("frame").sort("frame")
    return TruthIndex(annotated, placed, frozenset(seen), frozenset(ids), in_order), _frame_table(image_index, image_times)


def _frame_table(frames, times) -> pl.DataFrame:
    return pl.DataFrame({"frame": np.frombuffer(frames, np.int64), "t_ns": np.frombuffer(times, np.int64)},
                        schema={"frame": pl.Int64, "t_ns": pl.Int64})


def truth_parts(reader, topic: str, gt_id: int | None, chunk_frames: int | None = None):
    """``parts()`` for :func:`evaluate_parts`: object ``gt_id``'s truth rows read from the log,
    ``chunk_frames`` rows at a time (the :data:`TRUTH_COLUMNS`; the messages in frame order:
    :attr:`TruthIndex.in_order`); ``gt_id`` None: every object's rows, whole messages a part (at
    least ``chunk_frames`` rows, :func:`object_followed_parts`)."""
    chunk_frames = chunk_frames or EVAL_CHUNK_FRAMES

    def parts():
        rows: list[tuple] = []
        for item in reader.messages([topic]):
            pb = item.decode()
            for o in pb.objects:
                if gt_id is None or o.id == gt_id:  # GroundTruthObject.from_pb's values: None where a field is not set
                    rows.append((pb.frame, pb.t_ns, o.id, *(getattr(o, n) if o.HasField(n) else None for n in _FIELDS)))
            if len(rows) >= chunk_frames:
                yield pl.DataFrame(rows, schema=TRUTH_COLUMNS, orient="row")
                rows = []
        if rows:
            yield pl.DataFrame(rows, schema=TRUTH_COLUMNS, orient="row")

    return parts


def checked_scan(path: Path, chunk_rows: int = CHECK_ROWS) -> tuple[pl.LazyFrame, pl.DataFrame] | None:
    """A Parquet trajectory as a lazy table of the ★ columns and its keys (``tracker, status`` as
    categories, ``track_id, frame, t_ns, x, y``, ~45 bytes a row, canonical order), checked ``chunk_rows`` rows at a time as
    :func:`~trackreplay.replay.core.export.read_trajectory` checks the whole table. None when any check
    fails or the file does not read: then read it whole, which names the defect in its own words."""
    try:
        scan = pl.scan_parquet(path)
        names = scan.collect_schema().names()
        if "confidence" not in names:  # tables written before the column existed
            scan = scan.with_columns(pl.lit(None, dtype=pl.Float64).alias("confidence"))
        keys = []
        for part in scan.collect_batches(chunk_size=chunk_rows):  # (a sliced scan would read the whole file each time)
            part = conform(part, str(path))
            keys.append(part.select(pl.col("tracker", "status").cast(pl.Categorical), "track_id", "frame", "t_ns", "x", "y"))
    except (TrackreplayError, pl.exceptions.PolarsError, OSError):
        return None
    if not keys:
        return None
    table = pl.concat(keys, rechunk=False)  # the pieces as its chunks: no second copy
    del keys
    if not _in_order(table):  # a replay writes the canonical order: no second copy to sort
        table = table.sort(list(KEY), maintain_order=True)
    # sorted, a second row for a track and frame lies next to the first (a hash of every key costs ~200 B a row)
    if table.select(pl.all_horizontal(pl.col(c) == pl.col(c).shift(1) for c in KEY).any()).item():
        return None
    typed = scan.select(pl.col(c).cast(dtype) for c, dtype in SCHEMA.items())
    return typed, table


def _in_order(table: pl.DataFrame) -> bool:
    """Whether ``table`` is sorted by :data:`KEY` (``tracker`` by its text), checked on consecutive rows."""
    later, same = None, None
    for c in KEY:
        col = pl.col(c).cast(pl.String) if table.schema[c] == pl.Categorical else pl.col(c)
        gt, eq = col > col.shift(1), col == col.shift(1)
        later, same = (gt, eq) if later is None else (later | (same & gt), same & eq)
    return bool(table.select((later | same).fill_null(True).all()).item())


def format_summary(s: EvalSummary) -> str:
    def fmt(v, unit=""):
        return "n/a" if v is None else (f"{v:.3f}{unit}" if isinstance(v, float) else f"{v}{unit}")

    def share(v, n=s.gt_frames):
        return "n/a" if v is None else f"{round(v * n)} of {n} visible ({100 * v:.1f}%)"

    def pct(part):
        return f"{100 * part / s.gt_frames:.1f}%" if s.gt_frames else "n/a"

    rows = [
        ("tracker / track", f"{s.tracker} / {s.track_id} vs ground-truth object {s.gt_id}"),
        ("measured within 5 px", share(s.measured_within_5px)),
        ("measured within 10 px", share(s.measured_within_10px)),
        *([("measured with IoU >= 0.5", share(s.measured_iou_50))] if s.measured_iou_50 is not None else []),
        ("measured", f"{s.measured_frames} of {s.gt_frames} visible ({pct(s.measured_frames)})"),
        ("frames tracked (measured, predicted or interpolated)",
         f"{s.tracked_frames} of {s.gt_frames} visible ({100 * s.coverage:.1f}%)"),
        ("centre error mean / median / RMSE", f"{fmt(s.centre_error_mean)} / {fmt(s.centre_error_median)} / {fmt(s.centre_error_rmse)} px"),
        ("precision @ 20 px", fmt(s.precision_at_20px)),
        ("IoU mean / success AUC", f"{fmt(s.iou_mean)} / {fmt(s.success_auc)}"),
        ("velocity RMSE x / y", f"{fmt(s.velocity_rmse_x)} / {fmt(s.velocity_rmse_y)} px/frame ({s.velocity_frames} frames)"),
        ("velocity error mean |dv|", f"{fmt(s.velocity_error_mean)} px/frame"),
    ]
    width = max(len(k) for k, _ in rows)
    return "\n".join(f"{k:<{width}}  {v}" for k, v in rows)
