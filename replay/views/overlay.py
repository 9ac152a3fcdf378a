"""Draw a whole trajectory into any frame from its stored lines of sight (seed 000, the broadcast use).

A PTZ camera only rotates, so the unit vectors ``(dx, dy, dz)`` recorded per frame project into
the image of any other pose without depth.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import cv2
import numpy as np
import polars as pl

from trackreplay.schemas.errors import TrackreplayError
from trackreplay.trackers.frame import Frame

MEASURED = (0, 215, 255)  # BGR gold
FILLED = (255, 200, 80)  # BGR light blue


@dataclass(frozen=True)
class OverlayPoints:
    """Image points of one trajectory under one frame's pose, in frame order."""

    points: np.ndarray  # (N, 2), NaN where behind the camera
    frames: np.ndarray  # (N,)
    measured: np.ndarray  # (N,) bool: measured/predicted vs interpolated


def trajectory_directions(traj: pl.DataFrame, track_id: int | None = None) -> pl.DataFrame:
    """Rows with a line of sight, of one track (default: the one with most such rows)."""
    rows = traj.filter(pl.col("dx").is_not_null() & (pl.col("status") != "lost"))
    if rows.is_empty():
        raise TrackreplayError("the trajectory has no lines of sight (dx, dy, dz): was it tracked with PTZ encoders?")
    if track_id is None:
        track_id = int(rows.group_by("track_id").len().sort(["len", "track_id"], descending=[True, False])["track_id"][0])
    picked = rows.filter(pl.col("track_id") == track_id).sort("frame")
    if picked.is_empty():
        have = ", ".join(str(t) for t in sorted(rows["track_id"].unique().to_list()))
        raise TrackreplayError(f"the trajectory has no track {track_id} with lines of sight (tracks: {have})")
    return picked


def project_trajectory(rows: pl.DataFrame, frame: Frame) -> OverlayPoints:
    if frame.camera is None:
        raise TrackreplayError(f"frame {frame.index} has no camera pose (no encoder reading or lens table at its time)")
    directions = rows.select("dx", "dy", "dz").to_numpy()
    return OverlayPoints(
        frame.camera.project_directions(directions),
        rows["frame"].to_numpy(),
        (rows["status"] != "interpolated").to_numpy(),
    )


def draw(image: np.ndarray, overlay: OverlayPoints, upto_frame: int | None = None, thickness: int = 2) -> np.ndarray:
    """The image with the trajectory as an anti-aliased polyline and dots at measured points."""
    out = image.copy() if image.ndim == 3 else cv2.cvtColor(image, cv2.COLOR_GRAY2BGR)
    keep = np.isfinite(overlay.points).all(axis=1)
    if upto_frame is not None:
        keep &= overlay.frames <= upto_frame
    pts, measured = overlay.points[keep], overlay.measured[keep]
    if len(pts) == 0:
        return out
    shift = 4  # sub-pixel drawing: coordinates in 1/16 px
    fixed = np.round(pts * (1 << shift)).astype(np.int64)
    fixed = np.clip(fixed, -(1 << 28), 1 << 28).astype(np.int32)
    for a, b, m in zip(fixed[:-1], fixed[1:], measured[1:]):
        cv2.line(out, tuple(a), tuple(b), MEASURED if m else FILLED, thickness, cv2.LINE_AA, shift)
    for p in fixed[measured]:
        cv2.circle(out, tuple(p), 2 << shift, MEASURED, -1, cv2.LINE_AA, shift)
    return out


def overlay_frames(frames: Iterator[Frame], rows: pl.DataFrame, *, progressive: bool) -> Iterator[tuple[Frame, np.ndarray, OverlayPoints | None]]:
    """Each frame with the trajectory drawn (up to that frame when ``progressive``)."""
    for frame in frames:
        if frame.camera is None:
            yield frame, frame.image, None
            continue
        pts = project_trajectory(rows, frame)
        yield frame, draw(frame.image, pts, frame.index if progressive else None), pts
