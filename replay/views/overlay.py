"""Draw a trajectory over the log's frames: from its image positions (any tracker), or, for a PTZ
log, the whole trajectory into any frame from its stored lines of sight (seed 000, the broadcast use).

A PTZ camera only rotates, so the unit vectors ``(dx, dy, dz)`` recorded per frame project into
the image of any other pose without depth. Image positions are drawn as each frame's boxes (or dots
where the trajectory has no size), labelled "id status" and coloured by status, with a short trail,
and the log's ground truth beside them in magenta.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import cv2
import numpy as np
import polars as pl

from trackreplay.replay.views.parts import STATUS_COLOURS
from trackreplay.replay.views.truth import SEEN, UNSEEN
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


# --- image positions (every tracker) ----------------------------------------------------------

STATUS_BGR = {status: tuple(reversed(rgb[:3])) for status, rgb in STATUS_COLOURS.items()}
TRUTH_BGR, TRUTH_UNSEEN_BGR = tuple(reversed(SEEN)), tuple(reversed(UNSEEN))
TRAIL = 30  # frames of each track's past positions drawn behind its box
FONT = cv2.FONT_HERSHEY_SIMPLEX


def has_lines_of_sight(traj: pl.DataFrame) -> bool:
    """Whether the trajectory stores lines of sight (a PTZ log's golf: drawn by ``draw``)."""
    return traj.filter(pl.col("dx").is_not_null() & (pl.col("status") != "lost")).height > 0


class FrameRows:
    """Rows of a table with ``frame, x, y, w, h`` (and an id and a status or visibility), sorted by
    frame, so a frame's rows (or a window of frames) are a slice."""

    def __init__(self, table: pl.DataFrame, id_column: str) -> None:
        table = table.sort(["frame", id_column])
        self.frame = table["frame"].to_numpy()
        self.ids = table[id_column].to_numpy()
        self.xy = table.select("x", "y").to_numpy().astype(np.float64)
        self.wh = table.select("w", "h").to_numpy().astype(np.float64)
        self.status = table["status"].to_list() if "status" in table.columns else None
        self.visible = table["visible"].fill_null(True).to_numpy() if "visible" in table.columns else None

    def span(self, first: int, last: int) -> slice:
        """The rows of frames ``first`` to ``last`` (both included)."""
        lo, hi = np.searchsorted(self.frame, [first, last + 1], side="left").tolist()
        return slice(lo, hi)


@dataclass(frozen=True)
class ImageOverlay:
    """What is drawn over a frame: the trajectory's image rows and the log's truth (or None)."""

    tracks: FrameRows
    truth: FrameRows | None = None


def image_overlay(traj: pl.DataFrame, truth: pl.DataFrame | None, track_id: int | None = None) -> ImageOverlay:
    """The trajectory's rows with an image position (of one track when ``track_id``), and the truth's
    placed rows (``log.groundtruth.read_groundtruth``'s table)."""
    rows = traj.filter(pl.col("x").is_finite() & pl.col("y").is_finite())
    if rows.is_empty():
        raise TrackreplayError("the trajectory has no image positions (x, y) to draw")
    if track_id is not None:
        if rows.filter(pl.col("track_id") == track_id).is_empty():
            have = ", ".join(str(t) for t in sorted(rows["track_id"].unique().to_list()))
            raise TrackreplayError(f"the trajectory has no track {track_id} with image positions (tracks: {have})")
        rows = rows.filter(pl.col("track_id") == track_id)
    if truth is not None:
        truth = truth.filter(pl.col("x").is_finite() & pl.col("y").is_finite())
    placed = None if truth is None or truth.is_empty() else FrameRows(truth, "id")
    return ImageOverlay(FrameRows(rows, "track_id"), placed)


def draw_image_frame(image: np.ndarray, overlay: ImageOverlay, frame: int) -> np.ndarray:
    """``image`` (BGR or grey) with frame ``frame``'s truth, the tracks' trails and their boxes."""
    out = image.copy() if image.ndim == 3 else cv2.cvtColor(image, cv2.COLOR_GRAY2BGR)
    if overlay.truth is not None:
        rows = overlay.truth.span(frame, frame)
        colours = [TRUTH_BGR if v else TRUTH_UNSEEN_BGR for v in overlay.truth.visible[rows].tolist()]
        _marks(out, overlay.truth.xy[rows], overlay.truth.wh[rows], colours,
               [f"truth {i}" for i in overlay.truth.ids[rows].tolist()], thickness=1, below=True)
    tracks = overlay.tracks
    window = tracks.span(frame - TRAIL + 1, frame)
    now = tracks.span(frame, frame)
    colours = [STATUS_BGR[s] for s in tracks.status[now]]
    for track, colour in zip(tracks.ids[now].tolist(), colours):
        trail = tracks.xy[window][tracks.ids[window] == track]
        if len(trail) > 1:
            cv2.polylines(out, [_pixels(trail).astype(np.int32)], False, colour, 1, cv2.LINE_AA)
    _marks(out, tracks.xy[now], tracks.wh[now], colours,
           [f"{i} {s}" for i, s in zip(tracks.ids[now].tolist(), tracks.status[now])], thickness=2, below=False)
    return out


def _marks(out: np.ndarray, xy: np.ndarray, wh: np.ndarray, colours: list, labels: list[str], *, thickness: int,
           below: bool) -> None:
    """Boxes centred at ``xy`` (a cross where the size is unknown), each labelled above (or below) it."""
    boxed = np.isfinite(wh).all(axis=1)
    half = np.where(boxed[:, None], np.nan_to_num(wh) / 2.0, 4.0)
    corners = _pixels(np.concatenate([xy - half, xy + half], axis=1)).tolist()
    for (x0, y0, x1, y1), centre, is_box, colour, label in zip(corners, _pixels(xy).tolist(), boxed.tolist(), colours,
                                                               labels):
        if is_box:
            cv2.rectangle(out, (x0, y0), (x1, y1), colour, thickness, cv2.LINE_8)
        else:
            cv2.drawMarker(out, tuple(centre), colour, cv2.MARKER_CROSS if below else cv2.MARKER_SQUARE, 9, thickness)
        y = y1 + 11 if below or y0 < 12 else y0 - 3  # under the box where above it is off the image
        cv2.putText(out, label, (x0, min(y, out.shape[0] - 2)), FONT, 0.35, colour, 1, cv2.LINE_AA)


def _pixels(values: np.ndarray) -> np.ndarray:
    """Rounded to whole pixels, kept within what OpenCV's drawing takes (a point far off the image)."""
    return np.clip(np.round(values), -(1 << 20), 1 << 20).astype(np.int64)


def image_overlay_frames(frames: Iterator[Frame], overlay: ImageOverlay) -> Iterator[tuple[Frame, np.ndarray]]:
    """Each frame with its tracks and truth drawn."""
    for frame in frames:
        yield frame, draw_image_frame(frame.image, overlay, frame.index)
