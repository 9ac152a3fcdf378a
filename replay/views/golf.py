"""Rerun view of the golf-ball tracker (seed 000): every intermediate of a step.

Camera view: the search region I_s, the blobs labelled "area/circularity/reason" (green accepted,
red rejected, the ball ringed), the particles coloured and sized by weight, the estimate, the
trajectory so far (stored lines of sight drawn into the current pose) and the predicted landing.
Region view: the crop of I_s with the silhouette I_c over it. World view: the EKF's 3-D ball,
its past positions, the line of sight and the predicted landing point. Text: the active LUT and
re-initialisations. Time series: gating targets, spread, EKF height and time to landing.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from trackreplay.trackers.base import TrackState
from trackreplay.trackers.frame import Frame

from trackreplay.replay.rerun_sink import FrameLogger
from trackreplay.replay.views.common import log_estimates, log_scalar

ACCEPTED = (40, 230, 40)
REJECTED = (235, 50, 50)
BALL_CLASS = 1


def blueprint(name: str) -> rrb.Blueprint:
    root = f"trackers/{name}"
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Spatial2DView(
                name="camera + search region + particles",
                origin="/",
                contents=["camera/**", f"{root}/search_region", f"{root}/region/silhouette", f"{root}/blobs",
                          f"{root}/particles", f"{root}/estimate", f"{root}/trail", f"{root}/landing", f"{root}/reinit"],
            ),
            rrb.Vertical(
                rrb.Spatial2DView(name="I_s + silhouette I_c", origin=f"{root}/region"),
                rrb.Spatial3DView(name="EKF world (Z up)", origin=f"{root}/world"),
                rrb.TextLogView(name="LUT / events", origin=f"{root}/events"),
            ),
            rrb.Vertical(
                rrb.TimeSeriesView(name="gating targets", origin=f"{root}/targets"),
                rrb.TimeSeriesView(name="particle spread (px)", origin=f"{root}/spread"),
                rrb.TimeSeriesView(name="EKF height / time to landing", origin=f"{root}/ekf"),
            ),
            column_shares=[3, 2, 1],
        ),
        collapse_panels=False,
    )


def _weight_colours(w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Colour (blue -> yellow) and radius by weight relative to the largest."""
    rel = w / w.max() if w.size and w.max() > 0 else np.zeros_like(w)
    colours = np.stack([60 + 195 * rel, 80 + 175 * rel, 255 - 215 * rel], axis=1).astype(np.uint8)
    return colours, (0.8 + 2.2 * rel).astype(np.float32)


