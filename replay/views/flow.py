"""Rerun view of the gradient-flow tracker (seed 004): every intermediate of a step."""

from __future__ import annotations

import functools
import itertools
from collections.abc import Sequence

import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from trackreplay.trackers.base import TrackState
from trackreplay.trackers.frame import Frame

from trackreplay.replay.views.rerun_sink import FrameLogger
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
    if isinstance(rec, FrameLogger) and rec.has_static(f"{root}/window"):
        # After the first frame (whose static annotation context flushes its rows on their own): the
        # intermediates are kept as they are (the tracker's own arrays, never written again) and
        # become rows many frames at a time (_log_frames)
        parts.tracks(rec, states)
        rec.batch(_frames_logger(root), inter, sum(getattr(inter, k).nbytes for k in _HELD))
        return
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
    if np.any(keep):
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


_HELD = ("flow_u", "flow_v", "valid", "cond", "moving")  # a kept frame's arrays, bar a few small ones


@functools.lru_cache(maxsize=8)
def _frames_logger(root: str) -> functools.partial:
    """The batch builder of the view at ``root`` (one object per root: the logger keys batches by it)."""
    return functools.partial(_log_frames, root)


def _log_frames(root: str, rec: FrameLogger, records: list[tuple[int, int, object]]) -> None:
    """What :func:`log` logs frame by frame, for many frames at once: stacked arrays through the same
    elementwise operations, so the same rows (``tests/replay/views/test_rrd_columns.py`` compares them).
    Runs of frames with one window and histogram size go together."""
    for _, run in itertools.groupby(records, key=lambda r: (r[2].flow_u.shape, r[2].hist_edges.shape)):
        run = list(run)
        frames, times, inters = [r[0] for r in run], [r[1] for r in run], [r[2] for r in run]
        boxes = np.array([i.fov_box for i in inters], dtype=np.float64)
        half = (boxes[:, 2:4] / 2.0).astype(np.float32)
        ones = [1] * len(run)
        rec.columns(f"{root}/fov", rr.Boxes2D, frames, times, ones, half_sizes=half,
                    centers=boxes[:, :2].astype(np.float32) + half, colors=[(255, 255, 255)] * len(run))
        _points(rec, f"{root}/centroid", frames, times, np.array([i.centroid for i in inters], dtype=np.float64))
        x = np.array([i.kalman_x for i in inters], dtype=np.float64)
        P = np.array([i.kalman_P for i in inters], dtype=np.float64)
        _ellipses(rec, f"{root}/kalman/position", frames, times, x, P)
        _arrow_rows(rec, f"{root}/flow_field", frames, times, inters, boxes)
        translation = np.zeros((len(run), 3), dtype=np.float32)
        translation[:, :2] = boxes[:, :2]
        rec.columns(f"{root}/window", rr.Transform3D, frames, times, ones, translation=translation)
        cond = np.stack([i.cond for i in inters])
        rec.image_rows(f"{root}/window/log10_cond", rr.Image, frames, times,
                       parts.to_uint8(np.log10(np.maximum(cond, 1.0)), 0.0, 3.0), color_model="L")
        rec.image_rows(f"{root}/window/moving", rr.SegmentationImage, frames, times,
                       np.stack([i.moving for i in inters]).view(np.uint8) * np.uint8(MOVING_CLASS), opacity=0.5)
        _histograms(rec, f"{root}/histogram", frames, times, inters)
        _scalar_rows(rec, root, frames, times, inters, x, P)


def _points(rec: FrameLogger, path: str, frames: list[int], times: list[int], centroids: np.ndarray) -> None:
    """The centroid where it is finite, a Clear elsewhere."""
    ok = np.isfinite(centroids).all(axis=1)
    _clear_rows(rec, path, frames, times, ~ok)
    shown, at = _where(frames, times, ok)
    rec.columns(path, rr.Points2D, shown, at, [1] * len(shown), positions=centroids[ok].astype(np.float32),
                radii=[1.5] * len(shown), colors=[(255, 0, 255)] * len(shown))


