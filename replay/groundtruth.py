"""Ground truth from ``/groundtruth/objects`` as a Polars table (one row per object per frame)."""

from __future__ import annotations

import polars as pl

from trackreplay.schemas import topics as T
from trackreplay.schemas.records import GroundTruthFrame
from trackreplay.replay.reader import LogReader

GT_SCHEMA = {
    "frame": pl.Int64, "t_ns": pl.Int64, "id": pl.Int64,
    "x": pl.Float64, "y": pl.Float64, "w": pl.Float64, "h": pl.Float64,
    "X": pl.Float64, "Y": pl.Float64, "Z": pl.Float64,
    "vx": pl.Float64, "vy": pl.Float64, "visible": pl.Boolean, "group": pl.Int64,
}


def read_groundtruth(reader: LogReader, topic: str = T.GROUNDTRUTH) -> pl.DataFrame:
    reader.require(topic)
    rows = []
    for item in reader.messages([topic]):
        gt = GroundTruthFrame.from_pb(item.decode())
        for o in gt.objects:
            rows.append((gt.frame, gt.t_ns, o.id, o.x, o.y, o.w, o.h, o.X, o.Y, o.Z, o.vx, o.vy, o.visible, o.group))
    return pl.DataFrame(rows, schema=GT_SCHEMA, orient="row").sort(["id", "frame"])
