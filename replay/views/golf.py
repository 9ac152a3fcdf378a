"""Rerun view of the golf-ball tracker (seed 000): every stage's intermediates, under its own path.

``trackers/<name>/…`` per stage, in pipeline order:

- ``reinit``: where the samples started again (point, spread ellipse, label) and an event line;
- ``search``: the search region ``I_s``, labelled with the LUT in use; ``search/spread/{x,y}`` series;
- ``silhouette``: the crop of ``I_s`` with ``I_c`` over it, placed at the crop's offset (so it also
  overlays the camera image; the silhouette view shows it alone); ``silhouette/blobs`` the centres;
- ``blobs``: boxes labelled area/circularity/reason (green accepted, red rejected, the ball larger);
  ``blobs/targets/…`` the gate's targets and widening;
- ``particles``: the samples, coloured and sized by weight;
- ``ekf``: the predicted landing in the image; ``ekf/world/…`` the 3-D ball with its 2σ covariance,
  its path, the line of sight and the landing point; ``ekf/state|sigma/…``, ``ekf/nis`` and
  ``ekf/time_to_landing_s`` series;
- ``trail``: the measured trajectory drawn into the current pose (stored lines of sight);
- ``events``: LUT choice, re-initialisations, notices. The track itself is ``tracks/1``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from trackreplay.replay.views.rerun_sink import FrameLogger
from trackreplay.replay.views import parts
from trackreplay.trackers.base import TrackState
from trackreplay.trackers.frame import Frame

BALL_CLASS = 1
EKF_NAMES = ("X", "Y", "Z", "VX", "VY", "VZ")
DRAWN = ("reinit", "search", "blobs", "particles", "ekf/landing", "trail")  # cleared when idle


def blueprint(name: str) -> rrb.Blueprint:
    root = f"trackers/{name}"
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Spatial2DView(
                name="camera + search region + particles",
                origin="/",
                contents=["camera/**", "tracks/**", f"{root}/search", f"{root}/silhouette/mask", f"{root}/blobs",
                          f"{root}/particles", f"{root}/trail", f"{root}/ekf/landing", f"{root}/reinit/**"],
            ),
            rrb.Vertical(
                rrb.Spatial2DView(name="I_s + silhouette I_c", origin=f"{root}/silhouette"),
                rrb.Spatial3DView(name="EKF world (Z up)", origin=f"{root}/ekf/world"),
                rrb.TextLogView(name="LUT / events", origin=f"{root}/events"),
            ),
            rrb.Vertical(
                rrb.TimeSeriesView(name="gating targets", origin=f"{root}/blobs/targets"),
                rrb.TimeSeriesView(name="confidence: validation / reported", origin=f"{root}/validation",
                                   contents=[f"{root}/validation/confidence", f"{root}/validation/reported"]),
                rrb.TimeSeriesView(name="particle spread (px)", origin=f"{root}/search/spread"),
                rrb.TimeSeriesView(name="EKF height / time to landing", origin=f"{root}/ekf",
                                   contents=[f"{root}/ekf/state/Z", f"{root}/ekf/sigma/Z", f"{root}/ekf/nis",
                                             f"{root}/ekf/time_to_landing_s"]),
            ),
            column_shares=[3, 2, 1],
        ),
        collapse_panels=False,
    )


def log(rec: FrameLogger, name: str, frame: Frame, inter, states: Sequence[TrackState]) -> None:
    root = f"trackers/{name}"
    parts.tracks(rec, states)
    if inter is not None:
        parts.notice(rec, f"{root}/events", inter.notice)
    if inter is None or inter.mode == "idle":
        for stage in DRAWN:
            parts.clear(rec, f"{root}/{stage}", recursive=stage == "reinit")
        parts.clear(rec, f"{root}/silhouette", recursive=True)
        return
    _reinit(rec, f"{root}/reinit", f"{root}/events", frame, inter.reinit)
    sil = inter.silhouette
    parts.box_xywh(rec, f"{root}/search", inter.search.box, label=f"I_s {sil.lut_name}")
    parts.scalar(rec, f"{root}/search/spread/x", inter.search.spread[0])
    parts.scalar(rec, f"{root}/search/spread/y", inter.search.spread[1])
    scores = ", ".join(f"{n} {s:.2f}" for n, s in zip(sil.lut_names, sil.lut_scores) if np.isfinite(s))
    parts.draw(rec, f"{root}/events", rr.TextLog, text=[f"LUT {sil.lut_name or '-'} ({scores})"],
               level=[rr.TextLogLevel.DEBUG])
    _silhouette(rec, f"{root}/silhouette", frame, sil)
    check = inter.validation  # issue 10: the confidence and why a frame is (not) measured
    parts.scalar(rec, f"{root}/validation/confidence", check.confidence)
    parts.scalar(rec, f"{root}/validation/gate_px", check.gate_px)
    for state in states:  # the row's reported confidence (P(within 10 px) when calibrated), beside the validation's
        if state.status != "lost" and state.confidence is not None:
            parts.scalar(rec, f"{root}/validation/reported", state.confidence)
    if check.verdict not in ("", "measured", "confirmed"):
        parts.draw(rec, f"{root}/events", rr.TextLog,
                   text=[f"frame {frame.index}: not measured: {check.verdict} (confidence {check.confidence:.2f}, "
                         f"fit {check.fit:.2f}, tentative {len(check.tentative)} frames)"],
                   level=[rr.TextLogLevel.INFO])
    _blobs(rec, f"{root}/blobs", f"{root}/silhouette/blobs", inter.blobs, sil.offset)
    parts.particles(rec, f"{root}/particles", inter.particles.particles, inter.particles.weights)
    _ekf(rec, f"{root}/ekf", frame, inter.ekf, inter.trail.world)
    if len(inter.trail.image) >= 2:
        parts.draw(rec, f"{root}/trail", rr.LineStrips2D, strips=[inter.trail.image.astype(np.float32)],
                   colors=[(255, 200, 0)])
    else:
        parts.clear(rec, f"{root}/trail")


def _row(point) -> np.ndarray:
    """One point as a batch of one (float32, as Rerun stores positions)."""
    return np.asarray(point, dtype=np.float32).reshape(1, -1)


def _reinit(rec: FrameLogger, path: str, events: str, frame: Frame, reinit) -> None:
    if not reinit.kind:
        parts.clear(rec, path, recursive=True)
        return
    parts.draw(rec, f"{path}/point", rr.Points2D, positions=_row(reinit.point), radii=6.0, colors=[(0, 255, 255)],
               labels=[reinit.kind])
    parts.covariance_ellipses(rec, f"{path}/spread", reinit.point, np.diag(reinit.sigma**2), n_sigma=1.0,
                              colors=[(0, 255, 255)])
    parts.draw(rec, events, rr.TextLog, text=[f"frame {frame.index}: particles re-initialised ({reinit.kind}) at "
                                              f"({reinit.point[0]:.1f}, {reinit.point[1]:.1f})"])


def _silhouette(rec: FrameLogger, path: str, frame: Frame, sil) -> None:
    """The crop of I_s and the silhouette I_c over it, at the crop's place in the camera image."""
    ox, oy = (int(v) for v in sil.offset)
    sh, sw = sil.mask.shape[:2]
    crop = frame.image[oy : oy + sh, ox : ox + sw]
    if not crop.size:
        parts.clear(rec, path, recursive=True)
        return
    parts.annotation_context(rec, path, [(0, "background", (0, 0, 0, 0)), (BALL_CLASS, "ball", (255, 0, 255, 200))])
    parts.mask_over_crop(rec, path, sil.mask.astype(bool), (ox, oy), class_id=BALL_CLASS, image=crop)


