"""Rerun view of the colour particle filter (seed 002), built from :mod:`.parts`.

``trackers/<name>/…``:

- ``particles``: the particle centres coloured and sized by weight; ``particles/boxes`` their boxes
  (faint); ``estimate`` the eq. (6) box labelled with S;
- ``histograms/reference`` and ``histograms/current``: H_ref and the estimate box's H-S histogram
  as grey images (rows H, columns S);
- ``background``: the marked box's foreground from background subtraction (on the frame the
  reference was built; it stays shown), placed over the camera image;
- series: ``aspect/R`` (used) and ``aspect/R_t`` (eq. 11 measured), ``size/S_prime`` (eq. 9),
  ``ground/distance_m``, ``similarity/estimate``, ``particles/effective``;
- ``events``: notices and the reference's kind.
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

TARGET_CLASS = 1
DRAWN = ("particles", "particles/boxes", "estimate")


def blueprint(name: str) -> rrb.Blueprint:
    root = f"trackers/{name}"
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Spatial2DView(name="camera + particles + estimate", origin="/",
                              contents=["camera/**", "tracks/**", f"{root}/particles/**", f"{root}/estimate",
                                        f"{root}/background/**"]),
            rrb.Vertical(
                rrb.Spatial2DView(name="H_ref (rows H, columns S)", origin=f"{root}/histograms/reference"),
                rrb.Spatial2DView(name="estimate box histogram", origin=f"{root}/histograms/current"),
                rrb.TextLogView(name="events", origin=f"{root}/events"),
            ),
            rrb.Vertical(
                rrb.TimeSeriesView(name="aspect R (used) and R_t (eq. 11)", origin=f"{root}/aspect"),
                rrb.TimeSeriesView(name="S' (eq. 9, px²)", origin=f"{root}/size"),
                rrb.TimeSeriesView(name="ground distance Z (m)", origin=f"{root}/ground"),
                rrb.TimeSeriesView(name="similarity S of the estimate", origin=f"{root}/similarity"),
            ),
            column_shares=[3, 1, 1],
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
            parts.clear(rec, f"{root}/{stage}")
        return
    p = inter.particles
    parts.particles(rec, f"{root}/particles", p[:, :2], inter.weights)
    parts.boxes(rec, f"{root}/particles/boxes", p[:, :2], p[:, 2:4], colors=[(120, 170, 255, 70)])
    e = inter.estimate
    parts.boxes(rec, f"{root}/estimate", e[None, :2], e[None, 2:4], colors=[(255, 255, 0)],
                labels=[f"S={inter.estimate_similarity:.2f} {inter.status}"])
    parts.histogram_2d(rec, f"{root}/histograms/reference", np.atleast_2d(inter.reference))
    parts.histogram_2d(rec, f"{root}/histograms/current", np.atleast_2d(inter.current))
    if inter.mask.size:
        parts.annotation_context(rec, f"{root}/background", [(0, "background", (0, 0, 0, 0)),
                                                             (TARGET_CLASS, "foreground", (255, 0, 255, 160))])
        parts.mask_over_crop(rec, f"{root}/background", inter.mask, inter.mask_offset, name="foreground",
                             class_id=TARGET_CLASS)
        parts.draw(rec, f"{root}/events", rr.TextLog,
                   text=[f"frame {frame.index}: reference {inter.reference_kind} from the {inter.background} background"])
    parts.scalar(rec, f"{root}/aspect/R", inter.aspect)
    parts.scalar(rec, f"{root}/aspect/R_t", inter.aspect_measured)
    parts.scalar(rec, f"{root}/size/S_prime", inter.area)
    parts.scalar(rec, f"{root}/ground/distance_m", inter.distance)
    parts.scalar(rec, f"{root}/similarity/estimate", inter.estimate_similarity)
    w = inter.weights
    parts.scalar(rec, f"{root}/particles/effective", 1.0 / float(np.sum(w**2)) if w.size else float("nan"))
