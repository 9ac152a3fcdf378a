"""The group tracker's raw measurement per step, for the offline smoother: per group updated this
frame (and not born of a merge) the mean ``[u v d]`` of its points (eq. 4), carried to 3-D with the
covariance of the EKF's σ_u, σ_v, σ_d, ``R = J⁻¹ diag(σ_u², σ_v², σ_d²) J⁻ᵀ`` (eq. 6's Jacobian)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from trackreplay.trackers.base import TrackState
from trackreplay.trackers.geometry.stereo import StereoRig
from trackreplay.trackers.groups.config import GroupsConfig
from trackreplay.trackers.groups.intermediates import GroupsIntermediates


def raw_observations(intermediates: GroupsIntermediates, states: Sequence[TrackState], rig: StereoRig | None,
                     config: GroupsConfig | None = None) -> list[dict]:
    """Rows ``zX zY zZ`` (m) and ``rXX .. rZZ`` (m²), in the world frame (like the trajectory) when the
    rig's pose is known; ``config`` is the one replayed (None: the defaults). ``rig`` is the frame's
    stereo rig; None (one camera over a ground plane) uses the step's own (``intermediates.rig``)."""
    g = intermediates.groups
    cfg = config or GroupsConfig()
    sigma_d = cfg.ekf.sigma_d if rig is not None else cfg.ground.sigma_foot_px
    rig = rig or intermediates.rig  # one camera over a ground plane: the step's virtual rig
    if rig is None or not len(g.ids):
        return []
    e = cfg.ekf
    Ruvd = np.diag([e.sigma_u**2, e.sigma_v**2, sigma_d**2])
    uvd, labels = intermediates.points.uvd, intermediates.labels
    rows = []
    for k, gid in enumerate(g.ids.tolist()):
        if g.status[k] != "measured" or g.merged_from[k]:
            continue
        sel = labels == gid
        if not sel.any():
            continue
        m = uvd[sel].mean(axis=0)
        if not (np.isfinite(m).all() and m[2] > 0):
            continue
        p = rig.to_points(m[None])[0]
        Ji = np.linalg.inv(rig.jacobian(p))
        R = Ji @ Ruvd @ Ji.T
        if rig.pose is not None:  # the trajectory's X Y Z are then in the world frame: so are its observations
            p, R = rig.pose.to_world(p[None])[0], rig.pose.rotate_cov(R)
        rows.append({"track_id": int(gid), "zX": float(p[0]), "zY": float(p[1]), "zZ": float(p[2]),
                     "rXX": R[0, 0], "rXY": R[0, 1], "rXZ": R[0, 2], "rYY": R[1, 1], "rYZ": R[1, 2], "rZZ": R[2, 2]})
    return rows
