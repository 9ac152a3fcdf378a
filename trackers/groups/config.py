"""Parameters of the group tracker (seed 003), one frozen table per stage.

The paper gives the search radius of the initial grouping (1 m), the update threshold (a tracker
is updated when 2 or more points are assigned) and the form of every step; γ, α_s, the noises,
the time window and the merge gates it calls "found experimentally". Ours are explained per field
and are per frame at the paper's 48 fps.

TOML (every table and key optional; ``trackreplay replay LOG --tracker groups --config g.toml``)::

    [groups.association]
    gamma = 11.34
    [groups.tracks]
    max_empty_frames = 12
"""

from __future__ import annotations

from dataclasses import dataclass, field

from trackreplay.trackers.geometry.subtraction_stereo import SgbmConfig


@dataclass(frozen=True)
class BackgroundConfig:
    """§2 background subtraction in both views: per-pixel median of the first frames."""

    frames: int = 8  # the log's first frames (empty scene) make the median background
    threshold: float = 22.0  # grey levels, largest channel difference
    open_px: int = 3  # opening that drops isolated noisy pixels


@dataclass(frozen=True)
class StereoConfig:
    """§2 subtraction stereo: SGBM on foreground crops."""

    sgbm: SgbmConfig = field(default_factory=SgbmConfig)
    margin_px: int = 8  # crop growth around each foreground region
    right_tolerance_px: int = 2  # the match must land on the right foreground, dilated this much
    disparity_window: int = 5  # a feature's disparity: median of the valid values in this square


@dataclass(frozen=True)
class KltConfig:
    """§3.1 KLT (Shi–Tomasi corners + pyramidal Lucas–Kanade) on the left foreground; Fig. 3 time window."""

    max_corners: int = 400
    quality: float = 0.01
    min_distance: float = 4.0
    win: int = 11
    levels: int = 2
    forward_backward_px: float = 0.7  # LK there and back must return within this
    window: int = 6  # frames a track must span to be an observation point (paper: "Time Window")


@dataclass(frozen=True)
class EkfConfig:
    """§3.2 constant-velocity EKF, state [x ẋ y ẏ z ż] (m, m/frame), observation [u v d] (px)."""

    # m/frame²: white-noise acceleration (0.0015 m/frame² = 3.5 m/s² at 48 fps). It sets the EKF's
    # velocity sigma, which the merge's velocity gate reads: at 0.004 (9 m/s²) that sigma was
    # 0.4-0.65 m/s per axis and groups-passing's groups, 1 m/s apart, merged at 48 fps; 0.002 and
    # 0.003 still merged them; 0.0015 does not (scene seeds 0-2, clips from 0 s and 1 s) and merges
    # groups-merging 18 frames after the truth
    accel_sigma: float = 0.0015
    sigma_u: float = 3.0  # px: the mean of a group's points moves as members hide or show
    sigma_v: float = 4.0
    sigma_d: float = 0.25  # px (SGBM's sub-pixel disparity averaged over the points)
    init_velocity_sigma: float = 0.02  # m/frame


@dataclass(frozen=True)
class AssociationConfig:
    """§3.3 eq. (8) gate and eqs. (9)–(11) with the m_p·m_v fix; eq. (7) extent."""

    gamma: float = 16.27  # eq. (8) squared Mahalanobis gate: χ²(3 dof) at 99.9 % (the extent is a body, not a Gaussian)
    k_p: float = 1.0  # eq. (9) weight (scales every m_p alike: no effect on the arg max, kept for the form)
    k_v: float = 1.0  # eq. (10)
    alpha_s: float = 0.8  # eq. (7) weight of the previous extent
    min_points: int = 2  # paper: a tracker with 2 or more points is updated, else it only predicts
    min_extent_m: float = 0.15  # added in quadrature to the extent (a lone point still has a body around it)


@dataclass(frozen=True)
class GroupingConfig:
    """§3.4 eq. (12) initial grouping of unassigned points."""

    radius_m: float = 1.0  # paper: search region, Euclidean 1 m
    # Points needed to start a tracker (the paper: "a threshold", no value). 6 let splinters of 6-7
    # points (a few legs or heads at a wrong depth) start groups of their own in every scene at 48 fps;
    # 12 removes all but one late one (docs/groups.md: crossing 3-D MOTA 0.74 -> 0.97, stairs 0.52 -> 0.97)
    min_points: int = 12


@dataclass(frozen=True)
class MergeConfig:
    """§3.5 eq. (13): merge trackers whose position AND velocity regions overlap."""

    gamma_position: float = 11.34  # squared Mahalanobis of the centres under Σ_i + Σ_j (extent)
    gamma_velocity: float = 6.25  # (χ² 3 dof, 90 %) of the velocities under P_v,i + P_v,j (EKF velocity covariances)
    frames: int = 8  # the overlap must hold this many consecutive frames (ours: no merge on one noisy frame)
    # Add each group's point-velocity spread / member count to its EKF velocity covariance in the
    # velocity gate (off: the gate is the EKF velocity covariances alone, as eq. 13 reads). The EKF
    # never sees the points' velocities (it is updated with their mean [u v d]) and those are noisy
    # in depth (disparity noise over the time window): with the term, groups-passing's groups 1 m/s
    # apart were merged at 48 fps (a clip from 1.0 s, at frame 90); without it they are not, and
    # groups-merging merges on the same frame as with it.
    velocity_spread_in_gate: bool = False
    # Ours: a merge in which one group holds at least this share of the members keeps that group's
    # id (it absorbed a splinter, e.g. feet that started a tracker of their own); otherwise the
    # merged group is new, as in the paper (Group0 + Group1 -> Group2).
    keep_id_share: float = 0.7


@dataclass(frozen=True)
class TrackConfig:
    max_empty_frames: int = 12  # deleted after this many consecutive frames without an update (0.25 s at 48 fps)


@dataclass(frozen=True)
class GroupsConfig:
    background: BackgroundConfig = field(default_factory=BackgroundConfig)
    stereo: StereoConfig = field(default_factory=StereoConfig)
    klt: KltConfig = field(default_factory=KltConfig)
    ekf: EkfConfig = field(default_factory=EkfConfig)
    association: AssociationConfig = field(default_factory=AssociationConfig)
    grouping: GroupingConfig = field(default_factory=GroupingConfig)
    merge: MergeConfig = field(default_factory=MergeConfig)
    tracks: TrackConfig = field(default_factory=TrackConfig)

    def __post_init__(self) -> None:
        if self.klt.window < 2:
            raise ValueError("klt.window must be at least 2 frames (a velocity needs two positions)")
        if self.association.min_points < 1 or self.grouping.min_points < 1:
            raise ValueError("association.min_points and grouping.min_points must be at least 1")
        if not 0.0 <= self.association.alpha_s <= 1.0:
            raise ValueError("association.alpha_s must be in [0, 1]")
