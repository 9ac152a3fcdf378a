"""Rerun 3-D view of a fitted golf flight: the camera, its lines of sight, the fitted path and events.

Entity paths under ``flight/``: ``camera`` (point), ``path`` (the fitted 3-D trajectory, one strip
per phase), ``lines_of_sight`` (a segment per measured frame, from the camera to just beyond the
fitted ball; ``lines_of_sight_rescan``: those of the frames ``flight --rescan`` found), ``events`` (launch, apex, landing, rest), ``ball`` (per frame on the ``frame``
timeline), ``ground`` (the ground plane's outline under the shot). World metres, Z up.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import polars as pl
import rerun as rr

from trackreplay.schemas.errors import OutputError
from trackreplay.trackers.golf.ball_flight import PHASES

COLOURS = {"tee": (200, 200, 200), "air": (255, 200, 40), "bounce": (255, 120, 40), "roll": (80, 200, 255), "rest": (80, 200, 255)}


def write_flight_rrd(path: str | Path, fit, rows: pl.DataFrame, name: str = "flight", rescanned: frozenset[int] = frozenset()) -> Path:
    """Write the 3-D view of ``fit`` (a :class:`~trackreplay.replay.analysis.flight.FlightFit`) and its ``rows``;
    the lines of sight of the ``rescanned`` frames (found by ``flight --rescan``) apart, under
    ``flight/lines_of_sight_rescan``, in their own colour."""
    path = Path(path)
    rec = rr.RecordingStream(f"trackreplay-{name}", recording_id=name, send_properties=False)
    rec.set_log_time_enabled(False) if hasattr(rec, "set_log_time_enabled") else None
    try:
        rec.save(path)
    except Exception as err:  # noqa: BLE001 - rerun raises its own types for an unwritable path
        raise OutputError(f"cannot write {path} ({err})") from None
    obs, rep = fit.observations, fit.report
    cam = obs.camera
    rec.log("flight", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    rec.log("flight/camera", rr.Points3D([cam], radii=0.6, colors=[(255, 255, 255)], labels=["camera"]), static=True)
    pos, phase = fit.shot.at(obs.t)
    rng = np.linalg.norm(pos - cam, axis=1) * 1.05
    rays = [np.stack([cam, cam + r * d]) for r, d in zip(rng, obs.los)]
    found = np.isin(obs.frame, sorted(rescanned))
    rec.log("flight/lines_of_sight", rr.LineStrips3D([r for r, f in zip(rays, found) if not f], colors=[(120, 160, 255, 60)],
                                                     radii=0.02), static=True)
    if found.any():
        rec.log("flight/lines_of_sight_rescan", rr.LineStrips3D([r for r, f in zip(rays, found) if f], colors=[(255, 80, 200, 120)],
                                                                radii=0.02), static=True)
    t = np.linspace(fit.shot.t[0], fit.shot.t[-1], 600)
    path_pos, path_phase = fit.shot.at(t)
    strips, colours = [], []
    for code, phase_name in enumerate(PHASES):  # the shared model's phase codes
        sel = path_phase == code
        if sel.sum() >= 2:
            strips.append(path_pos[sel])
            colours.append(COLOURS[phase_name])
    rec.log("flight/path", rr.LineStrips3D(strips, colors=colours, radii=0.15), static=True)
    events, labels = [], []
    for label, point in (("launch", [v.value for v in rep.launch_point]), ("apex", fit.shot.apex_point),
                         ("landing", [v.value for v in rep.landing_point]), ("rest", [v.value for v in rep.rest_point])):
        if np.isfinite(point).all():
            events.append(point)
            labels.append(label)
    if events:
        rec.log("flight/events", rr.Points3D(events, radii=0.8, colors=[(255, 60, 60)], labels=labels), static=True)
    ext = np.concatenate([path_pos[:, :2], cam[None, :2]])
    (x0, y0), (x1, y1) = ext.min(axis=0) - 10, ext.max(axis=0) + 10
    rec.log("flight/ground", rr.LineStrips3D([[[x0, y0, 0], [x1, y0, 0], [x1, y1, 0], [x0, y1, 0], [x0, y0, 0]]],
                                              colors=[(60, 140, 60)]), static=True)
    for row in rows.filter(pl.col("X").is_not_null()).iter_rows(named=True):
        rec.set_time("frame", sequence=int(row["frame"]))
        rec.set_time("log_time", timestamp=np.datetime64(int(row["t_ns"]), "ns"))
        rec.log("flight/ball", rr.Points3D([[row["X"], row["Y"], row["Z"]]], radii=0.5, colors=[COLOURS[row["phase"]]]))
    rec.flush()
    rec.disconnect()
    return path