def _blobs(rec: FrameLogger, path: str, points_path: str, gated, offset: np.ndarray) -> None:
    b = gated.blobs
    reasons = np.array(gated.reasons, dtype=object)[gated.reason] if len(b) else np.zeros(0, dtype=object)
    parts.blobs(rec, path, b.centroid, b.size, gated.accepted,
                fields={"area": b.area, "circularity": b.circularity, "reason": reasons},
                formats={"area": "{:.0f}", "circularity": "{:.2f}"}, selected=gated.selected,
                points_path=points_path, offset=offset)
    if np.all(np.isfinite(gated.targets)):
        parts.scalar(rec, f"{path}/targets/area_px", gated.targets[0])
        parts.scalar(rec, f"{path}/targets/circularity", gated.targets[1])
    parts.scalar(rec, f"{path}/targets/gate_widen", gated.widen)


def _ekf(rec: FrameLogger, path: str, frame: Frame, ekf, trail_world: np.ndarray) -> None:
    world = f"{path}/world"
    if np.all(np.isfinite(ekf.landing_image)):
        parts.draw(rec, f"{path}/landing", rr.Points2D, positions=_row(ekf.landing_image), radii=4.0,
                   colors=[(255, 0, 255)], labels=[f"landing in {ekf.landing_in_s:.2f} s"])
    else:
        parts.clear(rec, f"{path}/landing")
    if frame.camera is not None:  # a PTZ head turns about a fixed point: its position once, not per frame
        parts.static_once(rec, f"{world}/camera", rr.Points3D(positions=_row(frame.camera.position), radii=0.5,
                                                              colors=[(255, 255, 255)], labels=["camera"]))
    if np.all(np.isfinite(ekf.x)):
        p = ekf.x[:3]
        parts.draw(rec, f"{world}/ball", rr.Points3D, positions=_row(p), radii=0.4, colors=[(255, 255, 0)])
        parts.covariance_ellipsoids(rec, f"{world}/covariance", p, ekf.P[:3, :3], colors=[(255, 255, 0)])
        if frame.camera is not None:
            parts.draw(rec, f"{world}/line_of_sight", rr.LineStrips3D,
                       strips=[np.array([frame.camera.position, p], dtype=np.float32)], colors=[(120, 120, 255)])
        if len(trail_world) >= 2:
            parts.draw(rec, f"{world}/trajectory", rr.LineStrips3D, strips=[np.asarray(trail_world, dtype=np.float32)],
                       colors=[(255, 200, 0)])
        parts.kalman_series(rec, path, ekf.x, ekf.P, EKF_NAMES)
        parts.scalar(rec, f"{path}/nis", ekf.nis)
    if np.all(np.isfinite(ekf.landing_world)):
        parts.draw(rec, f"{world}/landing", rr.Points3D, positions=_row(ekf.landing_world), radii=0.8,
                   colors=[(255, 0, 255)])
        parts.scalar(rec, f"{path}/time_to_landing_s", ekf.landing_in_s)
    else:
        parts.clear(rec, f"{world}/landing")
