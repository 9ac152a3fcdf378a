"""The trackers' raw measurements, kept during a replay for the offline smoother (``replay --smooth``,
``ReplayRequest(observations=True)``): one row per track and frame, before the tracker's own filter."""

from __future__ import annotations

import polars as pl

from trackreplay.trackers.base import TrackerSpec

# Raw observations (the tracker's measurement before its own filter), one row per track and frame:
# image position/velocity (flow: centroid and mean flow, trackers/flow/observations.py) or a 3-D point
# with its covariance (groups: the mean [u v d] of the group's points carried through the rig,
# R = J⁻¹ diag(σ_u², σ_v², σ_d²) J⁻ᵀ, trackers/groups/observations.py).
OBS_SCHEMA: dict[str, pl.DataType] = {
    "tracker": pl.String, "track_id": pl.Int64, "frame": pl.Int64,
    "zx": pl.Float64, "zy": pl.Float64, "zvx": pl.Float64, "zvy": pl.Float64,
    "zX": pl.Float64, "zY": pl.Float64, "zZ": pl.Float64,
    "rXX": pl.Float64, "rXY": pl.Float64, "rXZ": pl.Float64, "rYY": pl.Float64, "rYZ": pl.Float64, "rZZ": pl.Float64,
}


def observation_rows(spec: TrackerSpec, frame_index: int, intermediates, states, rig=None, config=None) -> list[dict]:
    """The raw measurements of one replay step (:data:`OBS_SCHEMA` rows), as the tracker's spec
    declares them (``observations``: flow, groups); empty for trackers whose output is already their
    measurement. ``rig``: the frame's stereo rig; ``config``: the tracker's config as replayed."""
    if spec.observations is None or intermediates is None:
        return []
    return [{"tracker": spec.name, "frame": int(frame_index), **row}
            for row in spec.observations(intermediates, states, rig, config)]


def observations_table(rows: list[dict]) -> pl.DataFrame:
    full = [{k: r.get(k) for k in OBS_SCHEMA} for r in rows]
    return pl.DataFrame(full, schema=OBS_SCHEMA, orient="row", nan_to_null=False) if full else pl.DataFrame(schema=OBS_SCHEMA)