def log(rec: FrameLogger, name: str, frame: Frame, inter, states: Sequence[TrackState]) -> None:
    root = f"trackers/{name}"
    if inter is None or inter.mode == "idle":
        for part in ("search_region", "blobs", "particles", "trail", "landing", "reinit", "region"):
            rec.log(f"{root}/{part}", rr.Clear(recursive=True))
        log_estimates(rec, f"{root}/estimate", states)
        if inter is not None and inter.notice:
            rec.log(f"{root}/events", rr.TextLog(inter.notice, level=rr.TextLogLevel.WARN))
        return

    x0, y0, w, h = (float(v) for v in inter.search_box)
    rec.log(f"{root}/search_region", rr.Boxes2D(array=[[x0, y0, w, h]], array_format=rr.Box2DFormat.XYWH,
                                                colors=[(255, 255, 255)], labels=[f"I_s {inter.lut_name}"]))
    log_estimates(rec, f"{root}/estimate", states)

    # Blobs: label "area/circ/reason"; the selected one gets a larger box.
    blobs = inter.blobs
    if len(blobs):
        reasons = inter.blob_reasons
        labels = [f"{b[2]:.0f}/{b[3]:.2f}/{reasons[int(b[5])]}" for b in blobs]
        colours = [ACCEPTED if b[4] > 0 else REJECTED for b in blobs]
        sizes = np.maximum(blobs[:, 6:8], 2.0) + np.where(np.arange(len(blobs)) == inter.selected, 6.0, 2.0)[:, None]
        rec.log(f"{root}/blobs", rr.Boxes2D(centers=blobs[:, :2], sizes=sizes, colors=colours, labels=labels))
    else:
        rec.log(f"{root}/blobs", rr.Clear(recursive=False))

    if len(inter.particles):
        colours, radii = _weight_colours(inter.weights)
        rec.log(f"{root}/particles", rr.Points2D(inter.particles[:, :2], colors=colours, radii=radii))
    if len(inter.trail_image) >= 2:
        rec.log(f"{root}/trail", rr.LineStrips2D([inter.trail_image], colors=[(255, 200, 0)]))
    else:
        rec.log(f"{root}/trail", rr.Clear(recursive=False))
    if np.all(np.isfinite(inter.landing_image)):
        rec.log(f"{root}/landing", rr.Points2D([inter.landing_image], radii=4.0, colors=[(255, 0, 255)],
                                               labels=[f"landing in {inter.landing_in_s:.2f} s"]))
    else:
        rec.log(f"{root}/landing", rr.Clear(recursive=False))
    if inter.reinit:
        rec.log(f"{root}/reinit", rr.Points2D([inter.reinit_point], radii=6.0, colors=[(0, 255, 255)], labels=[inter.reinit]))
        rec.log(f"{root}/events", rr.TextLog(f"frame {frame.index}: particles re-initialised ({inter.reinit}) at "
                                              f"({inter.reinit_point[0]:.1f}, {inter.reinit_point[1]:.1f})"))
    else:
        rec.log(f"{root}/reinit", rr.Clear(recursive=False))
    if inter.notice:
        rec.log(f"{root}/events", rr.TextLog(inter.notice, level=rr.TextLogLevel.WARN))
    scores = ", ".join(f"{n} {s:.2f}" for n, s in zip(inter.lut_names, inter.lut_scores) if np.isfinite(s))
    rec.log(f"{root}/events", rr.TextLog(f"LUT {inter.lut_name or '-'} ({scores})", level=rr.TextLogLevel.DEBUG))

    # The search region's crop and its silhouette, placed at the region's offset (so the silhouette
    # also overlays the camera view) and shown alone in the region view.
    ox, oy = (int(v) for v in inter.silhouette_offset)
    sh, sw = inter.silhouette.shape[:2]
    crop = frame.image[oy : oy + sh, ox : ox + sw]
    if crop.size:
        rec.log(f"{root}/region", rr.Transform3D(translation=[float(ox), float(oy), 0.0]))
        rec.log(f"{root}/region", rr.AnnotationContext([(0, "background", (0, 0, 0, 0)), (BALL_CLASS, "ball", (255, 0, 255, 200))]))
        rec.log(f"{root}/region/image", rr.Image(crop, color_model="L" if crop.ndim == 2 else "BGR"))
        rec.log(f"{root}/region/silhouette", rr.SegmentationImage(inter.silhouette * np.uint8(BALL_CLASS), opacity=0.6))
        if len(blobs):
            rec.log(f"{root}/region/blobs", rr.Points2D(blobs[:, :2] - [ox, oy], radii=1.5,
                                                        colors=[ACCEPTED if b[4] > 0 else REJECTED for b in blobs]))
        else:
            rec.log(f"{root}/region/blobs", rr.Clear(recursive=False))

    # World view.
    world = f"{root}/world"
    if frame.camera is not None:
        rec.log(f"{world}/camera", rr.Points3D([frame.camera.position], radii=0.5, colors=[(255, 255, 255)], labels=["camera"]))
    if np.all(np.isfinite(inter.ekf_x)):
        p = inter.ekf_x[:3]
        rec.log(f"{world}/ball", rr.Points3D([p], radii=0.4, colors=[(255, 255, 0)]))
        if frame.camera is not None:
            rec.log(f"{world}/line_of_sight", rr.LineStrips3D([[frame.camera.position, p]], colors=[(120, 120, 255)]))
        if len(inter.trail_world) >= 2:
            rec.log(f"{world}/trajectory", rr.LineStrips3D([inter.trail_world], colors=[(255, 200, 0)]))
        log_scalar(rec, f"{root}/ekf/height_m", float(p[2]))
        log_scalar(rec, f"{root}/ekf/nis", inter.ekf_nis)
    if np.all(np.isfinite(inter.landing_world)):
        rec.log(f"{world}/landing", rr.Points3D([inter.landing_world], radii=0.8, colors=[(255, 0, 255)]))
        log_scalar(rec, f"{root}/ekf/time_to_landing_s", inter.landing_in_s)
    else:
        rec.log(f"{world}/landing", rr.Clear(recursive=False))

    log_scalar(rec, f"{root}/targets/area_px", float(inter.targets[0]))
    log_scalar(rec, f"{root}/targets/circularity", float(inter.targets[1]))
    log_scalar(rec, f"{root}/targets/gate_widen", inter.gate_widen)
    log_scalar(rec, f"{root}/spread/x", float(inter.spread[0]))
    log_scalar(rec, f"{root}/spread/y", float(inter.spread[1]))
