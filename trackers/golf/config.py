"""Parameters of the golf-ball tracker (seed 000), one frozen table per stage.

The paper gives N = 1000 particles and the form of every step but no numeric value for
sigma, alpha, the noise or the gates; the defaults below are ours and are explained per field.
Pixel quantities are for a 1080-line frame and are scaled by ``image height / reference_height``
at run time, so the same config suits 720p and 1080p; by the marked ball's diameter over
``reference_ball_px`` instead when that is larger (a ball big for its frame moves as far, in its
own diameters, as the reference ball does).

TOML (every table and key optional; ``trackreplay replay LOG --tracker golf --config golf.toml``)::

    [golf]
    max_predicted_frames = 5
    [golf.particles]
    n = 1000
    sigma_px = 6.0
    [golf.lut]
    ball_weight = 1000.0
    [golf.reinit]
    landing = true
    lost = "centre"

Each stage receives only its own table (plus a plain number where it needs another's, e.g. the
ball diameter); the tracker is the only holder of the whole config.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from trackreplay.trackers.golf.ball_flight import GRAVITY, BallModel
from trackreplay.trackers.lifecycle import LifecycleConfig

_BALL = BallModel()  # the regulation ball: the EKF's physical constants


@dataclass(frozen=True)
class ParticleConfig:
    """CONDENSATION (§2.2, eqs. (1)-(3)); ``[golf.particles]``."""

    n: int = 1000  # paper: N = 1000
    sigma_px: float = 6.0  # eq. (2) sigma: about one ball diameter at broadcast zoom
    # eq. (2) alpha: likelihood floor far from every candidate. With sigma = 6 the Gaussian peak is
    # 1/(sqrt(2 pi) sigma) = 0.066; alpha = 0.002 (3 % of it) keeps far particles alive without
    # flattening the weights (the printed "1 +" would make the weights almost uniform).
    alpha: float = 0.002
    noise_pos_px: float = 2.0  # eq. (1) G w: position part of w, px
    noise_vel_px: float = 1.5  # eq. (1) G w: velocity part of w, px/frame
    init_spread_px: float = 4.0  # particle spread around the marked start box
    init_velocity_spread_px: float = 10.0  # unknown at the start: the first frames pick the velocity out
    # eq. (1) mixed state (ours): while a following camera holds the ball, this share of the
    # samples is given velocity 0 each frame, so the cloud keeps a hypothesis where the ball stops
    # or turns in the image (the operator catching up); never in a fixed view (particles.motion)
    stop_share: float = 0.1
    # Ours (ICONDENSATION-like): on a measured frame this share of the samples is drawn around the
    # measured blob (velocity: the step from the last measured frame), so the cloud follows an
    # image acceleration its constant-velocity noise cannot (the eq. (2) weights alone cannot pull
    # a cloud that has no sample near the blob).
    detection_share: float = 0.1
    # Ours: a ball seen lying still (rest_frames frames within rest_px) and then missed was struck:
    # the samples' velocities (and the missed frame's step) are spread by this (px/frame), so the
    # search region and gate open to where it can have flown (an iron: ~60 px/frame at 1280 lines)
    launch_velocity_px: float = 40.0
    rest_frames: int = 2
    rest_px: float = 1.5
    rest_roundness: float = 0.8  # ... or seen on its marked frame only, at least this round (no motion blur: a streak 2.5x as long as wide is ~0.8)
    # ... unless the ball is a speck, under this area (px, not scaled: a blob under a 2x2 block has no
    # shape). A far ball rolling along the line of sight looks still without lying still, and a strike's
    # wide search finds only other specks that fit a 1-3 px target as well as it does (a 240 fps shot:
    # 25-45 px off, "measured").
    strike_min_area_px: float = 4.0
    miss_velocity_damping: float = 0.85  # per frame without a ball the sample velocities decay: no drift when lost
    # With encoders, move the samples by each pose change (they then live in camera-independent
    # directions). Off by default: the operator keeps the ball nearly still in the picture, which the
    # paper's image-space constant-velocity model predicts well, while the ball's angular velocity
    # (what is left after compensation) changes faster than the velocity noise lets the samples
    # follow. On the synthetic broadcast shots off scored 0.81-0.86 within 5 px, on 0.65-0.83.
    compensate_camera_motion: bool = False

    def __post_init__(self) -> None:
        if self.n < 1:
            raise ValueError("particles.n must be at least 1")
        if self.sigma_px <= 0 or self.alpha < 0:
            raise ValueError("particles.sigma_px must be positive and particles.alpha non-negative")
        if self.rest_roundness < 0:
            raise ValueError("particles.rest_roundness must be >= 0 (above 1: a single sighting never counts as at rest)")
        if not self.strike_min_area_px >= 0:
            raise ValueError("particles.strike_min_area_px must be >= 0 (0: a ball of any size may be struck)")


@dataclass(frozen=True)
class SearchConfig:
    """The search region I_s (§2.1), sized by the particle spread (§2.2, last paragraph); ``[golf.search]``."""

    sigmas: float = 3.0  # region half-size = sigmas * particle std + ball diameter
    min_px: float = 64.0
    max_px: float = 480.0

    def __post_init__(self) -> None:
        if not 0 < self.min_px <= self.max_px:
            raise ValueError("need 0 < search.min_px <= search.max_px")


@dataclass(frozen=True)
class LutConfig:
    """The sky and ground colour LUTs (§2.1); ``[golf.lut]``."""

    bin: int = 4  # LUT histograms are collected at 256/bin levels per axis, then expanded to 256^3
    smooth_bins: float = 1.0  # Gaussian smoothing of both colour histograms, in bins
    # A colour is "ball" where weight x ball count > background count (counts, so the prior that a
    # marked ball has ~10-100 px and its frame ~10^6 is kept; 1000 lets a colour through when the
    # ball owns more than ~1/1000 of it: a 2-3 px ball over sky shares colours with cloud edges).
    ball_weight: float = 1000.0
    min_count: float = 0.02  # ... and the smoothed ball count is above this
    core: float = 0.8  # ball samples: the ellipse inscribed in the marked box, shrunk by this
    background_margin: float = 1.5  # background: the whole frame minus the box grown by this
    # The ring round a user's box (inside the box grown by this, outside the background_margin one): a
    # colour denser there than in the box's ball samples is what the ball lies on, not the ball's
    # (:func:`.lut.separable_from_ring`). 3 (twice the guard): local, yet a sample of the surroundings
    # 6.75 times the box's area. Not tuned: the one value tried. <= background_margin: off (as before).
    ring_margin: float = 3.0
    background_stride: int = 2  # subsample background pixels (speed; the LUT is smoothed anyway)
    context: float = 4.0  # reference luminance histogram: window this many box sizes, min search.min_px
    hist_bins: int = 32  # context luminance histogram bins
    switch_margin: float = 0.2  # hysteresis: switch when the other LUT fits 60 % of the region
    # The other LUT is tried on a miss (the background changed under the ball faster than the switch)
    # only where its own background is at least this share of I_s: the ground LUT over open sky passes
    # cloud puffs, and a 2 px ball among them was "measured" on one 30 px away.
    other_min_share: float = 0.05
    # Over open sky a small ball's blurred rim mixes with the sky, so the sky LUT keeps scattered core pixels: on the
    # synthetic shots its blob was a quarter of the ball's area, in pieces on a third of the frames
    # (the ground LUT: 1.3x, 0.5 %), so the area target shrank and the whole ball was refused as
    # too large once the ground LUT took over. Not the ground's: the clutter beside a ball on the
    # ground (a cup's liner) would join it.
    sky_close_px: int = 3  # ours: the sky silhouette closed with a square this wide (px; 0 or 1: off)
    # Learning from the track (ours): a confidently measured ball is added to the LUT of the
    # background it is over when that LUT does not exist yet, or when the ball's area changed by
    # this factor since that LUT last learned it (zoom); at most ``learn_max`` boxes per LUT.
    learn_confidence: float = 0.5
    learn_area_factor: float = 2.0
    learn_max: int = 6

    def __post_init__(self) -> None:
        if self.bin < 1 or 256 % self.bin:
            raise ValueError("lut.bin must divide 256")
        if not 0 <= self.other_min_share <= 1:
            raise ValueError("lut.other_min_share must be in [0, 1]")
        if self.sky_close_px < 0:
            raise ValueError("lut.sky_close_px must be >= 0 (0: the sky silhouette as the LUT gives it)")
        if self.hist_bins < 2 or self.background_stride < 1 or self.learn_max < 0:
            raise ValueError("lut.hist_bins must be >= 2, lut.background_stride >= 1 and lut.learn_max >= 0")
        if min(self.smooth_bins, self.min_count, self.background_margin, self.context) < 0 or not 0 < self.core <= 1:
            raise ValueError("lut.smooth_bins, min_count, background_margin and context must be >= 0, 0 < lut.core <= 1")
        if not 0 <= self.ring_margin < float("inf"):
            raise ValueError("lut.ring_margin must be a finite number >= 0 (at most lut.background_margin: no ring)")


@dataclass(frozen=True)
class ContrastConfig:
    """Ours: the fallback detector when neither LUT finds the ball near the prediction
    (:func:`~trackreplay.trackers.golf.silhouette.contrast_silhouette`); ``[golf.contrast]``."""

    enabled: bool = True
    min_contrast: float = 40.0  # luminance levels above the local background (a white ball on blue sky: ~90)
    noise_sigmas: float = 6.0  # ... and this many robust sigmas of the region's top-hat
    kernel_diameters: float = 3.0  # the opening's disc, in ball diameters (the background is what is wider)
    max_kernel_px: float = 61.0  # ... at most this wide (reference height)
    # With encoders (silhouette.moving_silhouette): the previous frame brought into this pose lines
    # up everything fixed in the world; a pixel brighter now than every pixel within
    # registration_px of its place before is moving. Clutter gone, a lower contrast is enough.
    moving: bool = True
    moving_min_contrast: float = 15.0  # levels (a 2 px ball against sky: +20 to +50 once its blur is shorter than ~10 px)
    registration_px: float = 2.0  # pose error tolerated (encoder noise and quantisation, rolling shutter)

    def __post_init__(self) -> None:
        if self.min_contrast <= 0 or self.kernel_diameters <= 1:
            raise ValueError("contrast: need min_contrast > 0 and kernel_diameters > 1")


@dataclass(frozen=True)
class BlobConfig:
    """Blob gating on area and circularity against targets from past balls (§2.1); ``[golf.blobs]``."""

    min_area_px: float = 2.0  # below this a blob is noise ("tiny"); at reference height
    area_tolerance: float = 3.0  # accept target/tol <= area <= target*tol ...
    area_slack_px: float = 4.0  # ... on areas plus this (a 1 px vs 3 px blob of a tiny ball is no real difference)
    circularity_tolerance: float = 0.35  # reject roundness < target - tol (rounder is never rejected)
    shape_area_px: float = 30.0  # below this many pixels (not scaled) the tolerance grows as sqrt(30 / area)
    target_rate: float = 0.3  # EMA rate of the targets from past selected blobs (follows zoom)
    # ... but a smaller blob moves the target area at this rate: a silhouette loses part of the ball (its
    # shaded side, its blurred rim, all but a highlight) far more often than the ball's image shrinks
    # that fast, and a target that follows such pieces down lets smaller pieces through next (on the
    # approach clip at 3/4 resolution the target area fell from 11 to 2 px² while the ball's grew past 200,
    # then specks by the hole were `measured` after the ball dropped). None (Python only; in TOML give target_rate): target_rate.
    target_shrink_rate: float | None = 0.15  # ... the area, towards a smaller blob, at this rate (pieces of the ball)
    initial_circularity: float = 0.9
    widen_per_miss: float = 0.25  # the area gate (log tolerance) grows by this per frame without a ball...
    widen_max: float = 3.0  # ...up to this factor (3: a ball 27x smaller or larger than the target)
    # Once lost the targets are stale (the ball receded or came closer, the lens zoomed): the area
    # gate opens this far (6: 729x) and a candidate must instead be confirmed over several frames
    # whose blobs agree with one another (validate.track_fit).
    widen_lost: float = 6.0
    max_blobs: int = 48  # blobs measured per frame (the nearest to the prediction); others "excess"
    # Shape against motion (blobs.streak_excess): a blob may be as long as the ball's streak at the
    # predicted speed plus streak_sigmas of its uncertainty, with streak_slack_px of edge blur, and
    # streak_tolerance more (a lit ball's silhouette may miss its shaded side: 20x14 px on a green).
    streak_sigmas: float = 3.0
    streak_slack_px: float = 1.0
    streak_tolerance: float = 0.6
    # Ours (golf.streak): a measured blob that is the bright end of a faint streak (a ball slowing
    # during the exposure) is measured at the whole streak's centre, the streak grown from the blob
    # over the top-hat at complete_streak of the blob's level (hysteresis), when no longer than the
    # predicted motion allows. 0: off (the blob's own centroid). Synthetic 1080p shot: RMSE 1.53 -> 1.25 px.
    complete_streak: float = 0.35

    def __post_init__(self) -> None:
        if not 0.0 <= self.complete_streak < 1.0:
            raise ValueError("blobs.complete_streak must be in [0, 1) (0: off)")
        if self.area_tolerance <= 1:
            raise ValueError("blobs.area_tolerance must exceed 1")
        if not 0 < self.target_rate <= 1 or not (self.target_shrink_rate is None or 0 < self.target_shrink_rate <= 1):
            raise ValueError("blobs.target_rate and blobs.target_shrink_rate must be in (0, 1]")
        if self.target_shrink_rate is not None and self.target_shrink_rate > self.target_rate:
            raise ValueError(f"blobs.target_shrink_rate ({self.target_shrink_rate:g}) must not exceed blobs.target_rate "
                             f"({self.target_rate:g}): a smaller blob is more often a piece of the ball than the ball shrinking; "
                             "set it to target_rate to move the target at one rate both ways")
        if min(self.min_area_px, self.area_slack_px, self.shape_area_px, self.circularity_tolerance) < 0 or self.max_blobs < 1:
            raise ValueError("blobs.min_area_px, area_slack_px, shape_area_px and circularity_tolerance must be >= 0, "
                             "blobs.max_blobs >= 1")


@dataclass(frozen=True)
class SnapConfig:
    """Each marked box placed on the bright ball drawn round (ours, :mod:`.snap`); ``[golf.snap]``."""

    enabled: bool = True  # False: the boxes as drawn (the paper: a box that fits the ball)
    window: float = 2.0  # the box's surroundings: a window this many times its size
    min_contrast: float = 12.0  # the box's brightest pixel above the window's median luminance (levels)
    # The ball: pixels above the median plus this share of the way to that brightest pixel. A quarter:
    # a small ball's blur is most of it (half the way keeps only its core: 3x4 px of a 6x6 px ball).
    level: float = 0.25
    min_fill: float = 0.5  # the ball's blob fills at least this of its bounding box ...
    max_aspect: float = 2.0  # ... which is at most this elongated (a still or slow ball)
    min_area_px: float = 4.0  # ... and has at least this many pixels (one pixel has no size)
    slack_px: float = 2.0  # a box is loose when its samples' ellipse is wider than the ball's blob by more (frame pixels): a pixel of blurred rim each side
    keep_px: float = 1.0  # a drawn centre within this of the ball's stays (frame pixels: a box's corners are integers)

    def __post_init__(self) -> None:
        if (self.window <= 1 or self.min_contrast <= 0 or not 0 < self.level < 1 or not 0 <= self.min_fill <= 1
                or self.max_aspect < 1 or self.min_area_px < 1 or self.slack_px < 0 or self.keep_px < 0):
            raise ValueError("snap: need window > 1, min_contrast > 0, 0 < level < 1, 0 <= min_fill <= 1, max_aspect >= 1, "
                             "min_area_px >= 1, slack_px >= 0, keep_px >= 0")


@dataclass(frozen=True)
class ValidateConfig:
    """Honest status (ours, :mod:`.validate`): the motion-model gate, the confidence that makes a
    row ``measured``, and the evidence a jump needs; ``[golf.validate]``."""

    gate_sigmas: float = 3.0  # gate radius = this x (cloud spread + ball radius)
    max_spread_px: float = 40.0  # the cloud spread the gate uses is capped here (reference height)
    min_confidence: float = 0.25  # below this the row is "predicted" (about 1.7 s off with a perfect fit)
    min_fit: float = 0.4  # ... and below this shape/area fit alone, however close to the prediction (0.4: area ~4x off, or not round)
    confirm_frames: int = 3  # a blob outside the gate (or after a loss) must be seen this many frames running
    confirm_px: float = 12.0  # ... each within this (+ a diameter) of the previous ones' extrapolation
    # ... but the second within this (+ a diameter) of the first: the speed is not known yet (a ball
    # falling back into the picture after a hop moves 30-110 px a frame at 720p)
    confirm_first_step_px: float = 120.0
    max_tentative: int = 16  # tentative tracks kept at once (longest first, then nearest the prediction)
    entry_margin_px: float = 24.0  # fixed camera, ball gone out of the picture: a new track starts this near the edge
    confirm_min_area_px: float = 2.0  # ... each blob of at least this many pixels (not scaled: one pixel has no shape)
    confirm_fit: float = 0.5  # ... and agree with each other in area and be round (validate.track_fit) at least this well
    # ... and, with encoders and a 3-D filter running, not put the ball (range from the blobs' area) more
    # than this many times nearer than the filter's range less 3 sigma (0: off). A cloud puff is tens
    # of px: a ball that size would be a few metres from the lens.
    confirm_max_nearer: float = 2.0
    # ... and not be something that was already there, beside the ball, on the frame where the ball was
    # last measured (seen_before.py: the cup's liner the ball dropped into). False: off.
    confirm_not_seen_before: bool = True
    # Still scenery (scenery.py): a blob within this of where a blob was the frame before, seen while the
    # ball was measured elsewhere, is refused while it stays (reference height; 0: off). Centroids of
    # a still object move 0.1-0.5 px between frames (noise, JPEG).
    still_px: float = 1.5

    def __post_init__(self) -> None:
        if self.confirm_frames < 1 or self.gate_sigmas <= 0 or not 0 <= self.min_confidence <= 1 or not 0 <= self.min_fit <= 1:
            raise ValueError("validate: need confirm_frames >= 1, gate_sigmas > 0, 0 <= min_confidence <= 1, 0 <= min_fit <= 1")
        if self.still_px < 0:
            raise ValueError("validate.still_px must be >= 0 (0: no still scenery)")
        if self.confirm_max_nearer != 0 and not self.confirm_max_nearer >= 1:
            raise ValueError("validate.confirm_max_nearer must be 0 (off) or >= 1")


@dataclass(frozen=True)
class EkfConfig:
    """The 3-D ballistic EKF that predicts the landing (§2.3); ``[golf.ekf]``."""

    gravity: float = GRAVITY  # (B1) of the shared ball model (ball_flight)
    # (B1)'s quadratic drag k C_d = rho*Cd*A/(2m) of the regulation ball (ball_flight.BallModel: 0.00467), to
    # two figures: 0.0047 1/m (0 = vacuum)
    drag_k: float = round(_BALL.k * _BALL.drag_cd, 4)
    accel_noise: float = 8.0  # m/s^2, absorbs lift, wind and drag error
    pixel_sigma: float = 1.5  # px, image position measurement
    init_velocity_sigma: float = 40.0  # m/s
    landing_arm_height_m: float = 2.0  # a landing fires only after the EKF saw the ball this high
    landing_horizon_s: float = 12.0
    landing_step_s: float = 0.02
    # A gap between frames longer than this is a restart, not a flight to integrate: the filter
    # forgets the ball (and the tracker calls it lost) instead of sub-stepping across the gap
    # (a 1-day gap would be 5 million 1/60 s steps; a log time near 2**63 ns, forever).
    max_gap_s: float = 2.0
    restitution: float = _BALL.restitution  # after the bounce: vertical speed *= -restitution ((B4)'s e)
    bounce_friction: float = 0.7  # ... horizontal speed *= this


    def __post_init__(self) -> None:
        if not 0 < self.max_gap_s < 3600:
            raise ValueError("ekf.max_gap_s must be positive and under an hour")


@dataclass(frozen=True)
class RangeConfig:
    """Range from the ball's apparent area (the EKF's third measurement, §2.3); ``[golf.range]``."""

    photometric: bool = True  # area from the light the ball adds, not its silhouette's pixel count
    rel_sigma: float = 0.1  # relative range error from the area, plus a blob-size term
    # Ours: a ball the EKF has rolling on the ground (at contact height, |vertical speed| below
    # ground_vz) is ranged where its line of sight meets the ground, to this relative error (a flat
    # course: a 0.3 m rise 150 m out is ~5 % of a 2.5 m camera height... hence not tighter)
    ground_vz: float = 0.5
    ground_sigma: float = 0.05


@dataclass(frozen=True)
class ReinitConfig:
    """Where the particles start again (§2.3 and ours); ``[golf.reinit]``."""

    landing: bool = True  # paper §2.3: at the EKF's predicted landing (False: never, for comparison)
    # Ours: for this many frames after the EKF's predicted landing, a ball missed on the frame before is
    # searched for around the 3-D filter's own prediction (it bounces at every contact; the image motion
    # model cannot follow a bounce), spread as the filter's uncertainty there; a landing predicted while
    # the ball is being measured (found on the frame before) re-initialises nothing then: the contact
    # can be a frame or more early (tens of metres at the landing's grazing angle), and samples moved
    # to it miss a ball still found where it is (seed 0's shot: a 0.4 px blob refused, the contact 52 px
    # off). 0: the paper alone, at the contact point at once.
    after_landing_frames: int = 30
    min_sigma_px: float = 12.0  # particle spread after a landing re-initialisation
    velocity_sigma_px: float = 8.0
    # Without encoders: an image-space parabola through the last measurements.
    parabola_history: int = 12  # measurements used for the parabola
    parabola_misses: int = 2  # re-initialise after this many misses while descending
    # While lost: "centre" = the samples are spread over the middle of the picture each frame (a
    # broadcast operator keeps following the ball, so it is most likely there; the search region is
    # then the largest allowed); "stay" = they keep diffusing where the ball was last predicted;
    # "auto" = "centre" when the camera was following the ball (encoders, or the last measurements
    # within the central half of the picture), else "stay" (a fixed camera: the ball crosses it).
    lost: str = "auto"

    def __post_init__(self) -> None:
        if self.after_landing_frames < 0:
            raise ValueError("reinit.after_landing_frames must be >= 0")
        if self.parabola_history < 3 or self.parabola_misses < 1 or self.min_sigma_px <= 0:
            raise ValueError("reinit.parabola_history must be >= 3 (a parabola), parabola_misses >= 1, min_sigma_px > 0")
        if self.lost not in ("centre", "stay", "auto"):
            raise ValueError("reinit.lost must be 'centre', 'stay' or 'auto'")


@dataclass(frozen=True)
class WorldBehindConfig:
    """How many recent pictures make the world behind the ball, and how far a blob must stand out
    (:mod:`.world_behind`)."""

    frames: int = 6  # recent pictures kept (0: off)
    min_frames: int = 3  # pictures of the same view needed for a median (fewer: no judgement): half of frames
    # a recent picture whose median pixel (over small copies) changed by more than this many grey levels
    # is of another view (fixed views in the ball corpus: 0-1; a hand-held camera: 4-10)
    max_change: float = 2.0
    noise_sigmas: float = 6.0  # how far (robust σ of |Y - world| over the region) a blob must stand out

    def __post_init__(self) -> None:
        if self.frames < 0 or not 1 <= self.min_frames:
            raise ValueError("world_behind.frames must be >= 0 (0: off) and min_frames >= 1")
        if not self.max_change >= 0 or not self.noise_sigmas > 0:
            raise ValueError("world_behind.max_change must be >= 0 and noise_sigmas > 0")


@dataclass(frozen=True)
class GolfConfig:
    """The whole tracker: shared scalars here, one table per stage."""

    ball_diameter_m: float = _BALL.diameter  # the regulation ball (ball_flight.BallModel)
    max_predicted_frames: int = 5  # misses reported as "predicted" before the track is "lost" (no position)
    # The reported confidence is P(within 10 px), fitted on the ball corpus (trackers/golf/calibration.py);
    # False: the validation's own confidence (the shape fit times the motion term)
    calibrate: bool = True
    trail_length: int = 600  # past measurements kept for the drawn trajectory
    reference_height: int = 1080  # the frame height the pixel parameters are given for
    # ... and the ball diameter (px) they suit: a marked ball larger than this in a 1080-line frame
    # scales them by its own size instead (tee balls in the synthetic shots: 14-15 px; 0: height only)
    reference_ball_px: float = 16.0
    particles: ParticleConfig = field(default_factory=ParticleConfig)
    search: SearchConfig = field(default_factory=SearchConfig)
    lut: LutConfig = field(default_factory=LutConfig)
    contrast: ContrastConfig = field(default_factory=ContrastConfig)
    blobs: BlobConfig = field(default_factory=BlobConfig)
    ekf: EkfConfig = field(default_factory=EkfConfig)
    range: RangeConfig = field(default_factory=RangeConfig)
    reinit: ReinitConfig = field(default_factory=ReinitConfig)
    validate: ValidateConfig = field(default_factory=ValidateConfig)
    snap: SnapConfig = field(default_factory=SnapConfig)
    world_behind: WorldBehindConfig = field(default_factory=WorldBehindConfig)

    def __post_init__(self) -> None:
        if not self.reference_height > 0 or not self.reference_ball_px >= 0:
            raise ValueError("reference_height must be > 0 and reference_ball_px >= 0 (0: the height alone scales)")
        if self.max_predicted_frames < 0:
            raise ValueError("max_predicted_frames must be >= 0 (0: lost on the first miss)")

    @property
    def lifecycle(self) -> LifecycleConfig:
        """The track's life (trackers.lifecycle): "predicted" on up to max_predicted_frames misses in a row,
        "lost" on the next one. (A lost ball is found again by the validation's confirmed jump or a mark.)"""
        return LifecycleConfig(lost_after=self.max_predicted_frames + 1)
