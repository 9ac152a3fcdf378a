"""Rerun view of the gradient-flow tracker (seed 004): every intermediate of a step."""

from __future__ import annotations

import functools
from collections.abc import Sequence

import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from trackreplay.trackers.base import TrackState
from trackreplay.trackers.frame import Frame

from trackreplay.replay.rerun_sink import FrameLogger
from trackreplay.replay.views import parts

ARROW_STRIDE = 4  # one arrow per 4x4 pixels keeps the field readable
ARROW_SCALE = 2.0
HIST_X_SCALE = 20.0  # drawing units per px/frame in the histogram view
MOVING_CLASS = 1


def blueprint(name: str) -> rrb.Blueprint:
    root = f"trackers/{name}"
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Spatial2DView(
                name="camera + FOV + flow",
                origin="/",
                contents=["camera/**", "tracks/**", f"{root}/fov", f"{root}/flow_field", f"{root}/centroid",
                          f"{root}/kalman/position", f"{root}/window/moving"],
            ),
            rrb.Vertical(
                rrb.Spatial2DView(name="FOV: log10 cond(G) (white = rejected side)", origin=f"{root}/window",
                                  contents=[f"{root}/window/log10_cond"]),
                rrb.Spatial2DView(name="flow histograms u, v (x: px/frame, up: pixels)", origin=f"{root}/histogram"),
            ),
            rrb.Vertical(
                rrb.TimeSeriesView(name="velocity raw vs filtered", origin=f"{root}/velocity"),
                rrb.TimeSeriesView(name="Kalman state", origin=f"{root}/kalman/state"),
                rrb.TimeSeriesView(name="Kalman sigma", origin=f"{root}/kalman/sigma"),
            ),
            column_shares=[2, 1, 1],
        ),
        collapse_panels=False,
    )


def log(rec: FrameLogger, name: str, frame: Frame, inter, states: Sequence[TrackState]) -> None:
    root = f"trackers/{name}"
    parts.box_xywh(rec, f"{root}/fov", inter.fov_box)
    parts.tracks(rec, states)
    if np.all(np.isfinite(inter.centroid)):
        parts.draw(rec, f"{root}/centroid", rr.Points2D, positions=np.asarray([inter.centroid], dtype=np.float32),
                   radii=1.5, colors=[(255, 0, 255)])
    else:
        parts.clear(rec, f"{root}/centroid")
    x0, y0 = float(inter.fov_box[0]), float(inter.fov_box[1])
    # The filters are per axis, so the position's covariance is diagonal.
    position_cov = np.diag([inter.kalman_P[0, 0, 0], inter.kalman_P[1, 0, 0]])
    parts.covariance_ellipses(rec, f"{root}/kalman/position", inter.kalman_x[:, 0], position_cov, colors=[(255, 255, 0)])

    # Flow arrows in full-image coordinates, subsampled, where the flow was accepted.
    u, v = inter.flow_u, inter.flow_v
    ys, xs = _arrow_grid(u.shape)
    us, vs = u[::ARROW_STRIDE, ::ARROW_STRIDE], v[::ARROW_STRIDE, ::ARROW_STRIDE]  # = u[ys, xs], v[ys, xs]
    keep = np.isfinite(us) & np.isfinite(vs)
    n = int(np.count_nonzero(keep))
    if n and isinstance(rec, FrameLogger):  # built at the flush for all frames at once (_Arrows)
        frame_arrows = _Arrows(xs, ys, us.copy(), vs.copy(), inter.moving[::ARROW_STRIDE, ::ARROW_STRIDE].copy(), keep,
                               x0, y0, n)
        parts.draw(rec, f"{root}/flow_field", rr.Arrows2D, origins=frame_arrows.field("origins"),
                   vectors=frame_arrows.field("vectors"), colors=frame_arrows.field("colors"))
    elif n:
        origins, vectors, colours = _arrows(xs, ys, us, vs, inter.moving[::ARROW_STRIDE, ::ARROW_STRIDE], keep, x0, y0)
        parts.draw(rec, f"{root}/flow_field", rr.Arrows2D, origins=origins, vectors=vectors, colors=colours)
    else:
        parts.clear(rec, f"{root}/flow_field")

    # FOV-space rasters sit at the window's place in the camera image, so they overlay it.
    parts.annotation_context(rec, f"{root}/window", [(0, "still", (0, 0, 0, 0)), (MOVING_CLASS, "moving", (255, 60, 60, 160))])
    parts.mask_over_crop(rec, f"{root}/window", inter.moving, (x0, y0), name="moving", class_id=MOVING_CLASS,
                         opacity=0.5, image=parts.to_uint8(np.log10(np.maximum(inter.cond, 1.0)), 0.0, 3.0),
                         image_name="log10_cond")

    parts.histogram_steps(rec, f"{root}/histogram", inter.hist_edges, (inter.hist_u, inter.hist_v), labels=["u", "v"],
                          colors=[(255, 120, 60), (60, 160, 255)], x_scale=HIST_X_SCALE)
    raw_x, filtered_x, names_x, raw_y, filtered_y, names_y, moving = _series_names(root)
    parts.scalars(rec, (raw_x, filtered_x, raw_y, filtered_y, moving),
                  [inter.raw_velocity[0], inter.filtered_velocity[0], inter.raw_velocity[1], inter.filtered_velocity[1],
                   float(inter.moving_pixels)])
    for k, names in ((0, names_x), (1, names_y)):
        parts.kalman_series(rec, f"{root}/kalman", inter.kalman_x[k], inter.kalman_P[k], names)


