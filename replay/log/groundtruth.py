"""Ground truth from ``/groundtruth/objects`` as a Polars table (one row per object per frame)."""

from __future__ import annotations

import numpy as np
import polars as pl

from trackreplay.schemas import topics as T
from trackreplay.schemas.records import GroundTruthFrame
from trackreplay.replay.log.frames import read_rig_pose
from trackreplay.replay.log.reader import LogReader

GT_SCHEMA = {
    "frame": pl.Int64, "t_ns": pl.Int64, "id": pl.Int64,
    "x": pl.Float64, "y": pl.Float64, "w": pl.Float64, "h": pl.Float64,
    "X": pl.Float64, "Y": pl.Float64, "Z": pl.Float64,
    "vx": pl.Float64, "vy": pl.Float64, "visible": pl.Boolean, "group": pl.Int64,
}

_FRAMES_SCHEMA = {"frame": pl.Int64, "t_ns": pl.Int64}
_BATCH = 4096  # ground-truth rows read before they become columns


def read_groundtruth(reader: LogReader, topic: str = T.GROUNDTRUTH, rig_world: bool = True) -> pl.DataFrame:
    """Ground truth rows, one per object per labelled frame, sorted by ``id, frame``:

    - ``frame`` (the image's position in the log), ``t_ns``, ``id``;
    - ``x, y``: the centre in image pixels; ``w, h``: the box size, null for a point truth (VOT/OTB/MOT
      files give boxes; point labels, TrackNet and reference files give centres only); ``x, y`` are
      null too where the truth places nothing (an absent target);
    - ``visible``: false where the truth says the target is not seen (absent, or occluded: a synthetic
      scene's truth may still place it); null when the truth does not say;
    - ``X Y Z`` (metres) as stored (stereo scenes: the left camera's frame), or, when the log carries
      the stereo rig's pose (``/stereo/pose``) and ``rig_world``, in that world frame (Z up) — the
      frame the group tracker then reports in, so the two compare as they are;
    - ``vx, vy`` (pixels per frame) and ``group``, where the truth gives them.

    A frame without a row is not labelled (for that object), unless :func:`groundtruth_with_frames`
    lists it as annotated: then the truth says nothing is there."""
    return groundtruth_with_frames(reader, topic, rig_world)[0]


def groundtruth_with_frames(reader: LogReader, topic: str = T.GROUNDTRUTH,
                            rig_world: bool = True) -> tuple[pl.DataFrame, pl.DataFrame]:
    """:func:`read_groundtruth`'s rows and the annotated frames (``frame, t_ns``, one per message),
    including those whose message lists no object: the truth says nothing is there."""
    reader.require(topic)
    rows, frames, parts, frame_parts = [], [], [], []
    for item in reader.messages([topic]):
        gt = GroundTruthFrame.from_pb(item.decode())
        frames.append((gt.frame, gt.t_ns))
        for o in gt.objects:
            rows.append((gt.frame, gt.t_ns, o.id, o.x, o.y, o.w, o.h, o.X, o.Y, o.Z, o.vx, o.vy, o.visible, o.group))
        if len(rows) >= _BATCH or len(frames) >= _BATCH:  # columns, not a Python tuple per row (~0.4 KB each)
            parts.append(pl.DataFrame(rows, schema=GT_SCHEMA, orient="row"))
            frame_parts.append(pl.DataFrame(frames, schema=_FRAMES_SCHEMA, orient="row"))
            rows, frames = [], []
    parts.append(pl.DataFrame(rows, schema=GT_SCHEMA, orient="row"))
    frame_parts.append(pl.DataFrame(frames, schema=_FRAMES_SCHEMA, orient="row"))
    table = pl.concat(parts, rechunk=True).sort(["id", "frame"])
    annotated = pl.concat(frame_parts, rechunk=True).unique("frame").sort("frame")
    pose = read_rig_pose(reader) if rig_world else None
    if pose is None or table.height == 0:
        return table, annotated
    cam = table.select("X", "Y", "Z").to_numpy().astype(np.float64)
    world = pose.to_world(np.nan_to_num(cam))
    world[~np.isfinite(cam).all(axis=1)] = np.nan
    return table.with_columns(*(pl.Series(c, world[:, k]).fill_nan(None) for k, c in enumerate("XYZ"))), annotated
