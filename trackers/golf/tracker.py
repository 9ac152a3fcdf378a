"""Golf-ball tracker for tee-shot broadcast video (seed 000): ``GolfTracker``, name "golf".

Per frame, the paper's pipeline (Fig. 1), one module per stage:

1. §2.3 / eq. (1): the 3-D EKF predicts; the samples start again at its ground contact, at an
   image-space parabola's bounce or, once lost, mid-picture (:mod:`.reinit`), else CONDENSATION
   selects and predicts (:mod:`.particles`).
2. §2.1-2.2: search region ``I_s`` around the predicted mean, sized by the spread (:mod:`.search_region`).
3. §2.1: sky/ground LUT from the region's luminance, silhouette ``I_c`` (:mod:`.silhouette`, :mod:`.lut`).
4. §2.1: blobs gated on area and circularity; the accepted one nearest the prediction is the ball (:mod:`.blobs`).
5. Ours: the motion-model gate, a confidence per frame and evidence over several frames for a
   jump (:mod:`.validate`); eq. (2) measures with the in-gate centroids, eq. (3) estimates.
6. Outputs: "measured" (the ball was seen there, with its confidence), "predicted", then "lost"
   (no position: the export interpolates) after ``max_predicted_frames`` misses; with a pose, the
   line of sight and X, Y, Z from the EKF, ranged from the ball's area (:mod:`.range`).

Every mark re-anchors: a box marked on frame N restarts the track there (and feeds the LUTs); a
confidently measured ball also teaches the LUT of the background it is over (:meth:`GolfLuts.learn_from_track`).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable

import numpy as np

from trackreplay.schemas.records import InitRegion
from trackreplay.schemas.errors import LogError
from trackreplay.trackers.base import Marked, TrackerBase, TrackState
from trackreplay.trackers.filters.particles import ParticleFilter, squared_deviations
from trackreplay.trackers.frame import Frame
from trackreplay.trackers.geometry.box import clip_box, crop
from trackreplay.trackers.geometry.ptz import PtzCamera, pose_homography, zoom_area_ratio
from trackreplay.trackers.golf.blobs import (STILL, ApparentMotion, BlobTargets, GatedBlobs, refuse, roundness, select_ball,
                                             spills_over, start_targets)
from trackreplay.trackers.golf.config import GolfConfig
from trackreplay.trackers.golf.intermediates import GolfIntermediates
from trackreplay.trackers.golf.landing import BallisticEkf, EkfState
from trackreplay.trackers.golf.lut import LUT_NAMES, GolfLuts
from trackreplay.trackers.golf.marks import Marks
from trackreplay.trackers.golf.notices import Notices
from trackreplay.trackers.golf.particles import (DIM, ParticleSet, launch, likelihood, motion, spread_sigma, state, warp,
                                                 with_camera_motion)
from trackreplay.trackers.golf.range import RangeFromArea, nearer_than_predicted
from trackreplay.trackers.golf.reinit import Reinit, ReinitPolicy
from trackreplay.trackers.golf.scenery import Scenery
from trackreplay.trackers.golf.search_region import reaching, search_region
from trackreplay.trackers.golf.seen_before import LastSighting, in_last_view, was_there_before, where_the_ball_was
from trackreplay.trackers.golf.streak import whole_streak
from trackreplay.trackers.golf.silhouette import (CONTRAST, LutSilhouette, box_silhouette, contrast_silhouette, lut_silhouette,
                                                  moving_silhouette, named_silhouette, previous_in_pose, top_hat)
from trackreplay.trackers.golf.trail import Trail
from trackreplay.trackers.golf.validate import Validator

NAN3 = np.full(3, np.nan)


class GolfTracker(TrackerBase):
    """Seed 000 (SPEC Tracker 1). ``step(frame)`` returns one track (id 1) once started."""

    name = "golf"
    needs = "mark"  # the engine refuses a log that marks no ball (replay.marks.check_can_track)
    one_start_per_frame = True  # ... and two different marks on a frame, neither labelled start (check_one_start_per_frame)

    def __init__(self, config: GolfConfig, rng: np.random.Generator) -> None:
        self.config = config
        self.rng = rng  # handed in by the engine: a tracker never draws its own seed
        self.marks = Marks(config.snap, config.lut.core)
        self.luts = GolfLuts(config.lut, config.search.min_px, config.reference_height)
        self.pf = ParticleFilter(config.particles.n, DIM, rng)
        self.ekf = BallisticEkf(config.ekf, config.ball_diameter_m / 2.0)
        self.range = RangeFromArea(config.range, config.ball_diameter_m)
        self.reinit = ReinitPolicy(config.reinit, config.search, config.max_predicted_frames)
        self.trail = Trail(config.trail_length)
        self.validator = Validator(config.validate, config.blobs)
        self.scenery = Scenery(config.validate.still_px)
        self.notices = Notices()
        self.targets: BlobTargets | None = None
        self.lut_name = ""
        self.started = False
        self.misses = 0
        self._prev: tuple[PtzCamera | None, int | None, int | None] = (None, None, None)  # camera, index, t_ns
        self._prev_image: np.ndarray | None = None
        self._last_measured: tuple[int, float, float] | None = None  # frame, x, y
        self._sightings = 0  # frames measured since the track (re)started
        self._last_sighting: LastSighting | None = None  # the frame the ball was last measured on (seen_before)
        self.intermediates = GolfIntermediates.idle("")
        self._moments_memo: list = [None, None, {}]  # particles, weights, {first component: (mean, spread)}
        self._estimate_memo: tuple = (None, None, None)  # particles, weights, estimate
        self._followed: bool | None = None  # this frame's ReinitPolicy.follows answer, once _predict asked
        self._pose_change: np.ndarray | None = None  # this frame's pose homography from the last frame's
        self._all_hints: tuple | None = None  # the frame bundle's all_hints last remembered
        self._marked_diameter = 0.0  # the last mark's ball, measured from its silhouette (0: not measured)

    def prepare(self, marked: Marked) -> None:
        """Build the LUTs up front from ``(image, regions marked on it)`` (optional: else as frames come)."""
        for image, regions in marked:
            self.marks.remember(regions)
            for index in sorted({r.frame for r in regions}):
                self.marks.place(image, index)
                self.luts.learn(image, self.marks.on(index))

    def step(self, frame: Frame) -> list[TrackState]:
        cfg, camera = self.config, frame.camera
        if frame.all_hints is not self._all_hints or not isinstance(frame.all_hints, tuple):
            self.marks.remember(frame.all_hints)  # the log's marks: one tuple, the same every frame (once)
            self._all_hints = frame.all_hints
        self.marks.remember(frame.hints)
        self.marks.place(frame.image, frame.index)
        self.luts.learn(frame.image, self.marks.on(frame.index))
        notice = self.notices.check(camera is not None, bool(self.marks))
        height, width = frame.image.shape[:2]
        scale = self._scale(height)
        prev_camera = self._prev[0]
        # the pose change from the last frame to this one (None: a pose is missing), asked by several stages
        self._pose_change = pose_homography(prev_camera, camera) if camera is not None and prev_camera is not None else None
        # With encoders (optional): the samples move with the pose change, living in camera-independent directions.
        compensated = self.started and cfg.particles.compensate_camera_motion and camera is not None and prev_camera is not None
        marked_now = self.marks.on(frame.index)
        self._followed = None
        if self.started and not marked_now:
            reinit = self._predict(frame, camera, scale, compensated)  # §2.3 re-initialisation, or eq. (1)
        elif (region := self.marks.start_region(frame.index)) is not None:
            reinit = self._start(frame, region, scale)  # the first mark, and every later one: re-anchor
            scale = self._scale(height)  # (the marked ball's size may widen it)
        else:
            self.intermediates = GolfIntermediates.idle(notice)
            self._prev = (camera, frame.index, frame.t_ns)
            self._prev_image = frame.image
            return []
        if camera is not None and prev_camera is not None and reinit.kind != "start":
            self.targets = self.targets.zoomed(zoom_area_ratio(prev_camera, camera))
            self.validator.follow_camera(self._pose_change)
            self.scenery.follow_camera(self._pose_change)
        diameter, expected_area = self.targets.diameter, self.targets.area  # this frame's expected ball (before it learns)
        search = search_region(*self._moments(0), diameter, width, height, scale, cfg.search)  # §2.1 I_s, §2.2 size from the spread
        if (ahead := self.validator.next_point(diameter, scale)) is not None:  # ours: where a jump's evidence will be
            search = reaching(search, *ahead, width, height)
        sil, ycc = lut_silhouette(frame.image, search.box, self.luts, self.lut_name)  # §2.1 I_c
        self.lut_name = sil.lut_name
        lost = self.misses > cfg.max_predicted_frames
        motion = None if lost else self._apparent_motion(search.centre, camera, compensated)
        hat = functools.cache(lambda: top_hat(ycc, diameter, cfg.contrast, scale))  # the contrast and moving silhouettes share it
        moving = (lambda: self._moving(frame, ycc, sil.offset, diameter, scale, hat)) if cfg.contrast.moving else (lambda: None)
        if lost and (mask := moving()) is not None:  # once lost, a ball moving against the world is a candidate too
            sil = dataclasses.replace(sil, mask=sil.mask | mask)
        gated = self._select(sil.mask, sil.offset, search.centre, scale, lost, motion)  # §2.1
        seen_gated = self.validator.seen_in_gate(gated=gated, predicted=search.centre, spread=search.spread,
                                                 diameter=diameter, size=(width, height), scale=scale, lost=lost)
        found = seen_gated[0]
        if not lost and (found is None or found.verdict != "measured"):
            # The background changed under the ball faster than the luminance switch (tree line, horizon):
            # the ball may pass the other LUT; take it only if that finds the ball in the gate.
            for name in (n for n in self.luts.names if n != sil.lut_name and self._background_here(sil, n)):
                other = LutSilhouette(name, sil.lut_scores, named_silhouette(ycc, self.luts, name), sil.offset)
                alt = self._select(other.mask, other.offset, search.centre, scale, False, motion)
                seen_alt = self.validator.seen_in_gate(gated=alt, predicted=search.centre, spread=search.spread,
                                                       diameter=diameter, size=(width, height), scale=scale, lost=lost)
                if seen_alt[0] is not None and seen_alt[0].verdict == "measured":
                    sil, gated, self.lut_name, seen_gated = other, alt, name, seen_alt
                    break
            else:
                fallback = self._contrast_fallback(ycc, sil, search, diameter, (width, height), scale, lost, motion, moving, hat)
                if fallback is not None:
                    sil, gated, seen_gated = fallback
        check = self.validator.validate(index=frame.index, gated=gated, predicted=search.centre, spread=search.spread,
                                        diameter=diameter, size=(width, height), scale=scale, lost=lost,
                                        entry_only=not self._centre_search(camera, prev_camera, width, height),
                                        seen=seen_gated, repeat=self._repeated(frame.image, search.box))
        if check.verdict == "confirmed" and self._too_near(camera):
            check = dataclasses.replace(check, verdict="too_near", confidence=0.0)
        if check.verdict == "confirmed" and self._seen_before(frame.image, camera, gated.blobs.centroid[check.candidate], scale):
            check = dataclasses.replace(check, verdict="seen_before", confidence=0.0)
            # ... and stays refused: otherwise, in the gate, it draws the samples to it and is measured there;
            # but not where the ball itself was last seen (a ball found again there, half hidden, would
            # be refused for good)
            point = gated.blobs.centroid[check.candidate]
            then = in_last_view(self._last_sighting, camera, point, 0.0, frame.image)[:2]  # the place in the last sighting's pixels
            if not where_the_ball_was(self._last_sighting, then, cfg.validate.still_px * scale):
                self.scenery.add(point)
        seen = check.verdict in ("measured", "confirmed")
        if check.verdict == "confirmed":  # a jump seen over confirm_frames frames: the samples start again there
            point = gated.blobs.centroid[check.candidate]
            sigma = cfg.particles.init_spread_px * scale
            velocity, unsure = self.validator.confirmed_velocity()
            motion = ApparentMotion(np.asarray(velocity, float), float(unsure))  # the confirmed track's, for .streak
            self.pf.initialise(state(point, velocity), spread_sigma(sigma, max(cfg.particles.init_velocity_spread_px * scale, unsure)))
            reinit = Reinit("confirmed", point.copy(), np.full(2, sigma))
            area, rnd = self.validator.confirmed_shape()  # the ball's size starts again from what was confirmed
            self.targets = BlobTargets(area, float(min(max(rnd, 0.6), 1.0)))
            observed = gated.blobs.centroid[[check.candidate]]
            self.validator.reset()
            self._last_measured = None
        else:
            observed = gated.blobs.centroid[check.in_gate]
        gated = GatedBlobs(gated.blobs, gated.reason, check.candidate if seen else -1, gated.targets, gated.widen, gated.reasons)
        if check.verdict == "measured" and cfg.particles.detection_share > 0:
            self._inject(frame.index, gated.blobs.centroid[check.candidate], scale)
        self.pf.weigh(likelihood(observed, cfg.particles.sigma_px * scale, cfg.particles.alpha / scale))  # eq. (2)
        estimate = self._estimate()  # eq. (3)

        if seen:
            x, y, w, h = self._measured(frame, camera, gated, ycc, sil, check.confidence, hat, motion, scale)
            status, confidence = "measured", check.confidence
        else:
            self.misses += 1
            status = "predicted" if self.misses <= cfg.max_predicted_frames else "lost"
            x, y, w, h = float(estimate[0]), float(estimate[1]), diameter, diameter
            confidence = check.confidence
        if status == "measured":
            self._last_measured = (frame.index, x, y)
            self._last_sighting = LastSighting(frame.image, camera, (x, y), diameter, expected_area)
            self._sightings += 1
        self.scenery.update(frame.index, gated.blobs, gated.accepted | (gated.reason == STILL),
                            (x, y) if status == "measured" else None, diameter, scale)
        los = camera.line_of_sight(np.array([[x, y]]))[0] if camera is not None else NAN3
        self.trail.add((x, y) if status == "measured" else None, los, self.ekf.x)
        vx, vy = float(estimate[2]), float(estimate[3])
        if compensated:  # the velocity in this pose's pixels includes the camera's own motion
            vx, vy = with_camera_motion((vx, vy), (x, y), self._pose_change)

        self._prev = (camera, frame.index, frame.t_ns)
        self._prev_image = frame.image
        self.intermediates = GolfIntermediates(
            "ptz" if camera is not None else "image", reinit, search, sil, gated,
            ParticleSet(self.pf.particles, self.pf.weights, estimate), EkfState.of(self.ekf, camera),
            self.trail.points(camera), notice, check)
        if status == "lost":
            return [TrackState(1, status="lost")]
        X, Y, Z = (float(v) for v in self.ekf.x[:3]) if self.ekf.initialised else (None, None, None)
        dx, dy, dz = (float(v) for v in los) if camera is not None else (None, None, None)
        return [TrackState(1, x, y, w, h, X, Y, Z, dx, dy, dz, vx, vy, status, confidence=float(min(max(confidence, 0.0), 1.0)))]

    # --- stages ------------------------------------------------------------------------------------
    def _scale(self, height: int) -> float:
        """The factor on every pixel parameter: the frame's height over ``reference_height``, or the
        ball's diameter over ``reference_ball_px`` when that is larger. The parameters were set on
        balls 14-16 px across at 1080 lines; a ball larger than that for its frame (a close camera, a
        portrait clip turned on its side, a crop) moves and blurs as many of its own diameters a frame
        as the reference ball does, so its gates and speeds grow with it. The diameter is the marked
        ball's, then the targets' as the ball flies off and shrinks, never more than the marked one (a
        blob that grows may be the ball merged with something white)."""
        cfg = self.config
        by_height = height / cfg.reference_height
        if not self._marked_diameter or self.targets is None or cfg.reference_ball_px <= 0:
            return by_height
        return max(by_height, min(self._marked_diameter, self.targets.diameter) / cfg.reference_ball_px)

    def _repeated(self, image: np.ndarray, box: np.ndarray) -> bool:
        """The search region shows exactly what it showed on the frame before (a repeated picture: 30 fps
        shown at 50 or 60 by copying frames; a camera's noise makes two real pictures differ)."""
        previous = self._prev_image
        if previous is None or previous.shape != image.shape:
            return False
        x0, y0, w, h = (float(v) for v in box)
        corners = clip_box(x0, y0, x0 + w, y0 + h, image.shape[1], image.shape[0])  # as the silhouettes crop it
        return bool(np.array_equal(crop(image, corners)[0], crop(previous, corners)[0]))

    def _background_here(self, sil: LutSilhouette, name: str) -> bool:
        """LUT ``name``'s background is at least ``lut.other_min_share`` of the search region (its
        score in :meth:`GolfLuts.choose`): a LUT says nothing about colours it never saw around the ball."""
        share = float(sil.lut_scores[LUT_NAMES.index(name)])
        return share >= self.config.lut.other_min_share  # (NaN, a LUT not built: False)

    def _spills_over(self, image: np.ndarray, region: InitRegion) -> bool:
        """The marked box's colours pick out more than twice the box (:func:`.blobs.spills_over`), seen
        in a crop four times the box and 16 px more each way."""
        w, h = region.w * 4.0 + 32.0, region.h * 4.0 + 32.0
        _, offset, mask = box_silhouette(image, np.array([region.x - w / 2, region.y - h / 2, w, h]), self.luts, self.lut_name)
        return spills_over(mask, offset, (region.x, region.y), (region.w, region.h))

    def _seen_before(self, image: np.ndarray, camera: PtzCamera | None, point: np.ndarray, scale: float) -> bool:
        """A confirmed track's blob was already there, beside the ball, when the ball was last
        measured (``validate.confirm_not_seen_before``, :mod:`.seen_before`)."""
        cfg = self.config
        if not cfg.validate.confirm_not_seen_before or self._last_sighting is None:
            return False
        area, _ = self.validator.confirmed_shape()
        return was_there_before(self._last_sighting, camera, point, area, self.luts, self.lut_name,
                                cfg.validate.still_px * scale, cfg.blobs.area_tolerance, image)

    def _too_near(self, camera: PtzCamera | None) -> bool:
        """A confirmed track's blobs are too big for the ball where the 3-D filter has it
        (``validate.confirm_max_nearer``; never without encoders or a running filter)."""
        factor = self.config.validate.confirm_max_nearer
        if factor <= 0 or camera is None or not self.ekf.initialised:
            return False
        area, _ = self.validator.confirmed_shape()
        range_m, _ = self.range.measure(area, camera)
        return nearer_than_predicted(range_m, self.ekf.kf.x[:3], self.ekf.kf.P[:3, :3], camera.position, factor)

    def _apparent_motion(self, position: np.ndarray, camera: PtzCamera | None, compensated: bool) -> ApparentMotion:
        """The samples' mean velocity as the image sees it (with the camera's own motion when the
        samples are compensated) and its spread: how long the ball's streak may be this frame."""
        velocity, spread = self._moments(2)
        if compensated:
            velocity = np.array(with_camera_motion(tuple(velocity), tuple(position), self._pose_change))
        return ApparentMotion(velocity, float(np.max(spread)))

    def _moments(self, first: int) -> tuple[np.ndarray, np.ndarray]:
        """The samples' weighted mean and spread of components ``first``, ``first + 1`` (positions: 0,
        velocities: 2), as ``weights @ particles[:, first:first + 2]`` and ``ParticleFilter.spread``
        compute them, once per set of samples (the search region, the apparent motion and the
        injection all ask)."""
        pf = self.pf
        particles, weights = pf.particles, pf.weights
        memo = self._moments_memo
        if memo[0] is not particles or memo[1] is not weights:
            memo = self._moments_memo = [particles, weights, {}]
        out = memo[2].get(first)
        if out is None:
            p = particles[:, first:first + 2]
            mean = weights @ p
            out = memo[2][first] = (mean, np.sqrt(np.maximum(weights @ squared_deviations(p, mean), 0.0)))
        return out

    def _centre_search(self, camera: PtzCamera | None, previous: PtzCamera | None, width: int, height: int) -> bool:
        """:meth:`ReinitPolicy.centre_search`, answered from this frame's :meth:`ReinitPolicy.follows`
        when :meth:`_predict` asked it already: the same question (same poses and size; nothing in
        between adds to the policy's history, only :meth:`_measured` does)."""
        if self._followed is not None and self.reinit.cfg.lost == "auto":
            return self._followed
        return self.reinit.centre_search(camera, previous, width, height, self._pose_change)

    def _estimate(self) -> np.ndarray:
        """``ParticleFilter.estimate`` (eq. (3)), once per set of samples (a copy: the caller may keep it)."""
        pf = self.pf
        memo = self._estimate_memo
        if memo[0] is not pf.particles or memo[1] is not pf.weights:
            memo = self._estimate_memo = (pf.particles, pf.weights, pf.estimate())
        return memo[2].copy()

    def _inject(self, index: int, point: np.ndarray, scale: float) -> None:
        """Importance samples around this frame's measured blob, moving as it moved since the last measured frame."""
        cfg = self.config.particles
        last = self._last_measured
        velocity = point - np.array(last[1:]) if last is not None and last[0] == index - 1 else self._estimate()[2:]
        # As spread out as the cloud itself: the samples move to the blob without the cloud
        # narrowing (a ball at rest must still be caught when it is struck).
        sigma = np.maximum(self.pf.spread(), spread_sigma(cfg.noise_pos_px * scale, cfg.noise_vel_px * scale))
        self.pf.inject(cfg.detection_share, state(point, velocity), sigma)

    def _moving(self, frame: Frame, ycc: np.ndarray, offset: np.ndarray, diameter: float, scale: float,
                hat: Callable[[], np.ndarray]) -> np.ndarray | None:
        """The moving-against-the-world silhouette over the crop (None: no pose for this frame and
        the one before it, or not the frame right after it); ``hat()`` gives the crop's top-hat."""
        prev_camera, prev_index, prev_t_ns = self._prev
        if (not self.config.contrast.moving or frame.camera is None or prev_camera is None or self._prev_image is None
                or prev_index != frame.index - 1 or ycc.size == 0):
            return None
        if prev_t_ns is not None and not 0 < frame.t_ns - prev_t_ns <= self.config.ekf.max_gap_s * 1e9:
            return None  # a time gap: the frame before is no picture of where the world was a frame ago
        before = previous_in_pose(self._prev_image, self._pose_change, (int(offset[0]), int(offset[1])),
                                  ycc.shape[:2])
        return moving_silhouette(ycc, before, diameter, self.config.contrast, scale, hat=hat())

    def _struck(self, scale: float) -> bool:
        """The ball, missed this frame for the first time, was lying still when last seen, so it was
        struck: seen still on ``rest_frames`` frames, or on its marked frame only and as a sharp disc
        there (round, no motion blur: a mark on the launch frame of a 30 fps clip, gone 40-70 px
        a frame later; a streak marked in flight is no ball at rest). Never for a speck (a target area
        under ``particles.strike_min_area_px``): a far ball rolling along the line of sight looks still
        without lying still, and the wide search a strike opens finds only other specks around it."""
        cfg = self.config.particles
        if self.targets is not None and self.targets.area < cfg.strike_min_area_px:
            return False
        if self._sightings == 1 and self.targets is not None:  # (never seen since the mark: nothing known)
            return self.targets.circularity >= cfg.rest_roundness
        return self.reinit.at_rest(cfg.rest_frames, cfg.rest_px * scale)

    def _select(self, mask: np.ndarray, offset, centre: np.ndarray, scale: float, lost: bool,
                motion: ApparentMotion | None) -> GatedBlobs:
        """§2.1's blob gate (:func:`select_ball`), then still scenery refused (:mod:`.scenery`)."""
        cfg = self.config
        gated = select_ball(mask, offset, centre, self.targets, self.misses, cfg.blobs, scale, lost=lost, motion=motion)
        if len(self.scenery.points):
            gated = refuse(gated, self.scenery.on_scenery(gated.blobs, scale), STILL, centre)
        return gated

    def _contrast_fallback(self, ycc: np.ndarray, sil: LutSilhouette, search, diameter: float, size: tuple[int, int],
                           scale: float, lost: bool, motion: ApparentMotion | None,
                           moving: Callable[[], np.ndarray | None],
                           hat: Callable[[], np.ndarray]) -> tuple[LutSilhouette, GatedBlobs, tuple] | None:
        """Neither LUT saw the ball near the prediction: the local-contrast silhouette (with the
        moving one when there is a pose), taken only when it finds a blob the validation gate
        measures (same gate, same confidence)."""
        cfg = self.config
        if not cfg.contrast.enabled:
            return None
        for make in (lambda: contrast_silhouette(ycc, diameter, cfg.contrast, scale, hat=hat()), moving):
            mask = make()  # the moving one second and alone: joined, its pixels would reshape a contrast blob
            if mask is None:
                continue
            other = LutSilhouette(CONTRAST, sil.lut_scores, mask, sil.offset)
            gated = self._select(mask, other.offset, search.centre, scale, lost, motion)
            seen = self.validator.seen_in_gate(gated=gated, predicted=search.centre, spread=search.spread,
                                               diameter=diameter, size=size, scale=scale, lost=lost)
            if seen[0] is not None and seen[0].verdict == "measured":
                return other, gated, seen
        return None

    def _start(self, frame: Frame, region: InitRegion, scale: float) -> Reinit:
        """§2.3 initialisation: targets from the marked box's own silhouette, samples around the box."""
        cfg = self.config
        self.started = True
        self.misses = 0
        self._last_measured = None  # a re-anchor is no step of the ball's
        self._sightings = 0
        self._last_sighting = None
        self.validator.reset()
        self.scenery.reset()  # the user says where the ball is
        self.reinit.landed_at, self.reinit.followed_landing = None, False  # a landing before the mark is not this track's
        name, self.lut_name = self.luts.start_names(frame.image, region)
        box = np.array([region.x - region.w, region.y - region.h, 2 * region.w, 2 * region.h])
        ycc, offset, mask = box_silhouette(frame.image, box, self.luts, self.lut_name)
        found = start_targets(mask, offset, np.array([region.x, region.y]), cfg.blobs, scale)
        if found is not None and self._spills_over(frame.image, region):
            raise LogError(f"the box marked on frame {region.frame} ({region.w:g}x{region.h:g} px round {region.x:g},{region.y:g}) "
                           "holds no ball the golf tracker can tell from its surroundings: the colours it picks out fill the "
                           "box and run past twice its size; draw the box round the ball alone (`trackreplay frame LOG "
                           f"{region.frame}` shows the pixel grid)")
        self.targets = found or BlobTargets(math.pi / 4.0 * region.w * region.h, cfg.blobs.initial_circularity)
        self._marked_diameter = found.diameter if found is not None else 0.0  # (a box may be drawn loose)
        scale = self._scale(frame.image.shape[0])
        if found is not None:
            self.range.learn_ball(ycc[..., 0], mask)
        if frame.camera is not None and name == "ground":  # a ball resting on the ground calibrates the range
            self.range.calibrate(frame.camera, np.array([region.x, region.y]), self.targets.area)
        sigma, centre = cfg.particles.init_spread_px * scale, np.array([region.x, region.y])
        self.pf.initialise(state(centre), spread_sigma(sigma, cfg.particles.init_velocity_spread_px * scale))
        return Reinit("start", centre, np.full(2, sigma))

    def _predict(self, frame: Frame, camera: PtzCamera | None, scale: float, compensated: bool) -> Reinit:
        """EKF predict (landing check), then re-initialise (:mod:`.reinit`) or select + predict (eq. (1))."""
        cfg = self.config
        prev_camera, prev_index, prev_t_ns = self._prev
        steps = max(1, frame.index - prev_index) if prev_index is not None else 1
        dt = (frame.t_ns - prev_t_ns) / 1e9 if prev_t_ns is not None else 0.0
        if not abs(dt) <= cfg.ekf.max_gap_s:  # a time gap (or a log time jumping back): the ball is lost, not coasted
            self.misses = max(self.misses, cfg.max_predicted_frames + 1)
            self.validator.reset()
            self.scenery.reset()
            self.ekf.forget()
            self.reinit.landed_at, self.reinit.followed_landing = None, False
            steps = 1
        landing = self.ekf.advance(dt)
        height, width = frame.image.shape[:2]
        reinit = self.reinit.choose(index=frame.index, size=(width, height), scale=scale, misses=self.misses,
                                    landing=landing, camera=camera, previous=prev_camera, ekf=self.ekf, estimate=self._estimate()[:2])
        if reinit.kind:
            self.pf.initialise(state(reinit.point), spread_sigma(reinit.sigma, cfg.reinit.velocity_sigma_px * scale))
            return reinit
        self.pf.resample()
        if compensated:
            self.pf.particles = warp(self.pf.particles, self._pose_change)
        if self.misses == 1 and self._struck(scale):
            self.pf.predict(launch(cfg.particles.launch_velocity_px * scale))
        followed = self._followed = self.reinit.follows(camera, prev_camera, width, height, self._pose_change)
        self.pf.predict(motion(cfg.particles, scale, damp=self.misses > 0, steps=steps, followed=followed))
        return reinit

    def _at_border(self, bbox: np.ndarray, shape: tuple[int, ...]) -> bool:
        """Whether a blob's box ``x0, y0, w, h`` comes within one target diameter of the picture's edge."""
        margin = self.targets.diameter
        x0, y0, w, h = (float(v) for v in bbox)
        return x0 < margin or y0 < margin or x0 + w > shape[1] - margin or y0 + h > shape[0] - margin

    def _measured(self, frame: Frame, camera: PtzCamera | None, gated: GatedBlobs, ycc: np.ndarray,
                  sil: LutSilhouette, confidence: float, hat: Callable[[], np.ndarray], motion: ApparentMotion | None,
                  scale: float) -> tuple[float, float, float, float]:
        """The ball was seen: targets follow it, a confident one teaches the LUT of its background;
        with a pose the EKF takes (u, v, range)."""
        blobs, k, offset = gated.blobs, gated.selected, sil.offset
        x, y = (float(v) for v in blobs.centroid[k])
        w, h = (float(v) for v in blobs.size[k])
        if motion is not None and self.config.blobs.complete_streak > 0:  # the bright end of a faint streak: its centre
            bx, by, bw, bh = (int(v) for v in blobs.bbox[k])
            ox, oy = int(offset[0]), int(offset[1])
            pixels = sil.mask[by - oy:by - oy + bh, bx - ox:bx - ox + bw] > 0
            whole = whole_streak(hat, pixels, (bx, by), (ox, oy), motion, self.targets.diameter, self.config.blobs, scale,
                                 low_fraction=self.config.blobs.complete_streak)
            if whole is not None:
                x, y = float(whole[0]), float(whole[1])
        # a blob at the picture's edge teaches nothing: the edge may cut it (its shape), and what is seen
        # there is a ball leaving or entering the picture, often a smear (its colours)
        teaches = not self._at_border(blobs.bbox[k], frame.image.shape)
        if teaches:
            blob_cfg = self.config.blobs
            self.targets = self.targets.follow(float(blobs.area[k]), float(roundness(blobs)[k]), blob_cfg.target_rate,
                                               blob_cfg.target_shrink_rate)
        if teaches and confidence >= self.config.lut.learn_confidence:
            side = max(w, h, 2.0)  # the core ellipse (lut.core) of this box: ball pixels, not its blurred rim
            region = InitRegion(frame.index, frame.t_ns, x, y, side, side, "track")
            self.luts.learn_from_track(frame.image, region, float(blobs.area[k]), ycc)
        self.misses = 0
        self.reinit.measured(frame.index, x, y)
        if camera is not None:
            pixel = np.array([x, y])
            ground = self.range.on_ground(camera, pixel) if self.ekf.on_ground(self.config.range.ground_vz) else None
            # Rolling after the landing: ranged where the line of sight meets the ground, unless the
            # filter gates that out (the ball hopped); then, and in flight, ranged from its area.
            if ground is None or not self.ekf.update(camera, pixel, *ground, may_restart=False):
                area = self.range.area(ycc[..., 0], blobs.centroid[k] - offset, blobs.size[k], float(blobs.area[k]))
                self.ekf.update(camera, pixel, *self.range.measure(area, camera))
        return x, y, w, h
