"""Golf-ball tracker for tee-shot broadcast video (seed 000): ``GolfTracker``, name "golf".

Per frame, the paper's pipeline (Fig. 1), one method of :meth:`GolfTracker.step` and one module per stage:

1. ``_start_or_predict``, §2.3 / eq. (1): a mark (re)starts the track; else the 3-D EKF predicts and
   the samples start again at its ground contact, at an image-space parabola's bounce or, once lost,
   mid-picture (:mod:`.reinit`), else CONDENSATION selects and predicts (:mod:`.particles`).
2. ``_expect``, §2.1-2.2: search region ``I_s`` around the predicted mean, sized by the spread (:mod:`.search_region`).
3. ``_extract``, §2.1: sky/ground LUT from the region's luminance, silhouette ``I_c`` (:mod:`.silhouette`,
   :mod:`.lut`); blobs gated on area and circularity, the accepted one nearest the prediction is
   the ball (:mod:`.blobs`). Ours: the other LUT, then local contrast, when neither finds the ball.
4. ``_validate``, ours: the motion-model gate, a confidence per frame and evidence over several frames
   for a jump (:mod:`.validate`); a confirmed jump restarts the samples there (``_restart_at_jump``).
5. ``_condensation``, eqs. (2)-(3): the samples measured with the in-gate centroids, the estimate.
6. ``_learn`` (a measured ball: targets, LUTs, the EKF's range), then ``_report``: "measured" (the
   ball was seen there, with its confidence), "predicted", then "lost" (no position: the export
   interpolates) after ``max_predicted_frames`` misses (:mod:`trackreplay.trackers.lifecycle`); with a
   pose, the line of sight and X, Y, Z from the EKF, ranged from the ball's area (:mod:`.range`).

Every mark re-anchors: a box marked on frame N restarts the track there (and feeds the LUTs); a
confidently measured ball also teaches the LUT of the background it is over (:meth:`GolfLuts.learn_from_track`).
What the tracker carries between frames is in :mod:`.memory`.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from trackreplay.schemas.errors import LogError
from trackreplay.schemas.records import InitRegion
from trackreplay.trackers.base import Marked, TrackerBase, TrackState
from trackreplay.trackers.filters.particles import ParticleFilter
from trackreplay.trackers.frame import Frame
from trackreplay.trackers.geometry.box import clip_box, crop
from trackreplay.trackers.geometry.ptz import PtzCamera, zoom_area_ratio
from trackreplay.trackers.golf.blobs import (STILL, ApparentMotion, BlobTargets, GatedBlobs, refuse, roundness, select_ball,
                                             spills_over, start_targets)
from trackreplay.trackers.golf.calibration import RowEvidence, calibrated
from trackreplay.trackers.golf.config import GolfConfig
from trackreplay.trackers.golf.intermediates import GolfIntermediates
from trackreplay.trackers.golf.landing import BallisticEkf, EkfState
from trackreplay.trackers.golf.lut import LUT_NAMES, GolfLuts
from trackreplay.trackers.golf.marks import Marks
from trackreplay.trackers.golf.memory import BallLook, FrameView, PreviousFrame, Sightings
from trackreplay.trackers.golf.notices import Notices
from trackreplay.trackers.golf.particles import (DIM, ParticleSet, SampleMoments, launch, likelihood, motion, spread_sigma,
                                                 state, warp, with_camera_motion)
from trackreplay.trackers.golf.range import RangeFromArea, nearer_than_predicted
from trackreplay.trackers.golf.reinit import Reinit, ReinitPolicy
from trackreplay.trackers.golf.scenery import Scenery
from trackreplay.trackers.golf.search_region import SearchRegion, reaching, search_region
from trackreplay.trackers.golf.seen_before import LastSighting, in_last_view, was_there_before, where_the_ball_was
from trackreplay.trackers.golf.silhouette import (CONTRAST, LutSilhouette, box_silhouette, contrast_silhouette, lut_silhouette,
                                                  moving_silhouette, named_silhouette, previous_in_pose, top_hat)
from trackreplay.trackers.golf.streak import whole_streak
from trackreplay.trackers.golf.trail import Trail
from trackreplay.trackers.golf.validate import Validation, Validator
from trackreplay.trackers.golf.world_behind import WorldBehind, WorldBehindCrop
from trackreplay.trackers.lifecycle import TrackLife

NAN3 = np.full(3, np.nan)
SEEN = ("measured", "confirmed")  # the validation's verdicts that find the ball
InGate = tuple[Validation | None, np.ndarray, bool]  # Validator.seen_in_gate's answer


@dataclass(frozen=True, eq=False)
class Expected:
    """This frame's expected ball, before anything is learned from the frame (§2.1-2.2)."""

    search: SearchRegion  # I_s around the samples' predicted mean
    diameter: float  # the targets' (px)
    area: float  # the targets' (px)
    scale: float  # on every pixel parameter (:meth:`BallLook.scale`)
    lost: bool  # missed on more than max_predicted_frames frames in a row


