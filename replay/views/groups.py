"""Rerun view of the group tracker (seed 003), under ``trackers/<name>/…``:

- the right view is the sink's ``camera/right`` (the left ``camera/image``);
- ``foreground/left``, ``foreground/right``: the background-subtraction masks;
- ``disparity``: the subtraction-stereo disparity (grey, 0 = none), ``crops``: the SGBM crops;
- ``klt/features``: every KLT feature; ``klt/tracks``: the observation points' window tracks,
  coloured by their group (grey unassigned);
- ``world/points``: the observation points in 3-D (left camera frame), coloured by group;
  ``world/groups``: each group's 2σ extent ellipsoid Σ, ``world/ekf``: its 2σ EKF position ellipsoid;
- ``events``: births, merges, deletions. Tracks are ``tracks/{id}`` (cleared when a group ends).

Masks and disparity are sent as lossless PNG (``EncodedImage``; a mask as a magenta RGBA overlay,
transparent off the foreground, at the segmentation image's opacity): raw they are 4 bytes a pixel
a stereo frame of the viewer's memory (178 of the 485 MB a 4 s ``synth groups-crossing`` replay
holds; 4.4 MB as PNG). The .rrd file compresses its chunks too, so on disk they were never the bulk:
that was the right image, logged here as well as by the sink (186 MB of 490 MB), now only by the
sink. ``replay --rrd-full`` (``ReplayRequest.rrd_full``, which sets ``FULL`` on the logger) sends
masks and disparity raw, as segmentation and grey images.
"""

from __future__ import annotations

from collections.abc import Sequence

import cv2
import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from trackreplay.replay.views.rerun_sink import RIGHT, FrameLogger
from trackreplay.replay.views import parts
from trackreplay.trackers.base import TrackState
from trackreplay.trackers.frame import Frame

POS = [0, 2, 4]
FULL = "rrd_full"  # the logger attribute that asks for raw masks and disparity
FOREGROUND = (255, 60, 200)  # RGB
MASK_OPACITY = 0.35
_PNG = [cv2.IMWRITE_PNG_COMPRESSION, 1]  # fast; a mostly empty raster compresses well at any level


def colour_of(gid: int) -> tuple[int, int, int]:
    if gid < 0:
        return (150, 150, 150)
    h = (gid * 0.61803398875) % 1.0
    rgb = np.clip(np.abs((h * 6.0 + np.array([0.0, 4.0, 2.0])) % 6.0 - 3.0) - 1.0, 0.0, 1.0)
    return tuple(int(v) for v in np.round(60 + 195 * rgb))


def blueprint(name: str) -> rrb.Blueprint:
    root = f"trackers/{name}"
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Vertical(
                rrb.Spatial2DView(name="left + groups", origin="/",
                                  contents=["camera/**", f"- {RIGHT}", "tracks/**", f"{root}/foreground/left",
                                            f"{root}/klt/**", f"{root}/crops"]),
                rrb.Spatial2DView(name="right", origin=RIGHT, contents=[RIGHT, f"{root}/foreground/right"]),
            ),
            rrb.Vertical(
                rrb.Spatial2DView(name="disparity", origin=f"{root}/disparity"),
                rrb.Spatial3DView(name="3-D points and groups (camera frame)", origin=f"{root}/world"),
                rrb.TextLogView(name="events", origin=f"{root}/events"),
            ),
        ),
        collapse_panels=False,
    )


def log(rec: FrameLogger, name: str, frame: Frame, inter, states: Sequence[TrackState]) -> None:
    root = f"trackers/{name}"
    parts.tracks(rec, states)
    if inter is not None and inter.notice:
        rec.log(f"{root}/events", rr.TextLog(inter.notice, level=rr.TextLogLevel.WARN))
    if inter is None or inter.mode != "tracking":
        for stage in ("foreground", "disparity", "crops", "klt", "world"):
            parts.clear(rec, f"{root}/{stage}", recursive=True)
        return
    _rasters(rec, root, inter)
    c = np.asarray(inter.crops, dtype=np.float64).reshape(-1, 4)
    parts.boxes(rec, f"{root}/crops", (c[:, :2] + c[:, 2:]) / 2, c[:, 2:] - c[:, :2], colors=[(255, 255, 0)])
    parts.particles(rec, f"{root}/klt/features", np.asarray(inter.features_uv, dtype=np.float64))
    pts = inter.points
    colours = [colour_of(int(g)) for g in inter.labels.tolist()]
    if len(pts):
        rec.log(f"{root}/klt/tracks", rr.LineStrips2D(pts.track_uv.astype(np.float32), colors=colours))
        rec.log(f"{root}/world/points", rr.Points3D(pts.xyz.astype(np.float32), colors=colours, radii=0.03))
    else:
        parts.clear(rec, f"{root}/klt/tracks")
        parts.clear(rec, f"{root}/world/points")
    g = inter.groups
    gc = [colour_of(int(i)) for i in g.ids.tolist()]
    parts.covariance_ellipsoids(rec, f"{root}/world/groups", g.x[:, POS] if len(g.ids) else np.zeros((0, 3)), g.extent, colors=gc)
    parts.covariance_ellipsoids(rec, f"{root}/world/ekf", g.x[:, POS] if len(g.ids) else np.zeros((0, 3)),
                                g.P[:, POS][:, :, POS] if len(g.ids) else np.zeros((0, 3, 3)), colors=gc)
    for e in inter.events:
        rec.log(f"{root}/events", rr.TextLog(e))


def _png(image: np.ndarray) -> bytes:
    ok, data = cv2.imencode(".png", image, _PNG)
    if not ok:
        raise ValueError(f"cannot PNG-encode a {image.shape} {image.dtype} raster")
    return data.tobytes()


def mask_overlay(mask: np.ndarray) -> bytes:
    """A foreground mask as a PNG: :data:`FOREGROUND` where set, transparent elsewhere."""
    bgra = np.zeros((*mask.shape, 4), np.uint8)
    bgra[mask.astype(bool)] = (*FOREGROUND[::-1], 255)
    return _png(bgra)


def _rasters(rec: FrameLogger, root: str, inter) -> None:
    """The foreground masks and the disparity: PNG, or raw when the logger says :data:`FULL`."""
    d = inter.disparity
    top = float(np.nanmax(d)) if np.isfinite(d).any() else 1.0
    grey = parts.to_uint8(d, 0.0, max(top, 1.0))
    if getattr(rec, FULL, False):
        parts.annotation_context(rec, f"{root}/foreground", [(1, "foreground", FOREGROUND)])
        rec.log(f"{root}/foreground/left", rr.SegmentationImage(inter.fg_left.astype(np.uint8), opacity=MASK_OPACITY))
        rec.log(f"{root}/foreground/right", rr.SegmentationImage(inter.fg_right.astype(np.uint8), opacity=MASK_OPACITY))
        rec.log(f"{root}/disparity", rr.Image(grey, color_model="L"))
        return
    for side, mask in (("left", inter.fg_left), ("right", inter.fg_right)):
        _encoded(rec, f"{root}/foreground/{side}", mask_overlay(mask), opacity=MASK_OPACITY)
    _encoded(rec, f"{root}/disparity", _png(grey))


def _encoded(rec, path: str, png: bytes, **params) -> None:
    """A PNG at ``path``: through the logger's image template, or ``rr.log``'s way on a bare stream."""
    if isinstance(rec, FrameLogger):
        rec.image(path, rr.EncodedImage, png, media_type="image/png", **params)
    else:
        rec.log(path, rr.EncodedImage(contents=png, media_type="image/png", **params))
