"""Golf-ball tracker for tee-shot broadcast video (seed 000): ``GolfTracker``, name "golf".

Per frame (paper Fig. 1):

1. **Predict.** CONDENSATION select + predict (eq. (1)) in image coordinates (optionally, with
   encoders, after moving the samples by the pose change: ``compensate_camera_motion``). The 3-D
   EKF predicts too; when its prediction crosses the ground the samples are re-initialised around
   the projected contact point instead (§2.3). Without encoders the same happens from an
   image-space parabola once the ball is lost while descending. Once the ball has been missed for
   more than ``max_predicted_frames`` ("lost"), the samples are spread over the middle of the
   picture each frame (``lost_search``): the operator keeps following the ball.
2. **Search region** ``I_s``: centred on the predicted mean, size ``2 (k std + ball diameter)`` per
   axis from the samples' horizontal and vertical spread (so it grows while the ball is missed,
   §2.3), clamped, kept inside the frame.
3. **LUT switch** from the region's luminance histogram; **silhouette** ``I_c`` by one LUT lookup
   on the region's pixels.
4. **Blobs**: area and circularity gated against targets that follow past selected blobs; the
   accepted blob nearest to the prediction is the ball.
5. **Measure** (eq. (2)) with all accepted centroids, normalise, **estimate** (eq. (3)).
6. Outputs: the selected blob ("measured") or the estimate ("predicted", then "lost" without a
   position, for the export to interpolate, §2.1/SPEC 7); the line of sight through the reported
   pixel when the camera pose is known; X, Y, Z from the EKF, whose range measurement is the
   ball's photometric area calibrated on the marked ball at rest.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from trackreplay.schemas.records import InitRegion
from trackreplay.trackers.base import TrackState
from trackreplay.trackers.frame import Frame
from trackreplay.trackers.golf import blobs as B
from trackreplay.trackers.golf.config import GolfConfig
from trackreplay.trackers.golf.landing import BallisticEkf, image_parabola_landing, range_from_area, range_rel_sigma
from trackreplay.trackers.golf.lut import LUT_NAMES, LutSet, region_key, region_samples
from trackreplay.trackers.golf.particles import CondensationFilter
from trackreplay.trackers.golf.posed import PosedCamera, pose_homography
from trackreplay.trackers.golf.silhouette import crop_ycc, silhouette

NO_ENCODER_NOTICE = (
    "no PTZ encoder pose for this frame (no /ptz/encoders or lens table): tracking in image "
    "coordinates only - no lines of sight, no 3-D landing prediction; the bounce is caught from "
    "an image-space parabola instead"
)
ENCODER_GAP_NOTICE = (
    "some frames have no PTZ encoder pose (outside the encoders' coverage): those frames are "
    "tracked in image coordinates only, without lines of sight"
)
NO_HINTS_NOTICE = (
    "the log marks no ball (/annotations/init is empty): the golf tracker needs marked ball boxes "
    "to build its colour LUTs and start; nothing is tracked"
)
MAX_CALIBRATION_RANGE_M = 1000.0
NAN2 = np.full(2, np.nan)
NAN3 = np.full(3, np.nan)


@dataclass(frozen=True, eq=False)
class GolfIntermediates:
    """Everything one step computed, as plain numpy data (hashed into the replay digest)."""

    mode: str  # "ptz" (camera pose known), "image" (no encoders) or "idle" (not started)
    search_box: np.ndarray  # (4,) x0, y0, w, h of I_s in frame pixels
    lut_name: str  # the LUT applied ("sky" / "ground"; "" if none)
    lut_names: tuple[str, ...]
    lut_scores: np.ndarray  # (2,) share of I_s's luminance histogram per name in lut_names (NaN: not built)
    silhouette: np.ndarray  # (h, w) uint8 0/1, I_c inside I_s
    silhouette_offset: np.ndarray  # (2,) int64 top-left of the silhouette in the frame
    blobs: np.ndarray  # (K, 8) rows as blob_columns
    blob_columns: tuple[str, ...]
    blob_reasons: tuple[str, ...]  # reason code -> name
    selected: int  # row of the ball in blobs, -1 if none
    targets: np.ndarray  # (2,) target area (px) and circularity used for gating
    gate_widen: float
    particles: np.ndarray  # (N, 4) x, y, vx, vy after the measurement
    weights: np.ndarray  # (N,)
    predicted: np.ndarray  # (2,) predicted position (mean of the predicted samples)
    estimate: np.ndarray  # (4,) eq. (3)
    spread: np.ndarray  # (2,) weighted std of x and y
    ekf_x: np.ndarray  # (6,) world X, Y, Z, VX, VY, VZ (NaN before the EKF starts)
    ekf_P: np.ndarray  # (6, 6)
    ekf_nis: float
    landing_world: np.ndarray  # (3,) predicted ground contact (NaN if none)
    landing_image: np.ndarray  # (2,) ... projected into this frame
    landing_in_s: float  # seconds until that contact
    reinit: str  # "", "start", "ekf_landing", "image_parabola" or "lost_centre"
    reinit_point: np.ndarray  # (2,) where the samples were re-initialised
    trail_image: np.ndarray  # (K, 2) past measured positions drawn into this frame's pose
    trail_world: np.ndarray  # (K, 3) past EKF positions
    notice: str = ""


def _empty(mode: str, notice: str) -> GolfIntermediates:
    return GolfIntermediates(
        mode, np.zeros(4), "", LUT_NAMES, np.full(len(LUT_NAMES), np.nan), np.zeros((0, 0), np.uint8),
        np.zeros(2, np.int64), np.zeros((0, len(B.BLOB_COLUMNS))), B.BLOB_COLUMNS, B.REASONS, -1, NAN2,
        1.0, np.zeros((0, 4)), np.zeros(0), NAN2, np.full(4, np.nan), NAN2, np.full(6, np.nan),
        np.full((6, 6), np.nan), math.nan, NAN3, NAN2, math.nan, "", NAN2, np.zeros((0, 2)), np.zeros((0, 3)), notice,
    )


def _apply_h(H: np.ndarray, p: np.ndarray) -> np.ndarray:
    q = H @ np.array([p[0], p[1], 1.0])
    return q[:2] / q[2]


class Ring:
    """The last ``capacity`` rows of a growing table, without per-frame reallocation."""

    def __init__(self, capacity: int, width: int) -> None:
        self.data = np.full((max(capacity, 1), width), np.nan)
        self.count = 0

    def __len__(self) -> int:
        return min(self.count, len(self.data))

    def append(self, row) -> None:
        self.data[self.count % len(self.data)] = row
        self.count += 1

    def ordered(self) -> np.ndarray:
        """Oldest first (a new array: safe to keep in the intermediates)."""
        n, cap = len(self), len(self.data)
        if self.count <= cap:
            return self.data[:n].copy()
        k = self.count % cap
        return np.concatenate([self.data[k:], self.data[:k]])


class GolfTracker:
    """Seed 000 (SPEC Tracker 1). ``step(frame)`` returns one track (id 1) once started."""

    name = "golf"

    def __init__(self, config: GolfConfig, rng: np.random.Generator) -> None:
        self.config = config
        self.rng = rng  # handed in by the engine: a tracker never draws its own seed
        self.luts = LutSet(self.config)
        self.pf = CondensationFilter(self.config.n_particles, self.rng)
        self.ekf = BallisticEkf(self.config)
        self.targets: B.BlobTargets | None = None
        self.range_scale = 1.0  # range-from-area correction, calibrated on the ball at rest at the start
        self.ball_luminance = math.nan  # mean Y of the marked ball's silhouette (photometric area)
        self.lut_name = ""
        self.started = False
        self.misses = 0
        self.parabola_used = False
        self._regions: list[InitRegion] = []
        self._region_keys: set = set()
        self._prev_camera: PosedCamera | None = None
        self._prev_index: int | None = None
        self._prev_t_ns: int | None = None
        self._history: deque = deque(maxlen=self.config.image_landing_history)
        self._trail = Ring(self.config.trail_length, 5)  # measured (x, y, dx, dy, dz)
        self._trail_world = Ring(self.config.trail_length, 3)  # EKF positions
        self._told_no_encoders = False
        self._had_camera = False
        self._told_no_hints = False
        self.intermediates = _empty("idle", "")

    # --- set-up --------------------------------------------------------------------------------
    def prepare(self, images_and_regions: Iterable[tuple[np.ndarray, Sequence[InitRegion]]]) -> None:
        """Build the LUTs up front from ``(image, regions marked on it)`` (optional: else lazily)."""
        for image, regions in images_and_regions:
            fresh = [r for r in regions if region_key(r) not in self.luts.consumed]
            if fresh:
                self.luts.add(image, fresh)
                self.luts.consumed.update(region_key(r) for r in fresh)
            self._remember(regions)

    def _remember(self, regions: Iterable[InitRegion]) -> None:
        for r in regions:
            key = region_key(r)
            if key not in self._region_keys:
                self._region_keys.add(key)
                self._regions.append(r)

    def _start_region(self, index: int) -> InitRegion | None:
        """The marked box to start from at frame ``index``: the latest one marked at or before it
        (a replay from the log's start begins on the first marked frame; one that starts later
        begins from the nearest earlier mark), preferring a label with "start"/"init"."""
        past = [r for r in self._regions if r.frame <= index]
        if not past:
            return None
        latest = max(r.frame for r in past)
        on_latest = [r for r in past if r.frame == latest]
        for r in on_latest:
            if any(word in r.label.lower() for word in ("start", "init")):
                return r
        return on_latest[0]

    # --- one frame -------------------------------------------------------------------------------
    def step(self, frame: Frame) -> list[TrackState]:
        cfg = self.config
        self._remember(frame.all_hints)
        self._remember(frame.hints)
        here = [r for r in self._regions if r.frame == frame.index and region_key(r) not in self.luts.consumed]
        if here:
            self.luts.add(frame.image, here)
            self.luts.consumed.update(region_key(r) for r in here)

        notice = ""
        camera = PosedCamera.of(frame.camera) if frame.camera is not None else None
        if camera is None and not self._told_no_encoders:
            self._told_no_encoders = True
            notice = ENCODER_GAP_NOTICE if self._had_camera else NO_ENCODER_NOTICE
        self._had_camera |= camera is not None
        if not self._regions and not self._told_no_hints:
            self._told_no_hints = True
            notice = f"{notice}; {NO_HINTS_NOTICE}" if notice else NO_HINTS_NOTICE
        mode = "ptz" if camera is not None else "image"

        height, width = frame.image.shape[:2]
        scale = height / cfg.reference_height
        reinit, reinit_point = "", NAN2
        start = self._start_region(frame.index) if not self.started else None
        if not self.started:
            if start is None:
                self.intermediates = _empty("idle", notice)
                self._prev_camera, self._prev_index, self._prev_t_ns = camera, frame.index, frame.t_ns
                return []
            self._start(frame, start, scale)
            reinit, reinit_point = "start", np.array([start.x, start.y])
            compensated = False
        else:
            compensated = self._compensates(camera)
            reinit, reinit_point = self._predict(frame, camera, scale)

        if camera is not None and self._prev_camera is not None and not reinit == "start":
            # The zoom changes the ball's apparent area by the squared focal-length ratio.
            zoom = (camera.intrinsics.fx * camera.intrinsics.fy) / (self._prev_camera.intrinsics.fx * self._prev_camera.intrinsics.fy)
            self.targets = B.BlobTargets(self.targets.area * zoom, self.targets.circularity)

        # --- search region from the predicted samples ------------------------------------------
        predicted = self.pf.w @ self.pf.s[:, :2]  # weights are uniform here: the predicted mean
        spread = self.pf.spread()
        diameter = 2.0 * math.sqrt(self.targets.area / math.pi)
        size = np.clip(2.0 * (cfg.search_sigmas * spread + diameter), cfg.search_min_px * scale, cfg.search_max_px * scale)
        size = np.minimum(size, [width, height])
        x0 = float(np.clip(predicted[0] - size[0] / 2, 0, width - size[0]))
        y0 = float(np.clip(predicted[1] - size[1] / 2, 0, height - size[1]))
        box = np.array([np.floor(x0), np.floor(y0), np.ceil(size[0]), np.ceil(size[1])])

        # --- LUT switch, silhouette, blobs ---------------------------------------------------------
        ycc, offset = crop_ycc(frame.image, box)
        self.lut_name, scores = self.luts.choose(ycc[..., 0], self.lut_name)
        mask = silhouette(ycc, self.luts.luts.get(self.lut_name))
        widen = min(1.0 + cfg.widen_per_miss * self.misses, cfg.widen_max)
        rows = B.measure_blobs(mask, offset, predicted, min_area=cfg.min_area_px * scale * scale, max_blobs=cfg.max_blobs)
        B.gate(rows, self.targets, area_tolerance=cfg.area_tolerance, circularity_tolerance=cfg.circularity_tolerance,
               widen=widen, area_slack=cfg.area_slack_px * scale * scale)
        selected = B.nearest(rows, predicted)
        targets_used = np.array([self.targets.area, self.targets.circularity])

        # --- particle measurement and estimate -----------------------------------------------------
        candidates = rows[rows[:, 4] > 0, :2] if len(rows) else np.zeros((0, 2))
        self.pf.measure(candidates, cfg.sigma_px * scale, cfg.alpha / scale)
        estimate = self.pf.estimate()

        # --- outputs, targets, EKF --------------------------------------------------------------------
        if selected >= 0:
            ball = rows[selected]
            x, y, w, h, status = float(ball[0]), float(ball[1]), float(ball[6]), float(ball[7]), "measured"
            self.targets = self.targets.follow(float(ball[2]), float(ball[3]), cfg.target_rate)
            self.misses = 0
            self.parabola_used = False
            self._history.append((frame.index, x, y))
            if camera is not None:
                area = self._range_area(ycc, offset, ball)
                rng_m = self.range_scale * range_from_area(area, camera, cfg.ball_diameter_m)
                self.ekf.update(camera, np.array([x, y]), rng_m, range_rel_sigma(area, cfg.ekf_range_rel_sigma))
        else:
            self.misses += 1
            status = "predicted" if self.misses <= cfg.max_predicted_frames else "lost"
            x, y = float(estimate[0]), float(estimate[1])
            w = h = diameter
        los = camera.line_of_sight(np.array([[x, y]]))[0] if camera is not None else NAN3
        if status == "measured":
            self._trail.append((x, y, los[0], los[1], los[2]))
        if self.ekf.initialised:
            self._trail_world.append(self.ekf.x[:3])

        vx, vy = float(estimate[2]), float(estimate[3])
        if compensated:
            H = pose_homography(self._prev_camera, camera)
            before = _apply_h(np.linalg.inv(H), np.array([x, y]))
            vx, vy = vx + x - float(before[0]), vy + y - float(before[1])

        landing_world, landing_image, landing_in = NAN3, NAN2, math.nan
        if self.ekf.initialised:
            pred = self.ekf.landing()
            if pred is not None:
                landing_in, landing_world = pred
                if camera is not None:
                    landing_image = camera.project_points(landing_world.reshape(1, 3))[0]

        self._prev_camera, self._prev_index, self._prev_t_ns = camera, frame.index, frame.t_ns
        ekf_x = self.ekf.x.copy() if self.ekf.initialised else np.full(6, np.nan)
        ekf_P = self.ekf.P.copy() if self.ekf.initialised else np.full((6, 6), np.nan)
        self.intermediates = GolfIntermediates(
            mode=mode, search_box=box, lut_name=self.lut_name, lut_names=LUT_NAMES, lut_scores=scores,
            silhouette=mask, silhouette_offset=np.array(offset, np.int64), blobs=rows,
            blob_columns=B.BLOB_COLUMNS, blob_reasons=B.REASONS, selected=selected, targets=targets_used,
            gate_widen=float(widen), particles=self.pf.s, weights=self.pf.w, predicted=np.asarray(predicted, float),
            estimate=estimate, spread=spread, ekf_x=ekf_x, ekf_P=ekf_P, ekf_nis=float(self.ekf.last_nis),
            landing_world=np.asarray(landing_world, float), landing_image=np.asarray(landing_image, float),
            landing_in_s=float(landing_in), reinit=reinit, reinit_point=np.asarray(reinit_point, float),
            trail_image=self._trail_image(camera), trail_world=self._trail_world.ordered(),
            notice=notice,
        )
        if status == "lost":
            return [TrackState(1, status="lost")]
        X = Y = Z = None
        if self.ekf.initialised:
            X, Y, Z = (float(v) for v in self.ekf.x[:3])
        dx = dy = dz = None
        if camera is not None:
            dx, dy, dz = (float(v) for v in los)
        return [TrackState(1, x, y, w, h, X, Y, Z, dx, dy, dz, vx, vy, status)]

    # --- stages ------------------------------------------------------------------------------------
    def _start(self, frame: Frame, region: InitRegion, scale: float) -> None:
        """Targets from the marked box's own silhouette; samples around the box (§2.3 initialisation)."""
        cfg = self.config
        self.started = True
        samples = region_samples(frame.image, region, cfg)
        self.lut_name = samples.name if samples.name in self.luts.luts else (self.luts.names[0] if self.luts.names else "")
        area, circ = math.pi / 4.0 * region.w * region.h, cfg.initial_circularity
        box = np.array([region.x - region.w, region.y - region.h, 2 * region.w, 2 * region.h])
        ycc, offset = crop_ycc(frame.image, box)
        rows = B.measure_blobs(silhouette(ycc, self.luts.luts.get(self.lut_name)), offset, np.array([region.x, region.y]),
                               min_area=cfg.min_area_px * scale * scale, max_blobs=cfg.max_blobs)
        if len(rows):
            measured = rows[np.isfinite(rows[:, 3])]
            if len(measured):
                biggest = measured[int(np.argmax(measured[:, 2]))]
                area = float(biggest[2])
                circ = float(min(max(biggest[3], 0.6), 1.0))
                mask = silhouette(ycc, self.luts.luts.get(self.lut_name)).astype(bool)
                if mask.any():
                    self.ball_luminance = float(ycc[..., 0][mask].mean())
        self.targets = B.BlobTargets(area, circ)
        if frame.camera is not None and samples.name == "ground":
            self.range_scale = self._calibrate_range(PosedCamera.of(frame.camera), region, area)
        self.pf.initialise(np.array([region.x, region.y]), cfg.init_spread_px * scale, cfg.init_velocity_spread_px * scale)

    def _predict(self, frame: Frame, camera: PosedCamera | None, scale: float) -> tuple[str, np.ndarray]:
        """EKF predict (and landing check), then either re-initialise or select + predict the samples."""
        cfg = self.config
        steps = max(1, frame.index - self._prev_index) if self._prev_index is not None else 1
        dt = (frame.t_ns - self._prev_t_ns) / 1e9 if self._prev_t_ns is not None else 0.0
        landing = None
        if self.ekf.initialised:
            previous = self.ekf.x.copy()
            self.ekf.predict(dt)
            contact = self.ekf.ground_contact(previous)
            if contact is not None:
                if self.ekf.armed and contact.fraction < 1.0:
                    landing = contact.point
                self.ekf.bounce(contact)
                if landing is not None:
                    self.ekf.armed = False

        if landing is not None and camera is not None and cfg.landing_reinit:
            centre = camera.project_points(landing.reshape(1, 3))[0]
            if np.all(np.isfinite(centre)):
                centre = np.clip(centre, 0, [frame.image.shape[1] - 1, frame.image.shape[0] - 1])
                # Spread: the EKF's own uncertainty, and wide enough to still cover the ball where
                # the samples had it (a contact predicted a few frames early must not lose it).
                sigma = self._projected_sigma(camera, scale, self.pf.estimate()[:2] - centre)
                self.pf.initialise(centre, sigma, cfg.reinit_velocity_sigma_px * scale)
                return "ekf_landing", centre

        if cfg.landing_reinit and not self.ekf.initialised and not self.parabola_used and self.misses >= cfg.image_landing_misses:
            found = image_parabola_landing(np.array(self._history, float).reshape(-1, 3), float(frame.index))
            if found is not None:
                centre, half = found
                sigma = np.maximum(half, cfg.reinit_min_sigma_px * scale)
                self.parabola_used = True
                self.pf.initialise(centre, sigma, cfg.reinit_velocity_sigma_px * scale)
                return "image_parabola", centre

        if cfg.lost_search == "centre" and self.misses > cfg.max_predicted_frames:
            width, height = frame.image.shape[1], frame.image.shape[0]
            centre = np.array([(width - 1) / 2.0, (height - 1) / 2.0])
            sigma = min(cfg.search_max_px * scale, width, height) / (2.0 * cfg.search_sigmas)
            self.pf.initialise(centre, sigma, cfg.reinit_velocity_sigma_px * scale)
            return "lost_centre", centre

        self.pf.select()
        if self._compensates(camera):
            self.pf.warp(pose_homography(self._prev_camera, camera))
        if self.misses:  # unseen: the velocity is ever less known; without this the cloud drifts away
            self.pf.s[:, 2:] *= cfg.miss_velocity_damping
        if steps > 1:  # dropped frames: constant velocity over the gap
            self.pf.s[:, :2] += (steps - 1) * self.pf.s[:, 2:]
        root = math.sqrt(steps)
        self.pf.predict(cfg.process_noise_pos_px * scale * root, cfg.process_noise_vel_px * scale * root)
        return "", NAN2

    def _range_area(self, ycc: np.ndarray, offset: tuple[int, int], ball: np.ndarray) -> float:
        """The ball's area for the range: photometric when it can be (see ``blobs.photometric_area``)."""
        cfg = self.config
        area = float(ball[2])
        if cfg.photometric_area and np.isfinite(self.ball_luminance):
            radius = max(3.0, 0.75 * max(float(ball[6]), float(ball[7])) + 2.0)
            photo = B.photometric_area(ycc[..., 0], float(ball[0]) - offset[0], float(ball[1]) - offset[1], radius,
                                       self.ball_luminance)
            if np.isfinite(photo) and photo > 0.5 * area:
                area = photo
        return area

    def _calibrate_range(self, camera: PosedCamera, region: InitRegion, area: float) -> float:
        """Range correction from the marked ball resting on the ground (paper: the ground plane).

        The silhouette of a small ball is not exactly its disc (blur, JPEG, the LUT's cut), so the
        range from its area is biased. Where the start box is a ball on the ground, its line of
        sight meets the ground plane at the true range; the ratio corrects every later range.
        """
        los = camera.line_of_sight(np.array([[region.x, region.y]]))[0]
        height = camera.position[2] - self.config.ball_diameter_m / 2.0
        if los[2] >= -1e-6 or height <= 0:
            return 1.0
        true_range = height / -los[2]
        if true_range > MAX_CALIBRATION_RANGE_M:
            return 1.0
        return float(np.clip(true_range / range_from_area(area, camera, self.config.ball_diameter_m), 0.5, 2.0))

    def _compensates(self, camera: PosedCamera | None) -> bool:
        """Move the samples with the pose change (both poses known)?

        The samples then live in the camera-independent space of directions: the ball's own
        angular motion is what the constant-velocity model sees, not the operator's pan, tilt and
        zoom. A long loss is handled by ``lost_search`` instead.
        """
        return self.config.compensate_camera_motion and camera is not None and self._prev_camera is not None

    def _projected_sigma(self, camera: PosedCamera, scale: float, offset: np.ndarray) -> np.ndarray:
        """Pixel spread of the EKF position covariance seen through ``camera``, at least the floor
        and half of ``offset`` (per axis), at most what the largest search region can hold."""
        from trackreplay.trackers.golf.landing import measurement_jacobian

        cfg = self.config
        _, H = measurement_jacobian(camera, self.ekf.x[:3])
        cov = H[:2, :3] @ self.ekf.P[:3, :3] @ H[:2, :3].T
        sigma = np.maximum(np.sqrt(np.maximum(np.diag(cov), 0.0)), 0.5 * np.abs(offset))
        cap = cfg.search_max_px * scale / (2.0 * cfg.search_sigmas)
        return np.clip(sigma, cfg.reinit_min_sigma_px * scale, cap)

    def _trail_image(self, camera: PosedCamera | None) -> np.ndarray:
        """Past measurements drawn into this frame: stored lines of sight projected with this pose."""
        if not len(self._trail):
            return np.zeros((0, 2))
        trail = self._trail.ordered()
        out = trail[:, :2].copy()
        if camera is not None:
            has = np.isfinite(trail[:, 2])
            if has.any():
                out[has] = camera.project_directions(trail[has, 2:5])
        return out
