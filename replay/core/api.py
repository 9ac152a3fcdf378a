"""The Python API for notebooks and scripts (see README "Python API"): replay a log in one call,
open a log's frames, truth and marks, export a trajectory. ``evaluate`` and ``smooth`` sit on the
analysis floor: :mod:`trackreplay.replay.runs.notebook`."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import polars as pl

from trackreplay.schemas import topics as T
from trackreplay.schemas.errors import LogError
from trackreplay.trackers.frame import Frame
from trackreplay.replay.core.config import ConfigSource
from trackreplay.replay.core.engine import ReplayRequest, ReplayResult, replay
from trackreplay.replay.core.export import fill_gaps, trajectory_format, write_trajectory
from trackreplay.replay.core.trajectory import COLUMNS
from trackreplay.replay.log.decode import decode_image
from trackreplay.replay.log.frames import (FrameTopics, choose_image_topic, image_times, iter_frames, read_hints,
                                           require_image_topic)
from trackreplay.replay.log.groundtruth import GT_SCHEMA, read_groundtruth
from trackreplay.replay.log.reader import LogMessage, LogReader


def replay_log(log: str | Path, tracker: str, *, config: ConfigSource = None, seed: int = 0,
               rrd: str | Path | None = None, start_s: float | None = None, end_s: float | None = None,
               image_topic: str | None = None) -> ReplayResult:
    """Replay ``tracker`` over ``log`` exactly as ``trackreplay replay`` does.

    ``config`` is None (the tracker's defaults), its config dataclass, a dict nested like the
    config (``{"particles": {"n": 500}}``) or a TOML file (the tracker's table or the top level).
    Returns the trajectory as a Polars DataFrame (``.trajectory``; past 2048 rows the replay keeps it
    in a temporary Parquet file and each access reads it back, ``.scan_trajectory()`` queries it
    lazily in bounded memory: docs/memory.md), the ``.digest`` the CLI
    prints for the same log, config and seed, the frame count and the tracker's ``.notices``;
    with ``rrd`` every intermediate also goes to that Rerun file.
    """
    return replay(ReplayRequest(
        log=Path(log), tracker=tracker, config=config, seed=seed, rrd=None if rrd is None else Path(rrd),
        start_s=start_s, end_s=end_s, image_topic=image_topic,
    ))


class LogFrames:
    """The images of one topic as numpy arrays: ``len``, ``frames[i]`` (negative and slices too) and
    iteration in log order. Each image is decoded when asked for, BGR ``uint8`` (H, W, 3) or grey (H, W),
    as the trackers receive it; ``frames[i]`` reads only the chunk that holds image ``i``."""

    def __init__(self, reader: LogReader, topic: str) -> None:
        self.reader, self.topic = reader, topic

    def __len__(self) -> int:
        return self.reader.topics()[self.topic].count

    def __repr__(self) -> str:
        return f"<{len(self)} frames of {self.topic} in {self.reader.path.name}>"

    def _image(self, item: LogMessage) -> np.ndarray:
        if item.lost is not None:
            raise LogError(f"{self.reader.path}: frame {item.index} on {self.topic} is lost ({item.lost})")
        return decode_image(item.decode(), item.schema, f"{self.reader.path}: topic {self.topic} message {item.index}")[0]

    def __iter__(self) -> Iterator[np.ndarray]:
        """Every image in log order; one lost with a damaged chunk is skipped (``items`` numbers them)."""
        return (image for _, _, image in self.items())

    def items(self) -> Iterator[tuple[int, int, np.ndarray]]:
        """``(frame, t_ns, image)`` of every image in log order, lost ones skipped."""
        for item in self.reader.messages([self.topic]):
            if item.lost is None:
                yield item.index, item.log_time, self._image(item)

    def __getitem__(self, key: int | slice) -> np.ndarray | list[np.ndarray]:
        n = len(self)
        if isinstance(key, slice):
            return self._at(list(range(n))[key])
        if isinstance(key, bool) or not isinstance(key, int | np.integer):
            raise TypeError(f"frames are indexed by an int or a slice, not {type(key).__name__}")
        index = int(key) + n if key < 0 else int(key)
        if not 0 <= index < n:
            raise IndexError(f"{self.reader.path} has no frame {key} on {self.topic} (it has {n} frames)")
        return self._at([index])[0]

    def _at(self, indices: list[int]) -> list[np.ndarray]:
        found = self.reader.messages_at(self.topic, indices)
        if found is None:  # the index cannot say (an unindexed log, ...): read through
            wanted = set(indices)
            found = [item for item in self.reader.messages([self.topic]) if item.index in wanted]
        by_index = {item.index: item for item in found}
        missing = [i for i in indices if i not in by_index]
        if missing:
            raise LogError(f"{self.reader.path}: frame {missing[0]} on {self.topic} is lost (damaged chunk)")
        return [self._image(by_index[i]) for i in indices]


class OpenedLog:
    """A log opened for reading in a notebook (:func:`open_log`): ``frames`` (numpy images),
    ``truth`` and ``marks`` (Polars DataFrames), ``times``, ``topics``, ``info()`` and ``bundles()``
    (the frames as a tracker receives them: stereo pairs, PTZ, calibrations)."""

    def __init__(self, path: str | Path, image_topic: str | None = None) -> None:
        self.reader = LogReader(path)
        self.path: Path = self.reader.path
        if image_topic is None:
            image_topic = choose_image_topic(self.reader)
        else:
            require_image_topic(self.reader, image_topic)
        self.image_topic = image_topic
        self.frames = LogFrames(self.reader, image_topic)

    def __repr__(self) -> str:
        return f"<log {self.path.name}: {len(self.frames)} frames on {self.image_topic}, {len(self.reader.topics())} topics>"

    @property
    def topics(self) -> pl.DataFrame:
        """One row per topic: ``topic, schema, encoding, messages``."""
        rows = [(t.topic, t.schema, t.encoding, t.count) for t in self.reader.topics().values()]
        return pl.DataFrame(rows, schema={"topic": pl.String, "schema": pl.String, "encoding": pl.String,
                                          "messages": pl.Int64}, orient="row").sort("topic")

    @property
    def times(self) -> pl.DataFrame:
        """``frame, t_ns`` of every image on the image topic: the frame numbers a replay gives."""
        times = image_times(self.reader, self.image_topic)
        return pl.DataFrame({"frame": list(times), "t_ns": list(times.values())}, schema={"frame": pl.Int64, "t_ns": pl.Int64})

    def truth_table(self, topic: str = T.GROUNDTRUTH) -> pl.DataFrame:
        """The ground truth on ``topic`` (``/groundtruth/objects``; the groups scenes also write
        ``/groundtruth/groups``) as :func:`~trackreplay.replay.log.groundtruth.read_groundtruth` reads
        it: one row per object per frame, ``x, y`` the centre in pixels, ``X Y Z`` in metres; no rows
        when the log has none."""
        if topic not in self.reader.topics():
            return pl.DataFrame(schema=GT_SCHEMA)
        return read_groundtruth(self.reader, topic)

    @property
    def truth(self) -> pl.DataFrame:
        """:meth:`truth_table` of ``/groundtruth/objects``."""
        return self.truth_table()

    @property
    def marks(self) -> pl.DataFrame:
        """The marks trackers start from (``/annotations/init``): ``frame, t_ns, label`` and the box as
        centre ``x, y`` and size ``w, h`` in pixels; no rows when the log marks nothing."""
        regions = read_hints(self.reader, T.ANNOTATIONS_INIT, self.image_topic)
        return pl.DataFrame([(r.frame, r.t_ns, r.label, r.x, r.y, r.w, r.h) for r in regions],
                            schema=MARKS_SCHEMA, orient="row")

    def info(self) -> dict[str, Any]:
        """What ``trackreplay info --json`` prints: topics, rates, gaps, chunking, damage."""
        from trackreplay.replay.log.info import log_info

        return log_info(self.path)

    def bundles(self, *, stereo_topics: tuple[str, str] | None = None) -> Iterator[Frame]:
        """The frames as the engine bundles them for a tracker (:class:`~trackreplay.trackers.frame.Frame`:
        ``image``, stereo ``right``, PTZ reading and camera, marks, calibrations)."""
        topics = FrameTopics.detect(self.reader, None if stereo_topics else self.image_topic, stereo_topics)
        return iter_frames(self.reader, topics)


MARKS_SCHEMA = {"frame": pl.Int64, "t_ns": pl.Int64, "label": pl.String,
                "x": pl.Float64, "y": pl.Float64, "w": pl.Float64, "h": pl.Float64}


def open_log(path: str | Path, *, image_topic: str | None = None) -> OpenedLog:
    """Open an MCAP log (or a ROS 2 bag folder) for reading in a notebook.

    ``log.frames`` are the images as numpy arrays (``len``, ``log.frames[i]``, iteration),
    ``log.truth`` and ``log.marks`` Polars DataFrames, ``log.topics`` and ``log.info()`` what the
    log holds. ``image_topic``: as ``replay --image-topic`` (default ``/camera/image``, else the
    stereo left, else the log's only image topic).
    """
    return OpenedLog(path, image_topic)


def export(trajectory: pl.DataFrame | ReplayResult, path: str | Path, *, interpolate: str = "linear",
           max_gap: int = 15) -> pl.DataFrame:
    """Write a trajectory as ``trackreplay export`` does and return the table written.

    ``trajectory``: a DataFrame (the ★ table) or a :func:`replay_log` result. Interior gaps of at
    most ``max_gap`` frames are filled (``interpolate`` ``"linear"`` or ``"cubic"``; ``"none"`` keeps
    them) with ``status = "interpolated"``; the suffix of ``path`` chooses the format: ``.parquet``,
    ``.csv`` or ``.txt`` (MOTChallenge, 1-based frames and pixels). Columns beyond the ★ table's (a
    smoothed table's ``*_std`` and ``fill``) are kept, null on the rows the interpolation adds.
    """
    table = trajectory.trajectory if isinstance(trajectory, ReplayResult) else trajectory
    trajectory_format(path)  # a wrong suffix before any work
    if interpolate != "none":
        keys = ["tracker", "track_id", "frame"]
        extra = [c for c in table.columns if c not in COLUMNS]
        filled = fill_gaps(table.select(COLUMNS), interpolate, max_gap)
        table = filled.join(table.select(*keys, *extra), on=keys, how="left", maintain_order="left") if extra else filled
    write_trajectory(table, path)
    return table