_ARROW_COLOURS = np.array([[80, 200, 255], [255, 60, 60]], dtype=np.uint8)  # still, moving


def _arrows(xs, ys, us, vs, moving, keep, x0, y0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Origins (image px), vectors and colours of the kept arrows: one frame's (2-D inputs) or many
    frames' stacked on a first axis (``x0``, ``y0`` then arrays broadcast against it), the same
    elementwise operations either way, frames in order."""
    origins = np.stack([(xs + x0)[keep], (ys + y0)[keep]], axis=1).astype(np.float32)
    vectors = ARROW_SCALE * np.stack([us[keep], vs[keep]], axis=1).astype(np.float32)
    colours = _ARROW_COLOURS[moving[keep].view(np.uint8)]
    return origins, vectors, colours


class _Arrows:
    """One frame's flow arrows as a deferred field (``parts.Ellipses``' pattern): the FrameLogger
    concatenates a path's frames at the flush and ``build_all`` computes the field for all of them
    with :func:`_arrows` on the stacked windows (~20 µs a frame less; the same arrays)."""

    __slots__ = ("xs", "ys", "us", "vs", "moving", "keep", "x0", "y0", "n", "name")

    def __init__(self, xs, ys, us, vs, moving, keep, x0, y0, n, name=None) -> None:
        self.xs, self.ys, self.us, self.vs, self.moving, self.keep = xs, ys, us, vs, moving, keep
        self.x0, self.y0, self.n, self.name = x0, y0, n, name

    def field(self, name: str) -> _Arrows:
        return _Arrows(self.xs, self.ys, self.us, self.vs, self.moving, self.keep, self.x0, self.y0, self.n, name)

    def __len__(self) -> int:
        return self.n

    @property
    def nbytes(self) -> int:
        """What the field's own array holds (the logger's flush threshold counts it, as before)."""
        return self.n * (3 if self.name == "colors" else 8)

    @staticmethod
    def build_all(frames: list[_Arrows]) -> np.ndarray:
        k = ("origins", "vectors", "colors").index(frames[0].name)
        first = frames[0]
        if any(f.xs is not first.xs for f in frames):  # the window changed size: frame by frame
            return np.concatenate([_arrows(f.xs, f.ys, f.us, f.vs, f.moving, f.keep, f.x0, f.y0)[k] for f in frames])
        x0 = np.array([f.x0 for f in frames])[:, None, None]
        y0 = np.array([f.y0 for f in frames])[:, None, None]
        stack = np.stack
        return _arrows(first.xs, first.ys, stack([f.us for f in frames]), stack([f.vs for f in frames]),
                       stack([f.moving for f in frames]), stack([f.keep for f in frames]), x0, y0)[k]


@functools.lru_cache(maxsize=8)
def _arrow_grid(shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """Rows and columns of the arrows' pixels (every ARROW_STRIDE-th), made once per window size."""
    ys, xs = np.mgrid[0 : shape[0] : ARROW_STRIDE, 0 : shape[1] : ARROW_STRIDE]
    ys.setflags(write=False)
    xs.setflags(write=False)
    return ys, xs


@functools.lru_cache(maxsize=8)
def _series_names(root: str) -> tuple:
    """raw_x, filtered_x, the x filter's state names, the same for y, then moving_pixels' path."""
    per_axis = tuple(x for axis in ("x", "y") for x in (
        f"{root}/velocity/raw_{axis}", f"{root}/velocity/filtered_{axis}",
        tuple(f"{axis}/{part}" for part in ("position", "velocity", "acceleration"))))
    return per_axis + (f"{root}/moving_pixels",)
