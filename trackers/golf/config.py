"""Parameters of the golf-ball tracker (seed 000).

The paper gives N = 1000 particles and the form of every step but no numeric value for
sigma, alpha, the noise or the gates; the defaults below are ours and are explained per field.
Pixel quantities are for a 1080-line frame and are scaled by ``image height / reference_height``
at run time, so the same config suits 720p and 1080p.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class GolfConfig:
    # --- particle filter (paper §2.2, eq. (1)-(3)) ---------------------------------------------
    n_particles: int = 1000  # paper: N = 1000
    sigma_px: float = 6.0  # eq. (2) sigma: about one ball diameter at broadcast zoom
    # eq. (2) alpha: likelihood floor far from every candidate. With sigma = 6 the Gaussian peak is
    # 1/(sqrt(2 pi) sigma) = 0.066; alpha = 0.002 (3 % of it) keeps far particles alive without
    # flattening the weights (the printed "1 +" would make the weights almost uniform).
    alpha: float = 0.002
    process_noise_pos_px: float = 2.0  # eq. (1) G w: position part of w, px
    process_noise_vel_px: float = 1.5  # eq. (1) G w: velocity part of w, px/frame
    init_spread_px: float = 4.0  # particle spread around the marked start box
    init_velocity_spread_px: float = 10.0  # unknown at the start: the first frames pick the velocity out
    miss_velocity_damping: float = 0.85  # per frame without a ball the sample velocities decay: no drift when lost
    # --- search region I_s (§2.1) from the particle spread (§2.2, last paragraph) ------------
    search_sigmas: float = 3.0  # region half-size = search_sigmas * particle std + ball diameter
    search_min_px: float = 64.0
    search_max_px: float = 480.0
    # --- colour LUTs (§2.1) ---------------------------------------------------------------------
    lut_bin: int = 4  # LUT histograms are collected at 256/lut_bin levels per axis, then expanded to 256^3
    lut_smooth_bins: float = 1.0  # Gaussian smoothing of both colour histograms, in bins
    # A colour is "ball" where weight x ball count > background count (counts, so the prior that a
    # marked ball has ~10-100 px and its frame ~10^6 is kept; 1000 lets a colour through when the
    # ball owns more than ~1/1000 of it: a 2-3 px ball over sky shares colours with cloud edges).
    lut_ball_weight: float = 1000.0
    lut_min_count: float = 0.02  # ... and the smoothed ball count is above this
    lut_core: float = 0.8  # ball samples: the ellipse inscribed in the marked box, shrunk by this
    lut_background_margin: float = 1.5  # background: the whole frame minus the box grown by this
    lut_background_stride: int = 2  # subsample background pixels (speed; the LUT is smoothed anyway)
    lut_context: float = 4.0  # reference luminance histogram: window this many box sizes, min search_min_px
    lut_hist_bins: int = 32  # context luminance histogram bins
    lut_switch_margin: float = 0.2  # hysteresis: switch when the other LUT fits 60 % of the region
    # --- blob gating (§2.1) -----------------------------------------------------------------------
    min_area_px: float = 2.0  # below this a blob is noise ("tiny"); at reference height
    area_tolerance: float = 3.0  # accept target/tol <= area <= target*tol ...
    area_slack_px: float = 4.0  # ... on areas plus this (a 1 px vs 3 px blob of a tiny ball is no real difference)
    circularity_tolerance: float = 0.35  # reject circularity < target - tol (rounder is never rejected)
    target_rate: float = 0.3  # EMA rate of the targets from past selected blobs (follows zoom)
    initial_circularity: float = 0.9
    widen_per_miss: float = 0.25  # the area gate (log tolerance) grows by this per frame without a ball...
    widen_max: float = 3.0  # ...up to this factor (3: a ball 27x smaller or larger than the target)
    max_blobs: int = 48  # blobs measured per frame (the nearest to the prediction); others "excess"
    # --- track status -------------------------------------------------------------------------
    max_predicted_frames: int = 5  # misses reported as "predicted" before the track is "lost"
    # While lost: "centre" = the samples are spread over the middle of the picture each frame (a
    # broadcast operator keeps following the ball, so it is most likely there; the search region is
    # then the largest allowed); "stay" = they keep diffusing where the ball was last predicted.
    lost_search: str = "centre"
    # --- 3-D EKF and landing (§2.3) ---------------------------------------------------------------
    ball_diameter_m: float = 0.04267
    gravity: float = 9.81
    drag_k: float = 0.0047  # quadratic drag rho*Cd*A/(2m) of a golf ball, 1/m (0 = vacuum)
    ekf_accel_noise: float = 8.0  # m/s^2, absorbs lift, wind and drag error
    ekf_pixel_sigma: float = 1.5  # px, image position measurement
    photometric_area: bool = True  # range from the light the ball adds, not its silhouette's pixel count
    ekf_range_rel_sigma: float = 0.1  # relative range error from the area, plus blob-size term
    ekf_init_velocity_sigma: float = 40.0  # m/s
    landing_reinit: bool = True  # paper §2.3; False = never re-initialise at a predicted landing (for comparison)
    landing_arm_height_m: float = 2.0  # a landing fires only after the EKF saw the ball this high
    landing_horizon_s: float = 12.0
    landing_step_s: float = 0.02
    restitution: float = 0.4  # EKF after the bounce: vertical speed *= -restitution
    bounce_friction: float = 0.7  # ... horizontal speed *= this
    reinit_min_sigma_px: float = 12.0  # particle spread after a landing re-initialisation
    reinit_velocity_sigma_px: float = 8.0
    # With encoders, move the samples by each pose change (they then live in camera-independent
    # directions). Off by default: the operator keeps the ball nearly still in the picture, which the
    # paper's image-space constant-velocity model predicts well, while the ball's angular velocity
    # (what is left after compensation) changes faster than the velocity noise lets the samples
    # follow. On the synthetic broadcast shots off scored 0.81-0.86 within 5 px, on 0.65-0.83.
    compensate_camera_motion: bool = False
    # --- landing without encoders (image-space parabola) ------------------------------------------
    image_landing_history: int = 12  # measurements used for the parabola
    image_landing_misses: int = 2  # re-initialise after this many misses while descending
    # --- output -----------------------------------------------------------------------------------
    trail_length: int = 600
    reference_height: int = 1080

    def __post_init__(self) -> None:
        if self.n_particles < 1:
            raise ValueError("n_particles must be at least 1")
        if self.sigma_px <= 0 or self.alpha < 0:
            raise ValueError("sigma_px must be positive and alpha non-negative")
        if self.lut_bin < 1 or 256 % self.lut_bin:
            raise ValueError("lut_bin must divide 256")
        if not 0 < self.search_min_px <= self.search_max_px:
            raise ValueError("need 0 < search_min_px <= search_max_px")
        if self.area_tolerance <= 1:
            raise ValueError("area_tolerance must exceed 1")
        if self.lost_search not in ("centre", "stay"):
            raise ValueError("lost_search must be 'centre' or 'stay'")
        if not 0 < self.target_rate <= 1:
            raise ValueError("target_rate must be in (0, 1]")
