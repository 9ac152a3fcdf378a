"""The log's ground truth in a replay's Rerun stream, under ``truth/`` beside the tracker's entities.

``truth/boxes`` (Boxes2D) holds the truth given as boxes, ``truth/points`` (Points2D) the truth
given as centres only, ``truth/world`` (Points3D) the 3-D positions where the truth has them; each
labelled "truth {id}". They are sent at the frames the replay logs, on the same ``frame`` and
``log_time`` timelines as the camera images, with a row (possibly empty) at every such frame so a
truth does not linger past its last label. The rows go out as columns in blocks of frames, never
through the :class:`FrameLogger`, so the tracker's own chunks are the same with or without truth.
"""

from __future__ import annotations

import numpy as np
import polars as pl
import rerun as rr
import rerun.blueprint as rrb

TRUTH = "truth"
BOXES = f"{TRUTH}/boxes"
POINTS = f"{TRUTH}/points"
WORLD = f"{TRUTH}/world"
SEEN = (255, 0, 255)  # RGB magenta: none of parts.STATUS_COLOURS
UNSEEN = (140, 0, 140)  # where the truth says the target is not seen (occluded, still placed)
BLOCK_FRAMES = 256  # frames of truth sent together (a live viewer gets them this often)


class TruthStream:
    """Ground-truth rows (``log.groundtruth.read_groundtruth``'s table) sent to ``rec`` for the
    frames the replay logs (``add_frame``), matched by the image's position in the log."""

    def __init__(self, rec: rr.RecordingStream, table: pl.DataFrame, block_frames: int | None = None) -> None:
        self.rec = rec
        self.block_frames = BLOCK_FRAMES if block_frames is None else block_frames
        rows = table.sort(["frame", "id"])
        self._frame = rows["frame"].to_numpy()
        self._ids = rows["id"].to_numpy()
        self._xy = rows.select("x", "y").to_numpy().astype(np.float64)
        self._wh = rows.select("w", "h").to_numpy().astype(np.float64)
        self._xyz = rows.select("X", "Y", "Z").to_numpy().astype(np.float64)
        placed = np.isfinite(self._xy).all(axis=1)
        self._boxed = placed & np.isfinite(self._wh).all(axis=1)
        self._pointed = placed & ~self._boxed
        self._placed3d = np.isfinite(self._xyz).all(axis=1)
        visible = rows["visible"].fill_null(True).to_numpy()
        self._colours = np.where(visible[:, None], np.array([SEEN]), np.array([UNSEEN])).astype(np.uint8)
        self.paths = tuple(p for p, m in ((BOXES, self._boxed), (POINTS, self._pointed), (WORLD, self._placed3d))
                           if m.any())
        self._pending: list[tuple[int, int]] = []

    def add_frame(self, index: int, t_ns: int) -> None:
        """The replay logs frame ``index`` (at ``t_ns``): its truth goes out with this block."""
        if self.paths:
            self._pending.append((index, t_ns))
            if len(self._pending) >= self.block_frames:
                self.flush()

    def flush(self) -> None:
        """Send the pending frames' truth: one chunk per entity, entities in a fixed order."""
        if not self._pending:
            return
        frames = np.array([f for f, _ in self._pending], dtype=np.int64)
        times = np.array([t for _, t in self._pending], dtype="datetime64[ns]")
        self._pending = []
        lo = np.searchsorted(self._frame, frames, side="left")
        hi = np.searchsorted(self._frame, frames, side="right")
        rows = np.concatenate([np.arange(a, b) for a, b in zip(lo.tolist(), hi.tolist())])
        owner = np.repeat(np.arange(len(frames)), hi - lo)  # the pending frame each row belongs to
        indexes = [rr.TimeColumn("frame", sequence=frames), rr.TimeColumn("log_time", timestamp=times)]
        for path in self.paths:
            mine = self._mask(path)[rows]
            lengths = np.bincount(owner[mine], minlength=len(frames))
            self.rec.send_columns(path, indexes=indexes, columns=self._columns(path, rows[mine]).partition(lengths))

    def _mask(self, path: str) -> np.ndarray:
        return {BOXES: self._boxed, POINTS: self._pointed, WORLD: self._placed3d}[path]

    def _columns(self, path: str, rows: np.ndarray) -> rr.ComponentColumnList:
        labels = [f"truth {i}" for i in self._ids[rows].tolist()]
        colours = self._colours[rows]
        if path == BOXES:
            return rr.Boxes2D.columns(centers=self._xy[rows].astype(np.float32),
                                      half_sizes=(self._wh[rows] / 2.0).astype(np.float32), colors=colours, labels=labels)
        if path == POINTS:
            return rr.Points2D.columns(positions=self._xy[rows].astype(np.float32), radii=np.full(len(rows), 3.0, np.float32),
                                       colors=colours, labels=labels)
        return rr.Points3D.columns(positions=self._xyz[rows].astype(np.float32), radii=np.full(len(rows), 0.05, np.float32),
                                   colors=colours, labels=labels)


def show_truth(blueprint: rrb.Blueprint, paths: tuple[str, ...]) -> rrb.Blueprint:
    """``blueprint`` with the truth's 2-D entities added to each 2-D view that lists the camera image.
    ``truth/world`` is left out of the tracker's 3-D views: theirs may be another frame (the groups
    view's is the camera's, the truth's the rig's world)."""
    flat = [p for p in paths if p != WORLD]
    for view in _views(blueprint.root_container):
        contents = view.contents
        if isinstance(view, rrb.Spatial2DView) and isinstance(contents, list) and any(
                str(c) in ("camera/**", "camera/image") for c in contents):  # the left image, not camera/right
            contents.extend(p for p in flat if p not in contents)
    return blueprint


def _views(node: object) -> list[rrb.View]:
    """Every view under a blueprint container, depth first."""
    if isinstance(node, rrb.View):
        return [node]
    inner = getattr(node, "contents", None)
    return [v for child in inner for v in _views(child)] if isinstance(inner, (list, tuple)) else []
