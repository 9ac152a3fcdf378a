"""Parameters of the group tracker (seed 003), one frozen table per stage.

The paper gives the search radius of the initial grouping (1 m), the update threshold (a tracker
is updated when 2 or more points are assigned) and the form of every step; γ, α_s, the noises,
the time window and the merge gates it calls "found experimentally". Ours are explained per field
and are per frame at ``rate_hz`` (the paper's 48 fps). With ``scale_with_rate`` (default) the
tracker reads the log's frame rate (median frame interval of the background frames) and rescales
every per-frame value so that it means the same time at any rate (:meth:`GroupsConfig.at_rate`):
frame counts by fps/48 (time window 6 frames = 0.125 s, merge confirmation 8 = 0.167 s, deletion
after 12 empty frames = 0.25 s), the EKF's white acceleration (m/frame²) by (48/fps)^1.5 (the same
continuous-time process noise, q = 0.25 m²/s³: scaling by (48/fps)², the same piecewise-constant
3.5 m/s², doubles the velocity noise per second at 24 fps, and groups-passing's groups merged), its
initial velocity sigma (m/frame) by 48/fps, and eq. (7)'s α_s per frame by α_s^(48/fps) (the same
time constant). The SGBM settings, pixel noises, gates and point counts do not depend on the rate.

TOML (every table and key optional; ``trackreplay replay LOG --tracker groups --config g.toml``)::

    [groups.association]
    gamma = 11.34
    [groups.tracks]
    max_empty_frames = 12
    [groups.ground]          # one camera over a ground plane instead of a stereo pair
    background_ratio = 0.7
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from trackreplay.trackers.geometry.subtraction_stereo import SgbmConfig
from trackreplay.trackers.lifecycle import LifecycleConfig


@dataclass(frozen=True)
class BackgroundConfig:
    """§2 background subtraction in both views: per-pixel median of the first frames."""

    frames: int = 8  # the log's first frames (empty scene) make the median background (one camera: MOG2's first frames)
    threshold: float = 22.0  # grey levels, largest channel difference
    open_px: int = 3  # opening that drops isolated noisy pixels

    def __post_init__(self) -> None:
        if self.frames < 1 or self.open_px < 0:
            raise ValueError("background.frames must be >= 1 and background.open_px >= 0")


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

    def __post_init__(self) -> None:
        # OpenCV's corner detector works in int pixels: an astronomically large min_distance crashed it
        if self.max_corners < 1 or not 0 < self.quality < 1 or not 0 <= self.min_distance <= 10_000:
            raise ValueError("klt.max_corners must be >= 1, 0 < klt.quality < 1 and 0 <= klt.min_distance <= 10000 px")
        if self.win < 3 or self.levels < 0 or self.forward_backward_px <= 0 or self.window < 1:
            raise ValueError("klt.win must be >= 3, klt.levels >= 0, klt.forward_backward_px > 0 and klt.window >= 1")


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
    # Ours (issue 34, "splinters"): a set of unassigned points that would start a group but whose region
    # overlaps a confirmed group's gate is not a new group: "join" gives its points to that group before
    # the group's update (§3.3), "leave" leaves them unassigned, "start" starts a group as the paper does.
    # Overlap: the set's centroid within the eq. (8) gate (gamma) of the group under the gate's
    # covariance plus the set's own position spread (the margin is the set's own extent, as eq. 13 adds
    # the two extents). Confirmed: the group has been measured on merge.frames frames (the time a merge
    # needs to believe an overlap). On the synthetic scenes every identity change of a group that stays a
    # group went through such a set started beside the group it belonged to. With "join" and inside_box,
    # merging and stairs at scene seeds 0-9: such changes 9 -> 3, merges found as before, no false merge;
    # PETS09 (one camera) as before but group MOTA / IDF1 0.787 / 0.482 -> 0.789 / 0.486 (docs/groups.md)
    near_gate: str = "join"
    # Ours (issue 34): nor does a set whose image points' centre lies in a confirmed group's image box start
    # a group (with near_gate "join" or "leave"), whatever its depth: on the synthetic stairs (seeds 1, 9)
    # the splinters were the group's heads at half their disparity (3 m behind it in 3-D, inside its box),
    # which started 12-point groups that later took the group's points (docs/groups.md). Stereo only: with
    # one camera a pixel's depth is its own column's foot, never a mismatched disparity, and on PETS09 the
    # test held real people out inside big group boxes (person coverage 0.863 -> 0.664; docs/groups_pets.md)
    inside_box: bool = True
    # Ours (issue 34): with a stereo rig's pose (world Z up), the near_gate test is made on the ground
    # (world X Y: the set's centroid and the gate's covariance projected) at gamma_ground = χ²(2 dof) at
    # 99.9 %, eq. (8)'s probability: people stand upright, so a set under a group's points (its legs,
    # which the 3-D gate of a group tracked on its torsos leaves out) is the group whatever its height.
    # Synthetic stairs seed 5: its splinter was such legs, 1.15 m under the group, which now join it.
    # Stereo only: with one camera a column's pixels all stand on its foot (no such splinter), and on
    # PETS09 the ground test pulled people into groups (person coverage 0.863 -> 0.847; docs/groups.md)
    near_gate_ground: bool = True
    gamma_ground: float = 13.82
    # Ours (issue 34): the inside_box test asks whether the set's own image box overlaps the group's box
    # instead of whether its centre lies inside (the margin is the set's own extent, as near_gate adds the
    # set's spread to the gate): synthetic stairs seeds 6, 8 started groups from heads matched at half
    # their disparity whose centre was 1-2 rows above the box's top edge. With both tests the stairs
    # seeds 0-9 have no identity change; merging, crossing, passing unchanged (docs/groups.md)
    box_overlap: bool = True
    # Ours (issue 34): a group's points on each frame must be one connected set under eq. (12)'s relation
    # (within radius_m), as the points that start a group are: of the points its gate took it keeps the
    # connected set with the most points, the rest are unassigned. Without it a group whose eq. (7)
    # extent grew over a passer-by's points gated the next person's (PETS09 with ground.stature_check
    # alone: one group held ids 1-8, up to 17 m apart). "ground": with one camera only; "all": with
    # stereo too (not measured on the stereo scenes); "off": as the paper (every point its gate holds)
    connected: str = "ground"

    def __post_init__(self) -> None:
        if self.near_gate not in ("join", "leave", "start"):
            raise ValueError('grouping.near_gate must be "join", "leave" or "start"')
        if self.connected not in ("ground", "all", "off"):
            raise ValueError('grouping.connected must be "ground", "all" or "off"')


@dataclass(frozen=True)
class MergeConfig:
    """§3.5 eq. (13): merge trackers whose position AND velocity regions overlap."""

    gamma_position: float = 11.34  # squared Mahalanobis of the centres under Σ_i + Σ_j (extent)
    gamma_velocity: float = 6.25  # (χ² 3 dof, 90 %) of the velocities under P_v,i + P_v,j (EKF velocity covariances)
    frames: int = 8  # the overlap must hold this many consecutive frames (ours: no merge on one noisy frame)
    # With the rig's pose in the log: test the velocities in the ground plane only (world X, Y; 2 dof,
    # gate gamma_velocity_ground = chi2(2 dof, 90 %), the same probability as gamma_velocity's 3 dof).
    # Walking groups move on the ground: the vertical velocity carries only depth noise (the camera
    # looks down 40°, so its z is 64 % vertical) and adds a degree of freedom of noise to the test.
    ground_velocity: bool = True
    gamma_velocity_ground: float = 4.61
    # Add each group's point-velocity spread / member count to its EKF velocity covariance in the
    # velocity gate (off: the gate is the EKF velocity covariances alone, as eq. 13 reads). The EKF
    # never sees the points' velocities (it is updated with their mean [u v d]) and those are noisy
    # in depth (disparity noise over the time window): with the term, groups-passing's groups 1 m/s
    # apart were merged at 48 fps (a clip from 1.0 s, at frame 90); without it they are not, and
    # groups-merging merges on the same frame as with it.
    velocity_spread_in_gate: bool = False
    # Ours: a frame counts towards a merge only if the velocities agree also as the groups' member
    # points measure them: the mean of their own velocities λ_i (eq. 10's λ; from the points no other
    # group gates when there are association.min_points of them), across the line of sight to the
    # pair (horizontal with the rig's pose, 1 dof, chi2 90 % = 2.71; else the 2 image-plane
    # directions, 4.61), under the EKF velocity covariances plus the means' standard errors cov(λ)/N.
    # The EKF sees only the mean position of its points: while a fast group passes behind a slower
    # one, that mean moves slower than the group (its visible part shrinks from the front, and it
    # takes boundary points of the other) and its EKF velocity drifts towards the other's
    # (groups-passing at 24 fps: 1.85 -> 1.56 m/s, truth 1.9; merged falsely). Along the line of
    # sight the points' velocities are disparity slopes whose errors the points of one surface
    # share, so that component is left to the EKF test. A group with fewer than min_points points
    # this frame has no measured velocity: the pair is then tested on the EKF velocities alone.
    measured_velocity: bool = True
    gamma_measured_1dof: float = 2.71
    gamma_measured_2dof: float = 4.61
    # Ours: a merge in which one group holds at least this share of the members keeps that group's
    # id (it absorbed a splinter, e.g. feet that started a tracker of their own); otherwise the
    # merged group is new, as in the paper (Group0 + Group1 -> Group2).
    keep_id_share: float = 0.7


@dataclass(frozen=True)
class GroundConfig:
    """One fixed camera over a ground plane instead of a stereo pair (:mod:`.ground_depth`): the
    foreground from OpenCV's MOG2 (it keeps learning, so people standing in the first frames fade out
    of the background), each region's depth from its foot point on the ground. Used only when the log
    has a ground plane and no stereo pair; the stereo tables are then unused."""

    history_s: float = 20.0  # seconds MOG2 remembers (history = history_s x the log's rate, frames)
    var_threshold: float = 16.0  # MOG2's squared Mahalanobis foreground threshold (OpenCV's default)
    # MOG2's background ratio: the heaviest Gaussians whose weights sum to this are the background. A
    # person who stops becomes background once the old background's weight falls below it: at OpenCV's
    # 0.9 after 0.1 x history frames (2 s at 20 s), at 0.7 after 0.36 x history (7 s), at 0.5 after
    # 0.7 x history (14 s). PETS09 (people stand and talk): person coverage 0.75 / 0.83 / 0.57 and
    # wrong measured rows 4.5 / 3.6 / 13 % at 0.9 / 0.7 / 0.5 (at 0.5 the people of the first frames,
    # learnt as background, leave ghosts for long); docs/groups_pets.md
    background_ratio: float = 0.7
    # MOG2 marks shadows apart (value 127) and they stay background: a person's shadow on the
    # ground would move the region's foot point (its lowest pixels) away from the feet
    shadows: bool = True
    # MOG2's shadow threshold τ: a pixel darker than the background by a ratio in [τ, 1] with the same
    # colour is a shadow (left out). At OpenCV's 0.5 dark-grey legs on the grey paving are "shadow" too,
    # so a far person's foot is found at the knees and they are placed ~2 m too far (PETS09 person 6:
    # coverage 0.61). PETS09, person coverage / least person / wrong measured rows / group MOTA, IDF1:
    # τ 0.5 0.863 / 0.605 / 3.1 % / 0.789, 0.486; 0.6 0.882 / 0.728 / 2.4 % / 0.822, 0.544; 0.7 0.866 /
    # 0.686 / 4.2 % / 0.780, 0.488 (real shadows become feet); no shadow test 0.768 / 0.257 / 8.7 %.
    # 0.6 is better on PETS09, but fitted on that one clip (the only labelled one here, none to leave
    # out): the default stays OpenCV's until another clip confirms it (docs/groups_pets.md).
    shadow_threshold: float = 0.5
    open_px: int = 3  # opening that drops isolated noisy pixels
    close_px: int = 5  # closing that joins a person's parts (legs, torso) into one region
    min_area_px: int = 60  # regions smaller than this are noise, not a person (before any depth)
    # EKF sigma_d with this depth source: the virtual disparity is the foot's rows below the horizon
    # (the virtual baseline is the camera's height), so its noise is the foot row's jitter in pixels
    sigma_foot_px: float = 3.0
    # A region whose foot, moved sigma_foot_px rows up or down, lands farther than this on the ground
    # (half the distance between the two) is left out: far from the camera a pixel spans metres of
    # ground and its depth could not tell people grouping.radius_m apart (ours; 1.0 m = that radius)
    max_foot_error_m: float = 1.0
    # Where a region's pixels stand: "box" (its box's bottom-centre: one distance for the region) or
    # "column" (the region's lowest pixel in the columns within column_m / 2 of the pixel's own, the
    # width taken at the region's distance: people side by side at different distances stand apart; a
    # shoulder width, 0.5 m, bridges the gap between one person's legs). PETS09: person coverage /
    # wrong measured rows / group MOTA 0.826 / 3.6 % / 0.71 with "box", 0.863 / 3.1 % / 0.79 with
    # "column" (0.3 m: 0.844 / 5.1 % / 0.73; 0.8 m: 0.838 / 3.7 % / 0.73); docs/groups_pets.md
    foot: str = "column"
    column_m: float = 0.5
    # Ours (issue 34): with the column foot, each column is checked against a standing person. A column
    # whose top stands under min_stature_m over its foot, with MOG2's shadow over most of the rows where
    # its feet would be (legs as dark as a shadow) or ending at the picture's bottom edge, has its feet
    # missing: it stands where a person stature_m tall has their head at its top (without such a reason
    # the foot stays: a head and torso faded into the background). In a column over max_stature_m above
    # its foot, the pixels above a stature_m person's head are someone behind: placed by the same rule.
    # Adults' statures, not fitted: 1.7 m the mean, 1.4 and 2.0 m beyond the shortest and tallest.
    # PETS09 with grouping.connected and tracks.ground_coast_sigma_m: person coverage 0.864 -> 0.919,
    # people >= 80 % 14 -> 18, wrong measured rows 3.5 -> 1.8 % (docs/groups_pets.md)
    stature_check: bool = True
    stature_m: float = 1.7
    min_stature_m: float = 1.4
    max_stature_m: float = 2.0
    # Points needed to start a group with this depth source (grouping.min_points with stereo). A person
    # far from one 480x360 camera is some 20 x 50 px and carries a dozen corners; 12 started most
    # groups late or never (PETS09: person coverage 0.59), 8 covers 0.75 and 6 0.83 (docs/groups_pets.md)
    min_points: int = 6

    def __post_init__(self) -> None:
        if not (self.history_s > 0 and self.var_threshold > 0 and self.sigma_foot_px > 0 and self.max_foot_error_m > 0):
            raise ValueError("ground.history_s, ground.var_threshold, ground.sigma_foot_px and ground.max_foot_error_m "
                             "must be positive")
        if not 0.0 < self.shadow_threshold < 1.0:
            raise ValueError("ground.shadow_threshold must be in (0, 1)")
        if not 0.0 < self.background_ratio <= 1.0:
            raise ValueError("ground.background_ratio must be in (0, 1]")
        if self.foot not in ("box", "column") or not self.column_m >= 0:
            raise ValueError("ground.foot must be \"box\" or \"column\" and ground.column_m >= 0")
        if self.open_px < 0 or self.close_px < 0 or self.min_area_px < 1 or self.min_points < 1:
            raise ValueError("ground.open_px and ground.close_px must be >= 0, ground.min_area_px and ground.min_points >= 1")
        if not 0.0 < self.min_stature_m <= self.stature_m <= self.max_stature_m:
            raise ValueError("ground statures must be 0 < min_stature_m <= stature_m <= max_stature_m (m)")


@dataclass(frozen=True)
class TrackConfig:
    max_empty_frames: int = 12  # deleted after this many consecutive frames without an update (0.25 s at 48 fps)
    # Ours (issue 34), one camera over a ground plane only: a group without an update coasts while its EKF
    # still places it on the ground to within this standard deviation (largest axis) and is deleted once
    # it does not, in place of max_empty_frames. 0.5 m: two sigmas are the grouping radius (1 m), beyond
    # which the coasting group could as well be a person beside it (0 = max_empty_frames, as with stereo).
    # PETS09 (10 fps: max_empty_frames 3): person coverage 0.900 -> 0.919, group
    # IDF1 0.564 -> 0.700, ID switches 38 -> 20 (docs/groups_pets.md)
    ground_coast_sigma_m: float = 0.5

    def __post_init__(self) -> None:
        if not self.ground_coast_sigma_m >= 0.0:
            raise ValueError("tracks.ground_coast_sigma_m must be >= 0 m (0: tracks.max_empty_frames)")

    @property
    def lifecycle(self) -> LifecycleConfig:
        """The groups' life (trackers.lifecycle): deleted on the (max_empty_frames + 1)-th frame in a row without an update."""
        return LifecycleConfig(lost_after=self.max_empty_frames + 1)


