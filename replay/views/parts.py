"""Small drawing pieces that every tracker view is composed of.

Each function takes the view's logger (a :class:`FrameLogger`, or a bare ``rr.RecordingStream``),
an entity path and plain numpy data, and logs one thing. Entity paths follow the stages:
``trackers/<tracker>/<stage>/…`` for intermediates and ``tracks/{id}`` for the estimates.

Determinism: values are converted to fixed dtypes here (float32 positions, uint8 colours), ids
are visited in sorted order, and nothing depends on set or dict iteration of strings. Something
that has nothing to show this frame is cleared rather than left standing from an earlier frame.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping, Sequence

import numpy as np
import rerun as rr

from trackreplay.replay.views.rerun_sink import FrameLogger
from trackreplay.trackers.base import TrackState

Logger = FrameLogger | rr.RecordingStream
Colour = tuple[int, int, int] | tuple[int, int, int, int]

STATUS_COLOURS: dict[str, Colour] = {
    "measured": (0, 220, 0), "predicted": (255, 170, 0), "interpolated": (0, 160, 255), "lost": (255, 0, 0),
}
ACCEPTED: Colour = (40, 230, 40)
REJECTED: Colour = (235, 50, 50)
TRACKS = "tracks"


# --- plumbing ---------------------------------------------------------------------------------


def clear(logger: Logger, path: str, *, recursive: bool = False) -> None:
    """Hide what ``path`` showed (from this frame on)."""
    logger.log(path, rr.Clear(recursive=recursive))


def clear_track(logger: Logger, path: str) -> None:
    """A track ended: clear ``path`` (e.g. ``tracks/7``) and everything under it."""
    logger.log(path, rr.Clear(recursive=True))


def static_once(logger: Logger, path: str, entity: rr.AsComponents) -> None:
    """Log ``entity`` statically, the first time only when ``logger`` is a :class:`FrameLogger`."""
    if isinstance(logger, FrameLogger):
        logger.static_once(path, entity)
    else:
        logger.log(path, entity, static=True)


def annotation_context(logger: Logger, path: str, classes: Sequence[tuple[int, str, Colour]]) -> None:
    """Class ids -> names and colours for segmentation images under ``path``; logged once, statically."""
    if isinstance(logger, FrameLogger) and logger.has_static(path):
        return  # building the context costs ~0.4 ms: not again for every frame
    static_once(logger, path, rr.AnnotationContext([(int(i), label, colour) for i, label, colour in classes]))


def scalars(logger: Logger, paths: tuple[str, ...], values: np.ndarray) -> None:
    """One point on each of ``paths`` (``values[k]`` on ``paths[k]``); non-finite values skipped, as
    :func:`scalar` skips them. Through a :class:`FrameLogger` it is one row a frame, split at the end."""
    values = np.asarray(values, dtype=np.float64).reshape(-1)
    if len(paths) != len(values):
        raise ValueError(f"scalars: {len(paths)} paths for {len(values)} values")
    if isinstance(logger, FrameLogger):
        logger.scalars(paths, values)
    else:
        for path, value in zip(paths, values.tolist()):
            scalar(logger, path, value)


def scalar(logger: Logger, path: str, value: float) -> None:
    """One time-series point; a non-finite value (nothing this frame) is skipped, not drawn."""
    value = float(value)
    if not math.isfinite(value):
        return
    if isinstance(logger, FrameLogger):
        logger.scalar(path, value)
    else:
        logger.log(path, rr.Scalars(value))


def to_uint8(values: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """Map ``[lo, hi]`` linearly to 0..255 (NaN -> 0), e.g. a raster of scores shown as grey."""
    # In float64 (a float32 input is widened exactly). NaN -> 0 by fmax (which drops a NaN operand):
    # as NaN -> lo before the scaling did; ±inf clip to the ends.
    scaled = np.subtract(values, lo, dtype=np.float64)
    scaled /= hi - lo
    np.fmax(scaled, 0.0, out=scaled)
    np.minimum(scaled, 1.0, out=scaled)
    scaled *= 255.0
    return np.round(scaled, out=scaled).astype(np.uint8)


def draw(logger: Logger, path: str, archetype: type, **fields) -> None:
    """``archetype(**fields)`` at ``path``. Through a :class:`FrameLogger` it is deferred and built
    once for many frames (``FrameLogger.defer``: a fraction of the cost of one archetype per frame);
    a bare stream gets it now. Fields are batches (first axis = instances); a scalar is one
    instance; None fields are left out. Names are those of ``archetype.columns`` (``half_sizes``,
    ``positions``, ``strips``), which its constructor takes too.
    """
    fields = {k: (v if type(v) in _BATCH_TYPES else [v] if np.isscalar(v) else v) for k, v in fields.items() if v is not None}
    if isinstance(logger, FrameLogger):
        logger.defer(path, archetype, **fields)
    else:
        logger.log(path, archetype(**fields))


_BATCH_TYPES = (list, tuple, np.ndarray)  # never scalars: skip np.isscalar's checks


def notice(logger: Logger, path: str, text: str | None) -> None:
    """A tracker's notice as a WARN line of the text log at ``path``; nothing when ``text`` is empty."""
    if text:
        draw(logger, path, rr.TextLog, text=[text], level=[rr.TextLogLevel.WARN])


