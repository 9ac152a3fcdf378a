"""Everything one group-tracker step computed (hashed into the replay digest, drawn by the view)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from trackreplay.trackers.base import NOT_HASHED
from trackreplay.trackers.geometry.rig_pose import RigPose
from trackreplay.trackers.geometry.stereo import StereoRig
from trackreplay.trackers.groups.features import ObservationPoints


@dataclass(frozen=True, eq=False)
class GroupSnapshot:
    """The live groups after this frame's update and merge, one row each (ids ascending)."""

    ids: np.ndarray  # (G,)
    x: np.ndarray  # (G, 6) EKF state [x ẋ y ẏ z ż], camera frame, m and m/frame
    P: np.ndarray  # (G, 6, 6) EKF covariance
    extent: np.ndarray  # (G, 3, 3) eq. (7) position extent Σ, m²
    velocity_spread: np.ndarray  # (G, 3, 3) eq. (7) on the points' velocities, (m/frame)²
    members: np.ndarray  # (G,) observation points assigned this frame
    status: tuple[str, ...]  # "measured" | "predicted"
    boxes: np.ndarray  # (G, 4) image box x0 y0 x1 y1 (left view)
    merged_from: tuple[str, ...]  # "3,5" for a group born of a merge on this frame, else ""

    @classmethod
    def empty(cls) -> GroupSnapshot:
        return cls(np.zeros(0, np.int64), np.zeros((0, 6)), np.zeros((0, 6, 6)), np.zeros((0, 3, 3)),
                   np.zeros((0, 3, 3)), np.zeros(0, np.int64), (), np.zeros((0, 4)), ())


@dataclass(frozen=True, eq=False)
class GroupsIntermediates:
    mode: str  # "learning" (background frames), "tracking", "idle" (no stereo pair / calibration)
    fg_left: np.ndarray  # (H, W) bool
    fg_right: np.ndarray
    disparity: np.ndarray  # (H, W) float32, NaN off the foreground
    crops: np.ndarray  # (K, 4) SGBM crops
    features_uv: np.ndarray  # (F, 2) every live KLT feature
    points: ObservationPoints  # the time window's observation points
    labels: np.ndarray  # (M,) group id per point, -1 unassigned
    groups: GroupSnapshot
    ended: np.ndarray  # (E,) ids of groups that ended this frame (deleted or merged into another)
    events: tuple[str, ...]
    dt_s: float  # seconds since the previous frame (m/frame → m/s)
    notice: str = ""
    world: RigPose | None = None  # the rig's pose: the second table's vectors and extents in the world frame
    # the rig the step measured with (a stereo pair's, or one camera's virtual rig over the ground
    # plane: trackers.groups.ground_depth); what the observations are computed from, not a result
    rig: StereoRig | None = field(default=None, metadata=NOT_HASHED)

    @classmethod
    def idle(cls, mode: str, shape: tuple[int, int], notice: str = "", window: int = 2) -> GroupsIntermediates:
        blank = np.zeros(shape, bool)
        return cls(mode, blank, blank, np.full(shape, np.nan, np.float32), np.zeros((0, 4), np.int64),
                   np.zeros((0, 2), np.float32), ObservationPoints.empty(window), np.zeros(0, np.int64),
                   GroupSnapshot.empty(), np.zeros(0, np.int64), (), float("nan"), notice)

    def extra_rows(self) -> list[dict]:
        """The second table's rows (docs/groups.md): per live group its member count, 3-D velocity
        (m/s), position extent Σ (m²) and EKF position sigma (m); ``merged_from`` on a merge. In the
        world frame (Z up) when the log carries the rig's pose, else the left camera's
        (``position_frame`` says which)."""
        g, rows = self.groups, []
        scale = 1.0 / self.dt_s if np.isfinite(self.dt_s) and self.dt_s > 0 else float("nan")
        pos, vel = [0, 2, 4], [1, 3, 5]
        V = g.x[:, vel] * scale
        extent, Ppos = g.extent, g.P[:, pos][:, :, pos]
        if self.world is not None:
            V, extent, Ppos = self.world.rotate(V), self.world.rotate_cov(extent), self.world.rotate_cov(Ppos)
        frame = "camera" if self.world is None else "world"
        for k, gid in enumerate(g.ids.tolist()):
            S = extent[k]
            P = Ppos[k]
            rows.append({
                "track_id": int(gid), "members": int(g.members[k]), "position_frame": frame,
                "VX": float(V[k, 0]), "VY": float(V[k, 1]), "VZ": float(V[k, 2]),
                "cov_xx": float(S[0, 0]), "cov_xy": float(S[0, 1]), "cov_xz": float(S[0, 2]),
                "cov_yy": float(S[1, 1]), "cov_yz": float(S[1, 2]), "cov_zz": float(S[2, 2]),
                "sigma_X": float(np.sqrt(P[0, 0])), "sigma_Y": float(np.sqrt(P[1, 1])), "sigma_Z": float(np.sqrt(P[2, 2])),
                "merged_from": g.merged_from[k] or None,
            })
        return rows