@dataclass(frozen=True)
class GroupsConfig:
    """Parameters of the group tracker (seed 003); per-frame values at ``rate_hz``, rescaled to the log's rate."""

    background: BackgroundConfig = field(default_factory=BackgroundConfig)
    stereo: StereoConfig = field(default_factory=StereoConfig)
    klt: KltConfig = field(default_factory=KltConfig)
    ekf: EkfConfig = field(default_factory=EkfConfig)
    association: AssociationConfig = field(default_factory=AssociationConfig)
    grouping: GroupingConfig = field(default_factory=GroupingConfig)
    merge: MergeConfig = field(default_factory=MergeConfig)
    tracks: TrackConfig = field(default_factory=TrackConfig)
    ground: GroundConfig = field(default_factory=GroundConfig)
    rate_hz: float = 48.0  # the frame rate the per-frame values (frame counts, m/frame) are given at
    scale_with_rate: bool = True  # rescale them to the log's frame rate (off: use them as they are)

    def at_rate(self, fps: float) -> GroupsConfig:
        """This config with every per-frame value rescaled from ``rate_hz`` to ``fps`` (itself when
        ``scale_with_rate`` is off or the rates agree to 0.1 %)."""
        if not self.scale_with_rate or not np.isfinite(fps) or fps <= 0 or abs(fps / self.rate_hz - 1.0) < 1e-3:
            return self
        s = fps / self.rate_hz  # frames at fps per frame at rate_hz

        def frames(n: int, lo: int) -> int:
            return max(lo, int(np.floor(n * s + 0.5)))

        return replace(
            self,
            klt=replace(self.klt, window=frames(self.klt.window, 2)),
            # the same continuous white-noise acceleration (spectral density q = a² dt, m²/s³): per frame
            # the velocity variance grows by a² dt² (m/s)², so a ∝ dt^-1/2 and a dt² (m/frame²) ∝ dt^1.5
            ekf=replace(self.ekf, accel_sigma=self.ekf.accel_sigma / s**1.5, init_velocity_sigma=self.ekf.init_velocity_sigma / s),
            association=replace(self.association, alpha_s=float(self.association.alpha_s ** (1.0 / s))),
            merge=replace(self.merge, frames=frames(self.merge.frames, 1)),
            tracks=replace(self.tracks, max_empty_frames=frames(self.tracks.max_empty_frames, 0)),
            rate_hz=float(fps),
        )

    def __post_init__(self) -> None:
        if self.klt.window < 2:
            raise ValueError("klt.window must be at least 2 frames (a velocity needs two positions)")
        if self.association.min_points < 1 or self.grouping.min_points < 1:
            raise ValueError("association.min_points and grouping.min_points must be at least 1")
        if not 0.0 <= self.association.alpha_s <= 1.0:
            raise ValueError("association.alpha_s must be in [0, 1]")
        if not (np.isfinite(self.rate_hz) and 0 < self.rate_hz <= 100_000):
            raise ValueError("rate_hz must be a positive frame rate of at most 100000")
        # a review: each of these gave an empty trajectory, exit 0 (or, rate_hz 1e300, a division by zero)
        if not (np.isfinite(self.grouping.radius_m) and self.grouping.radius_m > 0):
            raise ValueError("grouping.radius_m must be a positive distance (m)")
        if not 0.0 <= self.merge.keep_id_share <= 1.0:
            raise ValueError("merge.keep_id_share must be in [0, 1]")
        if not 0.0 <= self.background.threshold <= 255.0:
            raise ValueError("background.threshold must be in [0, 255] grey levels")