def _points(xy: np.ndarray, dim: int) -> np.ndarray:
    return np.asarray(xy, dtype=np.float32).reshape(-1, dim)


# --- particles, boxes, blobs ------------------------------------------------------------------


def weight_style(weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Colour (blue -> yellow) and radius (0.8 .. 3.0 px) by weight relative to the largest."""
    w = np.asarray(weights, dtype=np.float64)
    rel = w / w.max() if w.size and w.max() > 0 else np.zeros_like(w)
    colours = np.stack([60 + 195 * rel, 80 + 175 * rel, 255 - 215 * rel], axis=1).astype(np.uint8)
    return colours, (0.8 + 2.2 * rel).astype(np.float32)


def particles(logger: Logger, path: str, xy: np.ndarray, weights: np.ndarray | None = None) -> None:
    """Particle positions (first two state components), coloured and sized by weight."""
    xy = np.asarray(xy)
    if xy.size == 0:
        clear(logger, path)
        return
    xy = _points(xy[:, :2], 2)
    if weights is None:
        draw(logger, path, rr.Points2D, positions=xy, radii=1.0, colors=[(80, 200, 255)])
        return
    colours, radii = weight_style(weights)
    draw(logger, path, rr.Points2D, positions=xy, colors=colours, radii=radii)


def boxes(logger: Logger, path: str, centers: np.ndarray, sizes: np.ndarray, *,
          labels: Sequence[str] | None = None, colors: Sequence[Colour] | np.ndarray | None = None,
          class_ids: np.ndarray | None = None) -> None:
    """Axis-aligned boxes given by centre and full size (image px); none -> cleared."""
    centers, sizes = _points(centers, 2), _points(sizes, 2)
    if len(centers) == 0:
        clear(logger, path)
        return
    draw(logger, path, rr.Boxes2D, half_sizes=sizes / 2.0, centers=centers, labels=labels, colors=colors,
         class_ids=class_ids)


def box_xywh(logger: Logger, path: str, box: Sequence[float], *, label: str | None = None,
             color: Colour = (255, 255, 255)) -> None:
    """One box given as ``(x0, y0, w, h)`` (a search region, a field of view)."""
    x0, y0, w, h = (float(v) for v in box)
    half = np.array([[w / 2.0, h / 2.0]], dtype=np.float32)
    draw(logger, path, rr.Boxes2D, half_sizes=half, centers=np.array([[x0, y0]], dtype=np.float32) + half,
         colors=[color], labels=None if label is None else [label])


def field_labels(fields: Mapping[str, np.ndarray], formats: Mapping[str, str] | None = None) -> list[str]:
    """One label per row, the named fields joined by "/" (``{"area": a, "circularity": c}`` -> "12/0.80").

    ``formats`` maps a field name to a format spec such as ``"{:.0f}"``; the default is ``"{:.3g}"``
    for numbers and ``"{}"`` otherwise.
    """
    formats = formats or {}
    columns = []
    for name in fields:  # the caller's order: a Mapping literal keeps it
        values = np.asarray(fields[name])
        spec = formats.get(name, "{:.3g}" if np.issubdtype(values.dtype, np.number) else "{}")
        columns.append([spec.format(v) for v in values.tolist()])
    return ["/".join(parts) for parts in zip(*columns)]


def blobs(logger: Logger, path: str, centers: np.ndarray, sizes: np.ndarray, accepted: np.ndarray, *,
          fields: Mapping[str, np.ndarray] | None = None, formats: Mapping[str, str] | None = None,
          selected: int | None = None, points_path: str | None = None,
          offset: Sequence[float] = (0.0, 0.0)) -> None:
    """Detected blobs as boxes at ``path``: green accepted, red rejected, labelled by their named
    ``fields``; the ``selected`` one drawn larger. With ``points_path`` their centres are also
    logged there, shifted by ``-offset`` (e.g. into a crop placed by :func:`mask_over_crop`).
    """
    centers, sizes = _points(centers, 2), _points(sizes, 2)
    if len(centers) == 0:
        clear(logger, path)
        if points_path is not None:
            clear(logger, points_path)
        return
    accepted = np.asarray(accepted, dtype=bool).reshape(-1)
    colours = np.where(accepted[:, None], [ACCEPTED], [REJECTED]).astype(np.uint8)
    grow = np.full(len(centers), 2.0, dtype=np.float32)
    if selected is not None and 0 <= selected < len(centers):
        grow[selected] = 6.0
    labels = field_labels(fields, formats) if fields else None
    draw(logger, path, rr.Boxes2D, half_sizes=(np.maximum(sizes, 2.0) + grow[:, None]) / 2.0, centers=centers,
         colors=colours, labels=labels)
    if points_path is not None:
        local = centers - np.asarray(offset, dtype=np.float32)[None, :]
        draw(logger, points_path, rr.Points2D, positions=local, radii=1.5, colors=colours)


# --- rasters over a crop ----------------------------------------------------------------------


def place_crop(logger: Logger, path: str, offset: Sequence[float]) -> None:
    """Put ``path``'s children at ``offset`` (x, y) of the camera image, so rasters of a crop overlay it."""
    ox, oy = (float(v) for v in offset)
    draw(logger, path, rr.Transform3D, translation=np.array([[ox, oy, 0.0]], dtype=np.float32))


def mask_over_crop(logger: Logger, path: str, mask: np.ndarray, offset: Sequence[float], *, name: str = "mask",
                   class_id: int = 1, opacity: float = 0.6, image: np.ndarray | None = None,
                   image_name: str = "image") -> None:
    """A crop's mask (bool or class ids) as a segmentation image at ``path/name``, placed at the
    crop's ``offset`` in the camera image; optionally the crop's own pixels (BGR, grey or uint8
    scores) at ``path/image_name`` under it. Class colours come from :func:`annotation_context`.
    """
    place_crop(logger, path, offset)
    mask = np.asarray(mask)
    classes = mask.astype(np.uint8) * np.uint8(class_id) if mask.dtype == bool else mask.astype(np.uint8)
    if image is not None:
        image = np.asarray(image)
        _image(logger, f"{path}/{image_name}", rr.Image, image, color_model="L" if image.ndim == 2 else "BGR")
    _image(logger, f"{path}/{name}", rr.SegmentationImage, classes, opacity=opacity)


def _image(logger: Logger, path: str, archetype: type, pixels: np.ndarray, **params) -> None:
    if isinstance(logger, FrameLogger):
        logger.image(path, archetype, pixels, **params)  # built once per shape, then only the pixels
    else:
        logger.log(path, archetype(pixels, **params))


# --- Gaussians --------------------------------------------------------------------------------


def _axes(cov: np.ndarray, n_sigma: float) -> np.ndarray:
    """Principal semi-axes as columns, ``n_sigma`` standard deviations long."""
    values, vectors = np.linalg.eigh(0.5 * (cov + cov.T))
    return vectors * (n_sigma * np.sqrt(np.maximum(values, 0.0)))[None, :]


def ellipse_polyline(mean: np.ndarray, cov: np.ndarray, *, n_sigma: float = 2.0, segments: int = 48) -> np.ndarray:
    """Closed ``(segments + 1, 2)`` polyline of the ``n_sigma`` contour of a 2-D Gaussian."""
    unit = _unit_circle(segments)
    return (np.asarray(mean, dtype=np.float64)[:2, None] + _axes(np.asarray(cov, dtype=np.float64), n_sigma) @ unit).T


@functools.lru_cache(maxsize=8)
def _unit_circle(segments: int) -> np.ndarray:
    """(2, segments + 1) cos and sin of ``segments`` equal steps round the circle, made once."""
    angles = np.linspace(0.0, 2.0 * np.pi, segments + 1)
    unit = np.stack([np.cos(angles), np.sin(angles)], axis=0)
    unit.setflags(write=False)
    return unit


def ellipsoid_polylines(mean: np.ndarray, cov: np.ndarray, *, n_sigma: float = 2.0,
                        segments: int = 48) -> list[np.ndarray]:
    """The three principal sections of the ``n_sigma`` ellipsoid of a 3-D Gaussian (closed polylines)."""
    axes = _axes(np.asarray(cov, dtype=np.float64), n_sigma)
    angles = np.linspace(0.0, 2.0 * np.pi, segments + 1)
    c, s = np.cos(angles), np.sin(angles)
    centre = np.asarray(mean, dtype=np.float64)[:3, None]
    return [(centre + axes[:, [i]] * c + axes[:, [j]] * s).T for i, j in ((0, 1), (1, 2), (2, 0))]


def _finite(means: np.ndarray, covs: np.ndarray, dim: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    means = np.asarray(means, dtype=np.float64).reshape(-1, dim)
    covs = np.asarray(covs, dtype=np.float64).reshape(-1, dim, dim)
    keep = np.isfinite(means).all(axis=1) & np.isfinite(covs).all(axis=(1, 2))
    return means, covs, keep


def covariance_ellipses(logger: Logger, path: str, means: np.ndarray, covs: np.ndarray, *, n_sigma: float = 2.0,
                        colors: Sequence[Colour] | None = None, labels: Sequence[str] | None = None) -> None:
    """2-D Gaussians (one mean and 2x2 covariance per row) as ``n_sigma`` ellipses (polylines:
    ``Ellipses2D`` is axis-aligned only). Rows with non-finite values are left out.
    """
    means, covs, keep = _finite(means, covs, 2)
    if not keep.any():
        clear(logger, path)
        return
    if isinstance(logger, FrameLogger):  # built at the flush, for all frames in one go
        strips = Ellipses(means[keep], covs[keep], float(n_sigma))
    else:  # one (n, segments + 1, 2) array: Rerun converts it in one piece (a list, strip by strip)
        strips = np.stack([ellipse_polyline(m, c, n_sigma=n_sigma) for m, c in zip(means[keep], covs[keep])]).astype(np.float32)
    draw(logger, path, rr.LineStrips2D, strips=strips, colors=_pick(colors, keep), labels=_pick(labels, keep))


class Ellipses:
    """The ``n_sigma`` ellipses of some 2-D Gaussians as a deferred ``strips`` field: the
    :class:`FrameLogger` concatenates a path's frames at the flush and ``build_all`` draws them with
    one stacked ``eigh`` and one stacked matmul, which run the per-matrix LAPACK/BLAS calls of
    :func:`ellipse_polyline` (the same float32 strips; ``test_rrd_columns`` compares them with
    row-by-row logging). Per frame that leaves ~5 µs of the ~50 µs an ellipse cost."""

    __slots__ = ("means", "covs", "n_sigma")

    def __init__(self, means: np.ndarray, covs: np.ndarray, n_sigma: float) -> None:
        self.means, self.covs, self.n_sigma = means, covs, n_sigma

    def __len__(self) -> int:
        return len(self.means)

    @staticmethod
    def build_all(batches: list[Ellipses]) -> np.ndarray:
        means = np.concatenate([b.means for b in batches])
        covs = np.concatenate([b.covs for b in batches])
        sigmas = np.concatenate([np.full(len(b), b.n_sigma) for b in batches])
        values, vectors = np.linalg.eigh(0.5 * (covs + covs.transpose(0, 2, 1)))
        axes = vectors * (sigmas[:, None] * np.sqrt(np.maximum(values, 0.0)))[:, None, :]
        points = means[:, :2, None] + axes @ _unit_circle(48)
        return points.transpose(0, 2, 1).astype(np.float32)


def covariance_ellipsoids(logger: Logger, path: str, means: np.ndarray, covs: np.ndarray, *, n_sigma: float = 2.0,
                          colors: Sequence[Colour] | None = None) -> None:
    """3-D Gaussians (a mean and 3x3 covariance per row) as wire ellipsoids: three principal sections each."""
    means, covs, keep = _finite(means, covs, 3)
    if not keep.any():
        clear(logger, path)
        return
    strips, colours = [], []
    picked = _pick(colors, keep)
    for k, (m, c) in enumerate(zip(means[keep], covs[keep])):
        strips += [p.astype(np.float32) for p in ellipsoid_polylines(m, c, n_sigma=n_sigma)]
        if picked is not None:
            colours += [picked[k]] * 3
    draw(logger, path, rr.LineStrips3D, strips=strips, colors=colours or None)


def _pick(values: Sequence | None, keep: np.ndarray) -> list | None:
    if values is None:
        return None
    values = list(values)
    if len(values) == 1:
        return values * int(keep.sum())
    return [v for v, k in zip(values, keep) if k]


# --- time series ------------------------------------------------------------------------------


def kalman_series(logger: Logger, path: str, x: np.ndarray, P: np.ndarray, names: Sequence[str]) -> None:
    """A Kalman filter's state ``x`` and standard deviations ``sqrt(diag P)`` as one series per
    component: ``path/state/<name>`` and ``path/sigma/<name>``.
    """
    x = np.asarray(x, dtype=np.float64).reshape(-1)
    P = np.asarray(P, dtype=np.float64)
    if len(names) != len(x) or P.shape != (len(x), len(x)):
        raise ValueError(f"kalman_series: {len(names)} names for a state of {len(x)} and P of shape {P.shape}")
    sigma = np.sqrt(np.maximum(np.diag(P), 0.0))
    if isinstance(logger, FrameLogger):  # one row a frame (the series are split at the end)
        logger.scalars(series_columns(path, tuple(names)), np.concatenate([x, sigma]))
        return
    paths = _series_paths(path, tuple(names))
    for (state_path, sigma_path), value, s in zip(paths, x.tolist(), sigma.tolist()):
        scalar(logger, state_path, value)
        scalar(logger, sigma_path, s)


@functools.lru_cache(maxsize=256)
def _series_paths(path: str, names: tuple[str, ...]) -> tuple[tuple[str, str], ...]:
    return tuple((f"{path}/state/{name}", f"{path}/sigma/{name}") for name in names)


@functools.lru_cache(maxsize=256)
def series_columns(path: str, names: tuple[str, ...]) -> tuple[str, ...]:
    """The state paths then the sigma paths (the order of ``concatenate([x, sigma])``)."""
    pairs = _series_paths(path, names)
    return tuple(p for p, _ in pairs) + tuple(q for _, q in pairs)


# --- histograms -------------------------------------------------------------------------------


def histogram_steps(logger: Logger, path: str, edges: np.ndarray, counts: Sequence[np.ndarray], *,
                    labels: Sequence[str] | None = None, colors: Sequence[Colour] | None = None,
                    x_scale: float = 1.0) -> None:
    """1-D histograms sharing ``edges`` as step curves in a 2-D view (x right, counts up), one
    Rerun call for all of them (a ``BarChart`` costs ~0.35 ms each).
    """
    x = np.repeat(np.asarray(edges, dtype=np.float64), 2)[1:-1] * x_scale
    strips = np.empty((len(counts), len(x), 2), dtype=np.float32)  # one array: converted in one piece
    strips[:, :, 0] = x
    for k, h in enumerate(counts):
        strips[k, :, 1] = -np.repeat(np.asarray(h), 2).astype(np.float64)
    draw(logger, path, rr.LineStrips2D, strips=Stacked(strips) if isinstance(logger, FrameLogger) else strips,
         colors=colors, labels=labels)


class Stacked:
    """A batch of same-length strips ``(n, k, dim)`` kept for the flush, where a path's frames are
    concatenated into one array (``build_all``). It counts toward the logger's flush threshold as the
    list of strips it replaces did (no ``nbytes``), so chunk boundaries stay where they were."""

    __slots__ = ("array",)

    def __init__(self, array: np.ndarray) -> None:
        self.array = array

    def __len__(self) -> int:
        return len(self.array)

    @staticmethod
    def build_all(batches: list[Stacked]) -> np.ndarray:
        if len({b.array.shape[1:] for b in batches}) > 1:
            return [strip for b in batches for strip in b.array]  # lengths differ: strip by strip
        return np.concatenate([b.array for b in batches])


def histogram_bars(logger: Logger, path: str, counts: np.ndarray, *, edges: np.ndarray | None = None) -> None:
    """One 1-D histogram as a bar chart (bins at their centres when ``edges`` are given)."""
    counts = np.asarray(counts, dtype=np.float64).reshape(-1)
    if edges is None:
        logger.log(path, rr.BarChart(counts))
    else:
        e = np.asarray(edges, dtype=np.float64)
        logger.log(path, rr.BarChart(counts, abscissa=0.5 * (e[:-1] + e[1:])))


def histogram_2d(logger: Logger, path: str, hist: np.ndarray) -> None:
    """A 2-D histogram as a grey image, scaled to its largest bin (rows = first axis)."""
    hist = np.asarray(hist, dtype=np.float64)
    top = float(hist.max()) if hist.size else 0.0
    logger.log(path, rr.Image(to_uint8(hist, 0.0, top if top > 0 else 1.0), color_model="L"))


# --- tracks -----------------------------------------------------------------------------------


def tracks(logger: Logger, states: Sequence[TrackState], *, root: str = TRACKS) -> None:
    """Each track's box at ``root/{id}``, coloured by status and labelled "id status".

    A ``lost`` state clears its track. Through a :class:`FrameLogger`, a track that was drawn
    before and has no state this frame is cleared too (the logger remembers the ids it drew).
    """
    drawn: set[int] = set()
    for s in sorted(states, key=lambda s: s.track_id):
        path = f"{root}/{s.track_id}"
        if s.x is None or s.y is None:
            clear_track(logger, path)
            continue
        size = [s.w or 2.0, s.h or 2.0]
        draw(logger, path, rr.Boxes2D, half_sizes=np.array([size], dtype=np.float32) / 2.0,
             centers=np.array([[s.x, s.y]], dtype=np.float32), colors=[STATUS_COLOURS[s.status]],
             labels=[f"{s.track_id} {s.status}"])
        drawn.add(s.track_id)
    if isinstance(logger, FrameLogger):
        for ended in sorted(logger.live_tracks - drawn - {s.track_id for s in states}):
            clear_track(logger, f"{root}/{ended}")
        logger.live_tracks = drawn