@dataclass(frozen=True, eq=False)
class Extraction:
    """What §2.1's extraction found in ``I_s``: the silhouette, the crop's YCbCr, the gated blobs
    and the validation gate's first look at them; the cues later stages share: the samples'
    apparent motion (None: lost) and the crop's top-hat (computed when first asked)."""

    silhouette: LutSilhouette
    ycc: np.ndarray
    gated: GatedBlobs
    seen: InGate  # the validation gate's first look (:meth:`Validator.seen_in_gate`)
    motion: ApparentMotion | None
    hat: Callable[[], np.ndarray]
    behind: WorldBehindCrop | None = None  # the world behind the region (:mod:`.world_behind`; None: no judgement)

    @property
    def measures(self) -> bool:
        """The validation gate measures a blob of it."""
        return self.seen[0] is not None and self.seen[0].verdict == "measured"


class GolfTracker(TrackerBase):
    """Seed 000 (docs/papers.md §2). ``step(frame)`` returns one track (id 1) once started."""

    name = "golf"  # what the replay needs of it (a mark, one start per frame) is declared in trackers/golf/__init__.py

    def __init__(self, config: GolfConfig, rng: np.random.Generator) -> None:
        self.config = config
        self.rng = rng  # handed in by the engine: a tracker never draws its own seed
        # the pipeline's parts
        self.marks = Marks(config.snap, config.lut.core)
        self.luts = GolfLuts(config.lut, config.search.min_px, config.reference_height)
        self.pf = ParticleFilter(config.particles.n, DIM, rng)
        self.samples = SampleMoments(self.pf)
        self.ekf = BallisticEkf(config.ekf, config.ball_diameter_m / 2.0)
        self.range = RangeFromArea(config.range, config.ball_diameter_m)
        self.reinit = ReinitPolicy(config.reinit, config.search)
        self.trail = Trail(config.trail_length)
        self.validator = Validator(config.validate, config.blobs)
        self.scenery = Scenery(config.validate.still_px)
        self.world = WorldBehind(config.world_behind)
        self.notices = Notices()
        # the track, carried from frame to frame (:mod:`.memory`)
        self.started = False
        self.life = TrackLife(config.lifecycle)  # "predicted" while missed, then "lost" (:mod:`trackreplay.trackers.lifecycle`)
        self.look = BallLook()
        self.sightings = Sightings()
        self.previous = PreviousFrame()
        self.intermediates = GolfIntermediates.idle("")

    def prepare(self, marked: Marked) -> None:
        """Build the LUTs up front from ``(image, regions marked on it)`` (optional: else as frames come)."""
        for image, regions in marked:
            self.marks.remember(regions)
            for index in sorted({r.frame for r in regions}):
                self.marks.place(image, index)
                self.luts.learn(image, self.marks.on(index))

    def step(self, frame: Frame) -> list[TrackState]:
        """One frame through the paper's pipeline, stage by stage (the module docstring's list)."""
        notice = self._read_marks(frame)
        compensate = self.started and self.config.particles.compensate_camera_motion
        view = FrameView.of(frame, self.previous, self.reinit, compensate)
        begun = self._start_or_predict(view)  # §2.3, eq. (1)
        if begun is None:
            return self._idle(frame, notice)
        reinit, scale = begun
        self._follow_camera(view, reinit)
        ball = self._expect(view, scale)  # §2.1-2.2
        found = self._extract(view, ball)  # §2.1
        check = self._validate(view, ball, found)  # ours
        reinit, found = self._accept(check, found, reinit, scale)  # ours: a confirmed jump restarts the samples
        estimate = self._condensation(frame.index, check, found.gated, scale)  # eqs. (2)-(3)
        box, status = self._outcome(view, ball, found, check, estimate)  # a measured ball teaches; §2.3 the EKF
        los = view.camera.line_of_sight(np.array([box[:2]]))[0] if view.camera is not None else NAN3
        self._remember(view, ball, found.gated, box[:2] if status == "measured" else None, los)
        self.previous = PreviousFrame.of(frame)
        self._keep_picture(frame)
        self.intermediates = GolfIntermediates(
            "ptz" if view.camera is not None else "image", reinit, ball.search, found.silhouette, found.gated,
            ParticleSet(self.pf.particles, self.pf.weights, estimate), EkfState.of(self.ekf, view.camera),
            self.trail.points(view.camera), notice, check, evidence := self._evidence(status, check.confidence))
        return [self._report(view, box, los, estimate, status, evidence)]

    # --- the stages, in pipeline order --------------------------------------------------------------
    def _read_marks(self, frame: Frame) -> str:
        """The log's marks and this frame's, placed on the ball and taught to the LUTs; the notice for a
        log without encoders or marks."""
        self.marks.remember_log(frame.all_hints)
        self.marks.remember(frame.hints)
        self.marks.place(frame.image, frame.index)
        self.luts.learn(frame.image, self.marks.on(frame.index))
        return self.notices.check(frame.camera is not None, bool(self.marks))

    def _start_or_predict(self, view: FrameView) -> tuple[Reinit, float] | None:
        """§2.3: a mark, the first and every later one, (re)starts the track; between marks the 3-D filter
        predicts and the samples start again or select + predict (eq. (1)). With this frame's scale
        (a marked ball's size may widen it). None: nothing marked yet."""
        frame = view.frame
        height = frame.image.shape[0]
        if self.started and not self.marks.on(frame.index):
            scale = self._scale(height)
            return self._predict(view, scale), scale
        region = self.marks.start_region(frame.index)
        if region is None:
            return None
        reinit = self._start(frame, region)
        return reinit, self._scale(height)

    def _idle(self, frame: Frame, notice: str) -> list[TrackState]:
        """Nothing marked yet: no track."""
        self.intermediates = GolfIntermediates.idle(notice)
        self.previous = PreviousFrame.of(frame)
        self._keep_picture(frame)
        return []

    def _follow_camera(self, view: FrameView, reinit: Reinit) -> None:
        """With encoders, the targets, the tentative tracks and the still scenery follow the pose change."""
        previous = view.previous.camera
        if view.camera is not None and previous is not None and reinit.kind != "start":
            self.look.targets = self.look.targets.zoomed(zoom_area_ratio(previous, view.camera))
            self.validator.follow_camera(view.pose_change)
            self.scenery.follow_camera(view.pose_change)

    def _expect(self, view: FrameView, scale: float) -> Expected:
        """§2.1 ``I_s`` around the samples' mean, §2.2 sized from their spread, reaching where a jump's
        evidence will be (ours); the ball's expected size this frame (before it learns)."""
        width, height = view.size
        diameter, area = self.look.targets.diameter, self.look.targets.area
        search = search_region(*self.samples.moments(0), diameter, width, height, scale, self.config.search)
        if (ahead := self.validator.next_point(diameter, scale)) is not None:
            search = reaching(search, *ahead, width, height)
        return Expected(search, diameter, area, scale, self.life.lost)

    def _extract(self, view: FrameView, ball: Expected) -> Extraction:
        """§2.1 the LUT silhouette ``I_c`` in ``I_s`` and its blobs gated on area and circularity. Once
        lost, a ball moving against the world is a candidate too; while not lost, and the gate measures
        nothing, the other LUT or local contrast may find it (:meth:`_other_silhouettes`)."""
        cfg = self.config
        sil, ycc = lut_silhouette(view.frame.image, ball.search.box, self.luts, self.look.lut_name)
        self.look.lut_name = sil.lut_name
        motion = None if ball.lost else self._apparent_motion(ball.search.centre, view)
        hat = functools.cache(lambda: top_hat(ycc, ball.diameter, cfg.contrast, ball.scale))  # contrast and moving share it
        offset = sil.offset
        moving = (lambda: self._moving(view, ycc, offset, ball, hat)) if cfg.contrast.moving else (lambda: None)
        if ball.lost and (mask := moving()) is not None:
            sil = dataclasses.replace(sil, mask=sil.mask | mask)
        behind = self._world_behind(view, ycc, offset)
        gated, seen = self._blobs(sil, ball, view.size, ball.lost, motion, behind)
        found = Extraction(sil, ycc, gated, seen, motion, hat, behind)
        if not ball.lost and not found.measures:
            found = self._other_silhouettes(found, ball, view.size, moving) or found
        return found

    def _validate(self, view: FrameView, ball: Expected, found: Extraction) -> Validation:
        """Ours (:mod:`.validate`): the motion-model gate, a confidence, and a jump only on evidence over
        several frames, then refused when the 3-D filter has the ball farther (``_too_near``) or when
        it was already there beside the ball (``_seen_before``)."""
        frame, gated = view.frame, found.gated
        check = self.validator.validate(index=frame.index, gated=gated, predicted=ball.search.centre,
                                        spread=ball.search.spread, diameter=ball.diameter, size=view.size,
                                        scale=ball.scale, lost=ball.lost, entry_only=not self._centre_search(view),
                                        seen=found.seen, repeat=self._repeated(frame.image, ball.search.box))
        if check.verdict == "confirmed" and self._too_near(view.camera):
            check = dataclasses.replace(check, verdict="too_near", confidence=0.0)
        if check.verdict == "confirmed" and self._seen_before(view, gated.blobs.centroid[check.candidate], ball.scale):
            check = dataclasses.replace(check, verdict="seen_before", confidence=0.0)
            self._refuse_for_good(view, gated.blobs.centroid[check.candidate], ball.scale)
        return check

    def _accept(self, check: Validation, found: Extraction, reinit: Reinit, scale: float) -> tuple[Reinit, Extraction]:
        """The validated blob is the frame's ball (``GatedBlobs.selected``; -1: not seen); a confirmed
        jump first restarts the samples there (:meth:`_restart_at_jump`)."""
        if check.verdict == "confirmed":
            reinit, found = self._restart_at_jump(check, found, scale)
        selected = check.candidate if check.verdict in SEEN else -1
        return reinit, dataclasses.replace(found, gated=dataclasses.replace(found.gated, selected=selected))

    def _restart_at_jump(self, check: Validation, found: Extraction, scale: float) -> tuple[Reinit, Extraction]:
        """A confirmed jump: the samples start again at its blob, moving as the tentative track moved
        (its motion is the streak's, :mod:`.streak`); the ball's size starts again from the confirmed blobs."""
        cfg = self.config.particles
        point = found.gated.blobs.centroid[check.candidate]
        sigma = cfg.init_spread_px * scale
        velocity, unsure = self.validator.confirmed_velocity()
        motion = ApparentMotion(np.asarray(velocity, float), float(unsure))
        self.pf.initialise(state(point, velocity), spread_sigma(sigma, max(cfg.init_velocity_spread_px * scale, unsure)))
        area, rnd = self.validator.confirmed_shape()
        self.look.targets = BlobTargets(area, float(min(max(rnd, 0.6), 1.0)))
        self.validator.reset()
        self.sightings.last_step = None
        return Reinit("confirmed", point.copy(), np.full(2, sigma)), dataclasses.replace(found, motion=motion)

    def _condensation(self, index: int, check: Validation, gated: GatedBlobs, scale: float) -> np.ndarray:
        """Eq. (2): the samples weighed by the in-gate centroids (a confirmed jump's blob alone), after
        importance samples around a measured blob (ours, ``detection_share``); eq. (3): the estimate."""
        cfg = self.config.particles
        observed = gated.blobs.centroid[[check.candidate] if check.verdict == "confirmed" else check.in_gate]
        if check.verdict == "measured" and cfg.detection_share > 0:
            self._inject(index, gated.blobs.centroid[check.candidate], scale)
        self.pf.weigh(likelihood(observed, cfg.sigma_px * scale, cfg.alpha / scale))
        return self.samples.estimate()

    def _outcome(self, view: FrameView, ball: Expected, found: Extraction, check: Validation,
                 estimate: np.ndarray) -> tuple[tuple[float, float, float, float], str]:
        """The frame's box and status: a seen ball's, "measured" (and learned from, :meth:`_learn`); else the
        estimate with the expected size, "predicted" and then "lost" (:mod:`trackreplay.trackers.lifecycle`)."""
        if check.verdict in SEEN:
            return self._learn(view, found, check.confidence, ball.scale), self.life.supported()
        return (float(estimate[0]), float(estimate[1]), ball.diameter, ball.diameter), self.life.missed()

    def _learn(self, view: FrameView, found: Extraction, confidence: float, scale: float) -> tuple[float, float, float, float]:
        """The ball was seen: its centre and size (a faint streak's whole length); the targets follow it,
        a confident one teaches the LUT of its background; with a pose the EKF takes (u, v, range)."""
        blobs, k = found.gated.blobs, found.gated.selected
        x, y = self._centre(found, scale)
        w, h = (float(v) for v in blobs.size[k])
        # a blob at the picture's edge teaches nothing: the edge may cut it (its shape), and what is seen
        # there is a ball leaving or entering the picture, often a smear (its colours)
        teaches = not self._at_border(blobs.bbox[k], view.frame.image.shape)
        if teaches:
            blob_cfg = self.config.blobs
            self.look.targets = self.look.targets.follow(float(blobs.area[k]), float(roundness(blobs)[k]),
                                                         blob_cfg.target_rate, blob_cfg.target_shrink_rate)
        if teaches and confidence >= self.config.lut.learn_confidence:
            side = max(w, h, 2.0)  # the core ellipse (lut.core) of this box: ball pixels, not its blurred rim
            region = InitRegion(view.frame.index, view.frame.t_ns, x, y, side, side, "track")
            self.luts.learn_from_track(view.frame.image, region, float(blobs.area[k]), found.ycc)
        self.reinit.measured(view.frame.index, x, y)
        if view.camera is not None:
            self._range(view.camera, found, np.array([x, y]))
        return x, y, w, h

    def _remember(self, view: FrameView, ball: Expected, gated: GatedBlobs, measured: tuple[float, float] | None,
                  los: np.ndarray) -> None:
        """The frame's sighting (None: not measured), its still blobs (:mod:`.scenery`) and the drawn trail."""
        frame = view.frame
        if measured is not None:
            sighting = LastSighting(frame.image, view.camera, measured, ball.diameter, ball.area)
            self.sightings.add(frame.index, *measured, sighting)
        self.scenery.update(frame.index, gated.blobs, gated.accepted | (gated.reason == STILL), measured, ball.diameter,
                            ball.scale)
        self.trail.add(measured, los, self.ekf.x)

    def _evidence(self, status: str, confidence: float) -> RowEvidence:
        """What the row's reported confidence is calibrated from (:mod:`.calibration`): the validation's
        confidence, whether the ball was measured, and the misses in a row over ``lost_after``."""
        return RowEvidence(float(min(max(confidence, 0.0), 1.0)), status == "measured",
                           self.life.misses / self.config.lifecycle.lost_after)

    def _report(self, view: FrameView, box: tuple[float, float, float, float], los: np.ndarray, estimate: np.ndarray,
                status: str, evidence: RowEvidence) -> TrackState:
        """The frame's row: the image position and size, with a pose the EKF's X, Y, Z and the line of
        sight, the samples' velocity (with the camera's own motion when compensated), the confidence as
        P(within 10 px) (:mod:`.calibration`); "lost": no position."""
        if status == "lost":
            return TrackState(1, status="lost")
        x, y, w, h = box
        vx, vy = float(estimate[2]), float(estimate[3])
        if view.compensated:  # the velocity in this pose's pixels includes the camera's own motion
            vx, vy = with_camera_motion((vx, vy), (x, y), view.pose_change)
        X, Y, Z = (float(v) for v in self.ekf.x[:3]) if self.ekf.initialised else (None, None, None)
        dx, dy, dz = (float(v) for v in los) if view.camera is not None else (None, None, None)
        confidence = calibrated(evidence) if self.config.calibrate else evidence.gate
        return TrackState(1, x, y, w, h, X, Y, Z, dx, dy, dz, vx, vy, status, confidence=confidence)

    # --- §2.3: start, predict, re-initialise ---------------------------------------------------------
    def _start(self, frame: Frame, region: InitRegion) -> Reinit:
        """§2.3 initialisation: targets from the marked box's own silhouette, samples around the box."""
        cfg = self.config
        self.started = True
        self.life.start()
        self.sightings.restart()  # a re-anchor is no step of the ball's
        self.validator.reset()
        self.validator.seed_at(frame.index, (region.x, region.y))  # its speed is unknown until a step is seen
        self.scenery.reset()  # the user says where the ball is
        self.reinit.landed_at, self.reinit.followed_landing = None, False  # a landing before the mark is not this track's
        name, self.look.lut_name = self.luts.start_names(frame.image, region)
        found, ycc, mask = self._marked_ball(frame.image, region, self._scale(frame.image.shape[0]))  # the last ball's scale
        self.look.targets = found or BlobTargets(math.pi / 4.0 * region.w * region.h, cfg.blobs.initial_circularity)
        self.look.marked_diameter = found.diameter if found is not None else 0.0  # (a box may be drawn loose)
        scale = self._scale(frame.image.shape[0])
        if found is not None:
            self.range.learn_ball(ycc[..., 0], mask)
        if frame.camera is not None and name == "ground":  # a ball resting on the ground calibrates the range
            self.range.calibrate(frame.camera, np.array([region.x, region.y]), self.look.targets.area)
        sigma, centre = cfg.particles.init_spread_px * scale, np.array([region.x, region.y])
        self.pf.initialise(state(centre), spread_sigma(sigma, cfg.particles.init_velocity_spread_px * scale))
        return Reinit("start", centre, np.full(2, sigma))

    def _marked_ball(self, image: np.ndarray, region: InitRegion,
                     scale: float) -> tuple[BlobTargets | None, np.ndarray, np.ndarray]:
        """The marked box's own silhouette: the ball's targets (None: no blob), the box's YCbCr and
        mask. A box whose colours run past twice its size holds no ball to track: refused."""
        box = np.array([region.x - region.w, region.y - region.h, 2 * region.w, 2 * region.h])
        ycc, offset, mask = box_silhouette(image, box, self.luts, self.look.lut_name)
        found = start_targets(mask, offset, np.array([region.x, region.y]), self.config.blobs, scale)
        if found is not None and self._spills_over(image, region):
            raise LogError(f"the box marked on frame {region.frame} ({region.w:g}x{region.h:g} px round {region.x:g},{region.y:g}) "
                           "holds no ball the golf tracker can tell from its surroundings: the colours it picks out fill the "
                           "box and run past twice its size; draw the box round the ball alone (`trackreplay frame LOG "
                           f"{region.frame}` shows the pixel grid)")
        return found, ycc, mask

    def _predict(self, view: FrameView, scale: float) -> Reinit:
        """EKF predict (landing check), then re-initialise (:mod:`.reinit`) or select + predict (eq. (1))."""
        cfg, frame, previous = self.config, view.frame, view.previous
        steps = max(1, frame.index - previous.index) if previous.index is not None else 1
        dt = (frame.t_ns - previous.t_ns) / 1e9 if previous.t_ns is not None else 0.0
        if not abs(dt) <= cfg.ekf.max_gap_s:  # a time gap (or a log time jumping back): the ball is lost, not coasted
            self._lose_at_gap()
            steps = 1
        landing = self.ekf.advance(dt)
        reinit = self.reinit.choose(index=frame.index, size=view.size, scale=scale, life=self.life, landing=landing,
                                    camera=view.camera, previous=previous.camera, ekf=self.ekf,
                                    estimate=self.samples.estimate()[:2])
        if reinit.kind:
            self.pf.initialise(state(reinit.point), spread_sigma(reinit.sigma, cfg.reinit.velocity_sigma_px * scale))
            return reinit
        self._select_and_predict(view, scale, steps)
        return reinit

    def _select_and_predict(self, view: FrameView, scale: float, steps: int) -> None:
        """Eq. (1): resample, move with the pose change (compensated samples), then the motion model,
        with a strike's launch first (ours: a ball at rest missed for the first time was struck)."""
        cfg = self.config.particles
        self.pf.resample()
        if view.compensated:
            self.pf.particles = warp(self.pf.particles, view.pose_change)
        if self.life.misses == 1 and self._struck(scale):
            self.pf.predict(launch(cfg.launch_velocity_px * scale))
        self.pf.predict(motion(cfg, scale, damp=self.life.misses > 0, steps=steps, followed=view.follows))

    def _lose_at_gap(self) -> None:
        """A time gap: the ball is lost at once, and nothing from before it is carried over it."""
        self.life.lose()
        self.validator.reset()
        self.scenery.reset()
        self.ekf.forget()
        self.reinit.landed_at, self.reinit.followed_landing = None, False

    def _struck(self, scale: float) -> bool:
        """The ball, missed this frame for the first time, was lying still when last seen, so it was
        struck: seen still on ``rest_frames`` frames, or on its marked frame only and as a sharp disc
        there (round, no motion blur: a mark on the launch frame of a 30 fps clip, gone 40-70 px
        a frame later; a streak marked in flight is no ball at rest). Never for a speck (a target area
        under ``particles.strike_min_area_px``): a far ball rolling along the line of sight looks still
        without lying still, and the wide search a strike opens finds only other specks around it."""
        cfg, targets = self.config.particles, self.look.targets
        if targets is not None and targets.area < cfg.strike_min_area_px:
            return False
        if self.sightings.count == 1 and targets is not None:  # (never seen since the mark: nothing known)
            return targets.circularity >= cfg.rest_roundness
        return self.reinit.at_rest(cfg.rest_frames, cfg.rest_px * scale)

    def _inject(self, index: int, point: np.ndarray, scale: float) -> None:
        """Importance samples around this frame's measured blob, moving as it moved since the last measured frame."""
        cfg = self.config.particles
        last = self.sightings.last_step
        velocity = point - np.array(last[1:]) if last is not None and last[0] == index - 1 else self.samples.estimate()[2:]
        # As spread out as the cloud itself: the samples move to the blob without the cloud
        # narrowing (a ball at rest must still be caught when it is struck).
        sigma = np.maximum(self.pf.spread(), spread_sigma(cfg.noise_pos_px * scale, cfg.noise_vel_px * scale))
        self.pf.inject(cfg.detection_share, state(point, velocity), sigma)

    # --- §2.1: silhouettes and blobs -----------------------------------------------------------------
    def _scale(self, height: int) -> float:
        """:meth:`BallLook.scale` with the config's references."""
        return self.look.scale(height, self.config.reference_height, self.config.reference_ball_px)

    def _apparent_motion(self, position: np.ndarray, view: FrameView) -> ApparentMotion:
        """The samples' mean velocity as the image sees it (with the camera's own motion when the
        samples are compensated) and its spread: how long the ball's streak may be this frame."""
        velocity, spread = self.samples.moments(2)
        if view.compensated:
            velocity = np.array(with_camera_motion(tuple(velocity), tuple(position), view.pose_change))
        return ApparentMotion(velocity, float(np.max(spread)))

    def _blobs(self, sil: LutSilhouette, ball: Expected, size: tuple[int, int], lost: bool,
               motion: ApparentMotion | None, behind: WorldBehindCrop | None) -> tuple[GatedBlobs, InGate]:
        """§2.1's blob gate (:func:`select_ball`), then still scenery and blobs that do not stand out from
        the world behind them refused (:mod:`.scenery`, :mod:`.world_behind`), and the validation gate's
        first look (:meth:`Validator.seen_in_gate`, which changes nothing)."""
        centre = ball.search.centre
        gated = select_ball(sil.mask, sil.offset, centre, self.look.targets, self.life.misses, self.config.blobs, ball.scale,
                            lost=lost, motion=motion)
        if len(self.scenery.points):
            gated = refuse(gated, self.scenery.on_scenery(gated.blobs, ball.scale), STILL, centre)
        if behind is not None and len(gated.blobs):
            gated = refuse(gated, behind.still(gated.blobs, gated.accepted), STILL, centre)
        seen = self.validator.seen_in_gate(gated=gated, predicted=centre, spread=ball.search.spread,
                                           diameter=ball.diameter, size=size, scale=ball.scale, lost=lost)
        return gated, seen

    def _other_silhouettes(self, found: Extraction, ball: Expected, size: tuple[int, int],
                           moving: Callable[[], np.ndarray | None]) -> Extraction | None:
        """Ours, when the LUT chosen sees no ball near the prediction. The background changed under the
        ball faster than the luminance switch (tree line, horizon): the ball may pass the other LUT
        (where its background is around the ball, :meth:`_background_here`); else the local-contrast
        silhouette, then the moving one (with a pose). Each taken only when the gate measures a blob
        of it (same gate, same confidence). None: none did."""
        sil, ycc = found.silhouette, found.ycc
        for name in (n for n in self.luts.names if n != sil.lut_name and self._background_here(sil, n)):
            other = LutSilhouette(name, sil.lut_scores, named_silhouette(ycc, self.luts, name), sil.offset)
            alt = dataclasses.replace(found, silhouette=other, **self._gate_fields(other, ball, size, found))
            if alt.measures:
                self.look.lut_name = name
                return alt
        if not self.config.contrast.enabled:
            return None
        cfg = self.config.contrast
        for make in (lambda: contrast_silhouette(ycc, ball.diameter, cfg, ball.scale, hat=found.hat()), moving):
            mask = make()  # the moving one second and alone: joined, its pixels would reshape a contrast blob
            if mask is None:
                continue
            other = LutSilhouette(CONTRAST, sil.lut_scores, mask, sil.offset)
            alt = dataclasses.replace(found, silhouette=other, **self._gate_fields(other, ball, size, found))
            if alt.measures:
                return alt
        return None

    def _gate_fields(self, sil: LutSilhouette, ball: Expected, size: tuple[int, int], found: Extraction) -> dict:
        """:meth:`_blobs` of a silhouette tried while not lost, as :class:`Extraction` fields."""
        gated, seen = self._blobs(sil, ball, size, False, found.motion, found.behind)
        return {"gated": gated, "seen": seen}

    def _background_here(self, sil: LutSilhouette, name: str) -> bool:
        """LUT ``name``'s background is at least ``lut.other_min_share`` of the search region (its
        score in :meth:`GolfLuts.choose`): a LUT says nothing about colours it never saw around the ball."""
        share = float(sil.lut_scores[LUT_NAMES.index(name)])
        return share >= self.config.lut.other_min_share  # (NaN, a LUT not built: False)

    def _world_behind(self, view: FrameView, ycc: np.ndarray, offset: np.ndarray) -> WorldBehindCrop | None:
        """The world behind the search region (:mod:`.world_behind`) on a frame without a pose and
        without a mark (the user says where the ball is), with where the ball rests if it has not
        moved since it was first measured (:meth:`Sightings.resting`); None: no judgement."""
        frame = view.frame
        if frame.camera is not None or self.marks.on(frame.index) or ycc.size == 0:
            return None
        return self.world.behind(frame.index, frame.image, ycc[..., 0], (int(offset[0]), int(offset[1])),
                                 self.sightings.resting(frame.index))

    def _keep_picture(self, frame: Frame) -> None:
        """The frame's picture joins the recent ones (:mod:`.world_behind`; without a pose only)."""
        if frame.camera is None:
            self.world.push(frame.index, frame.image)

    def _moving(self, view: FrameView, ycc: np.ndarray, offset: np.ndarray, ball: Expected,
                hat: Callable[[], np.ndarray]) -> np.ndarray | None:
        """The moving-against-the-world silhouette over the crop (None: no pose for this frame and
        the one before it, or not the frame right after it); ``hat()`` gives the crop's top-hat."""
        cfg, frame, previous = self.config, view.frame, view.previous
        if (not cfg.contrast.moving or frame.camera is None or previous.camera is None or previous.image is None
                or previous.index != frame.index - 1 or ycc.size == 0):
            return None
        if previous.t_ns is not None and not 0 < frame.t_ns - previous.t_ns <= cfg.ekf.max_gap_s * 1e9:
            return None  # a time gap: the frame before is no picture of where the world was a frame ago
        before = previous_in_pose(previous.image, view.pose_change, (int(offset[0]), int(offset[1])), ycc.shape[:2])
        return moving_silhouette(ycc, before, ball.diameter, cfg.contrast, ball.scale, hat=hat())

    def _spills_over(self, image: np.ndarray, region: InitRegion) -> bool:
        """The marked box's colours pick out more than twice the box (:func:`.blobs.spills_over`), seen
        in a crop four times the box and 16 px more each way."""
        w, h = region.w * 4.0 + 32.0, region.h * 4.0 + 32.0
        _, offset, mask = box_silhouette(image, np.array([region.x - w / 2, region.y - h / 2, w, h]), self.luts,
                                         self.look.lut_name)
        return spills_over(mask, offset, (region.x, region.y), (region.w, region.h))

    # --- ours: validation checks ---------------------------------------------------------------------
    def _centre_search(self, view: FrameView) -> bool:
        """:meth:`ReinitPolicy.centre_search`, with the frame's own :attr:`FrameView.follows`."""
        lost = self.reinit.cfg.lost
        return view.follows if lost == "auto" else lost == "centre"

    def _repeated(self, image: np.ndarray, box: np.ndarray) -> bool:
        """The search region shows exactly what it showed on the frame before (a repeated picture: 30 fps
        shown at 50 or 60 by copying frames; a camera's noise makes two real pictures differ)."""
        previous = self.previous.image
        if previous is None or previous.shape != image.shape:
            return False
        x0, y0, w, h = (float(v) for v in box)
        corners = clip_box(x0, y0, x0 + w, y0 + h, image.shape[1], image.shape[0])  # as the silhouettes crop it
        return bool(np.array_equal(crop(image, corners)[0], crop(previous, corners)[0]))

    def _too_near(self, camera: PtzCamera | None) -> bool:
        """A confirmed track's blobs are too big for the ball where the 3-D filter has it
        (``validate.confirm_max_nearer``; never without encoders or a running filter)."""
        factor = self.config.validate.confirm_max_nearer
        if factor <= 0 or camera is None or not self.ekf.initialised:
            return False
        area, _ = self.validator.confirmed_shape()
        range_m, _ = self.range.measure(area, camera)
        return nearer_than_predicted(range_m, self.ekf.kf.x[:3], self.ekf.kf.P[:3, :3], camera.position, factor)

    def _seen_before(self, view: FrameView, point: np.ndarray, scale: float) -> bool:
        """A confirmed track's blob was already there, beside the ball, when the ball was last
        measured (``validate.confirm_not_seen_before``, :mod:`.seen_before`)."""
        cfg = self.config
        if not cfg.validate.confirm_not_seen_before or self.sightings.last is None:
            return False
        area, _ = self.validator.confirmed_shape()
        return was_there_before(self.sightings.last, view.camera, point, area, self.luts, self.look.lut_name,
                                cfg.validate.still_px * scale, cfg.blobs.area_tolerance, view.frame.image)

    def _refuse_for_good(self, view: FrameView, point: np.ndarray, scale: float) -> None:
        """A blob refused as seen before stays refused (:mod:`.scenery`): otherwise, in the gate, it draws
        the samples to it and is measured there; but not where the ball itself was last seen (a ball
        found again there, half hidden, would be refused for good)."""
        last = self.sightings.last
        then = in_last_view(last, view.camera, point, 0.0, view.frame.image)[:2]  # the place in the last sighting's pixels
        if not where_the_ball_was(last, then, self.config.validate.still_px * scale):
            self.scenery.add(point)

    # --- a measured ball -----------------------------------------------------------------------------
    def _centre(self, found: Extraction, scale: float) -> tuple[float, float]:
        """The selected blob's centroid, or the centre of the whole streak when it is the bright end of
        a faint one (``blobs.complete_streak``, :mod:`.streak`)."""
        gated, cfg = found.gated, self.config.blobs
        blobs, k, offset = gated.blobs, gated.selected, found.silhouette.offset
        x, y = (float(v) for v in blobs.centroid[k])
        if found.motion is not None and cfg.complete_streak > 0:
            bx, by, bw, bh = (int(v) for v in blobs.bbox[k])
            ox, oy = int(offset[0]), int(offset[1])
            pixels = found.silhouette.mask[by - oy:by - oy + bh, bx - ox:bx - ox + bw] > 0
            whole = whole_streak(found.hat, pixels, (bx, by), (ox, oy), found.motion, self.look.targets.diameter, cfg,
                                 scale, low_fraction=cfg.complete_streak)
            if whole is not None:
                x, y = float(whole[0]), float(whole[1])
        return x, y

    def _at_border(self, bbox: np.ndarray, shape: tuple[int, ...]) -> bool:
        """Whether a blob's box ``x0, y0, w, h`` comes within one target diameter of the picture's edge."""
        margin = self.look.targets.diameter
        x0, y0, w, h = (float(v) for v in bbox)
        return x0 < margin or y0 < margin or x0 + w > shape[1] - margin or y0 + h > shape[0] - margin

    def _range(self, camera: PtzCamera, found: Extraction, pixel: np.ndarray) -> None:
        """§2.3 the EKF's measurement (u, v, range). Rolling after the landing: ranged where the line of
        sight meets the ground, unless the filter gates that out (the ball hopped); then, and in
        flight, ranged from its area."""
        blobs, k, offset = found.gated.blobs, found.gated.selected, found.silhouette.offset
        ground = self.range.on_ground(camera, pixel) if self.ekf.on_ground(self.config.range.ground_vz) else None
        if ground is None or not self.ekf.update(camera, pixel, *ground, may_restart=False):
            area = self.range.area(found.ycc[..., 0], blobs.centroid[k] - offset, blobs.size[k], float(blobs.area[k]))
            self.ekf.update(camera, pixel, *self.range.measure(area, camera))