def _ellipses(rec: FrameLogger, path: str, frames: list[int], times: list[int], x: np.ndarray, P: np.ndarray) -> None:
    """The position's 2-sigma ellipse (the filters are per axis: a diagonal covariance) where finite."""
    means = x[:, :, 0]
    covs = np.zeros((len(frames), 2, 2))
    covs[:, 0, 0], covs[:, 1, 1] = P[:, 0, 0, 0], P[:, 1, 0, 0]
    ok = np.isfinite(means).all(axis=1) & np.isfinite(covs).all(axis=(1, 2))
    _clear_rows(rec, path, frames, times, ~ok)
    shown, at = _where(frames, times, ok)
    strips = parts.Ellipses.build_all([parts.Ellipses(means[ok], covs[ok], 2.0)])
    rec.columns(path, rr.LineStrips2D, shown, at, [1] * len(shown), strips=strips, colors=[(255, 255, 0)] * len(shown))


def _arrow_rows(rec: FrameLogger, path: str, frames: list[int], times: list[int], inters: list,
                boxes: np.ndarray) -> None:
    """The flow arrows of each frame with any, a Clear on the others."""
    s = ARROW_STRIDE
    us = np.stack([i.flow_u[::s, ::s] for i in inters])
    vs = np.stack([i.flow_v[::s, ::s] for i in inters])
    keep = np.isfinite(us) & np.isfinite(vs)
    counts = np.count_nonzero(keep, axis=(1, 2))
    ok = counts > 0
    _clear_rows(rec, path, frames, times, ~ok)
    if not ok.any():
        return
    ys, xs = _arrow_grid(inters[0].flow_u.shape)
    moving = np.stack([i.moving[::s, ::s] for i in inters])
    origins, vectors, colours = _arrows(xs, ys, us[ok], vs[ok], moving[ok], keep[ok], boxes[ok, 0, None, None],
                                        boxes[ok, 1, None, None])
    rec.columns(path, rr.Arrows2D, *_where(frames, times, ok), counts[ok].tolist(), origins=origins, vectors=vectors,
                colors=colours)


def _histograms(rec: FrameLogger, path: str, frames: list[int], times: list[int], inters: list) -> None:
    """``parts.histogram_steps`` of u and v, each frame's two strips."""
    x = np.repeat(np.array([i.hist_edges for i in inters], dtype=np.float64), 2, axis=1)[:, 1:-1] * HIST_X_SCALE
    strips = np.empty((len(frames), 2, x.shape[1], 2), dtype=np.float32)
    strips[:, :, :, 0] = x[:, None, :]
    for k, name in enumerate(("hist_u", "hist_v")):
        strips[:, k, :, 1] = -np.repeat(np.array([getattr(i, name) for i in inters]), 2, axis=1).astype(np.float64)
    rec.columns(path, rr.LineStrips2D, frames, times, [2] * len(frames), strips=strips.reshape(-1, x.shape[1], 2),
                colors=[(255, 120, 60), (60, 160, 255)] * len(frames), labels=["u", "v"] * len(frames))


def _scalar_rows(rec: FrameLogger, root: str, frames: list[int], times: list[int], inters: list, x: np.ndarray,
                 P: np.ndarray) -> None:
    """The velocities, moving pixels and both filters' states ``x`` and sigmas (``parts.kalman_series``)."""
    raw_x, filtered_x, names_x, raw_y, filtered_y, names_y, moving = _series_names(root)
    raw = np.array([i.raw_velocity for i in inters], dtype=np.float64)
    filtered = np.array([i.filtered_velocity for i in inters], dtype=np.float64)
    pixels = np.array([i.moving_pixels for i in inters], dtype=np.float64)
    rec.scalar_rows((raw_x, filtered_x, raw_y, filtered_y, moving), frames, times,
                    np.stack([raw[:, 0], filtered[:, 0], raw[:, 1], filtered[:, 1], pixels], axis=1))
    for k, names in ((0, names_x), (1, names_y)):
        sigma = np.sqrt(np.maximum(np.diagonal(P[:, k], axis1=1, axis2=2), 0.0))
        rec.scalar_rows(parts.series_columns(f"{root}/kalman", names), frames, times,
                        np.concatenate([x[:, k], sigma], axis=1))


def _clear_rows(rec: FrameLogger, path: str, frames: list[int], times: list[int], where: np.ndarray) -> None:
    if where.any():
        rec.entity_rows(path, rr.Clear(recursive=False), *_where(frames, times, where))


def _where(frames: list[int], times: list[int], mask: np.ndarray) -> tuple[list[int], list[int]]:
    """The frames and times where ``mask`` holds."""
    keep = mask.tolist()
    return [f for f, k in zip(frames, keep) if k], [t for t, k in zip(times, keep) if k]
