"""Colour particle filter robust to background, illumination and size (seed 002): ``ColorPfTracker``, "colorpf".

Per frame, the paper's pipeline (§2-§4), one module per stage:

1. Before the mark: frames are kept for the background (:mod:`.reference`).
2. At the mark: background subtraction in the marked box, reference ``H_ref`` by eq. (7) (the
   correction in docs/papers.md §3), ``S`` of eq. (9) from the marked box's area and its foot's distance, ``R_0`` from
   the box; the particles start on the box.
3. Then (``_track``, one method per stage): select (systematic resampling, the engine's Generator) ->
   eq. (2) predict, ``w, h`` from the size estimate (``_predict``; :mod:`.motion`, :mod:`.size`) ->
   eqs. (4)-(5) weigh with the H-S histogram intersection (:mod:`.likelihood`; our cues, ``_cues``)
   -> eq. (6) estimate (``_weigh``) -> ours: refine or hold (``_refine``, ``_hold``) -> eqs. (10)-(11)
   ``R_t`` with jump rejection (``_size_and_aspect``; :mod:`.aspect`) -> confidence (``_score``) ->
   ours: adapt (``_adapt``) -> status (``_status``).
4. Status: the confidence places the estimate box's intersection ``S`` between the background's
   score and the marked box's (see ``ColorPfConfig.measured_fraction``); "measured" from 0.5 on,
   "predicted" otherwise; "lost" (no position) after ``lost_after`` such frames in a row, until
   the colour is found again (the track's life: :mod:`trackreplay.trackers.lifecycle`). When the background scores within ``min_separation`` of the mark
   (H-S cannot tell them apart), it cannot set the scale: ``c = S / S_mark`` then, said once.
   With an "early" reference ``S_mark`` is the marked box's score against the new reference.
   Ours (``neighbour_check``): a "measured" estimate with a neighbouring box (its size, beside it)
   holding more foreground than the marked box did is reported "predicted" (on or against a
   larger moving region; :func:`.foreground.neighbour_shares`).
   Ours (``support``, :meth:`_unsupported`): a row neither "measured" nor placed by a foreground region has
   no support; its box is at most the last supported one's, its confidence falls, and after
   ``support.lost_unsupported`` such frames in a row (2 s) the track is "lost" (:mod:`.support`).

Departures of ours, each a switch (``colorpf.config``; measured in docs/colorpf.md): by default the
histograms are Epanechnikov-weighted, the reference adapts (rate 0.05, only while the confidence
against the reference as built is high and tells the target from the background) and, once eq. (7)'s
background exists, each particle's likelihood is multiplied by a foreground centre-surround cue
(:mod:`~trackreplay.trackers.colorpf.foreground`; the confidence stays colour's alone) and the estimate
is refined onto the foreground region it sits on when that region is consistent with the target
(``refine.mode = "foreground"``, :func:`.foreground.foreground_region`: the cloud moves with it,
without a ground plane the size follows it, and such a frame does not count towards "lost"); with an
"early" background each frame's tracked box is left out of the median, so it is ready once the target
has left its marked box (``reference.exclude``, :class:`.reference.BackgroundFrames`); and while a larger moving region is
beside the estimate (the neighbour check's condition) and no region places it, the estimate is held
on the motion prediction, the last estimate plus the track's velocity (``hold``, :meth:`_hold`; the rows made before
the background are vouched for by the foreground region on the median's frames once it exists, ``hold.early``,
:meth:`_revouch`); the camera's
motion since the marked frame (a similarity from corners, :mod:`.camera`) carries the early median's frames back to
the marked view, the background to each frame's view and the particle cloud with the scene (``camera.compensate``;
a still camera measures the identity and is unchanged; where the background was resampled, the foreground test
tolerates its 3x3 neighbourhood, ``reference.registration_tolerance``); the constants that describe time (the
position noise, the hold's memory and horizon, the early median's window) are kept in seconds at the log's frame
interval (``frame_rate``, :mod:`.timing`; a 30 fps log is unchanged). Issue 31 (docs/colorpf.md, "Issue 31"):
a grey picture is histogrammed by grey level and gradient direction (``likelihood.grey``,
:mod:`~trackreplay.trackers.appearance.gradient`); the camera's measured zoom moves the cloud but does not
size the target (``camera.scale_size``); a region grows the box by at most ``refine.max_growth`` per side
past the last "measured" box; N = 100 particles; the reported confidence is the fitted probability that
the row is right (``calibrate``, :mod:`.calibration`); on a grey picture the layout (template) cue is on too
(``likelihood.grey_template``), and wherever that cue is on a colour match is "measured" only when the estimate's
box correlates with the target's template (``likelihood.layout_vouches``, :meth:`_layout_agrees`); while lost, a scan
of the whole picture with the reference re-seeds the cloud on a single clear match (``redetect``, :meth:`_redetect`,
:mod:`.redetect`); an eq. (7) reference against which the mark does not stand out from the background is refused
(``reference.refuse_unseparated``, :meth:`_refuse_reference`: the marked box's own histogram, a match "measured" only as
the picture's single match, :meth:`_single_match`), and once a frame's background fails to explain it, the background
and the eq. (7) reference made from it are given up for good (``reference.forget_on_change``, :meth:`_forget_background`).
Off by default,
two-part histograms, a constant-velocity drift, a final mean-shift refinement (the particle cloud
moves with it) and a scale random walk without a ground plane. ``config.PAPER`` restores the paper.

The first mark in the log (lowest frame; on one frame, the first listed), whatever its label,
starts the track; later marks are not used (a notice says so).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from trackreplay.schemas.errors import LogError
from trackreplay.schemas.records import InitRegion
from trackreplay.trackers.appearance.color import saturated_share
from trackreplay.trackers.appearance.gradient import edge_threshold
from trackreplay.trackers.base import TrackerBase, TrackState
from trackreplay.trackers.colorpf.aspect import AspectEstimate, AspectUpdate, box_from_area
from trackreplay.trackers.colorpf.calibration import RowEvidence, calibrated, cloud_evidence
from trackreplay.trackers.colorpf.camera import IDENTITY as NO_MOTION, CameraMotion, apply, resamples, scale_of, snap
from trackreplay.trackers.colorpf.config import ColorPfConfig
from trackreplay.trackers.colorpf.foreground import (IDENTITY, Band, brightness_gain, foreground_contrast,
                                                     foreground_region, neighbour_shares, region_layout,
                                                     registration_band, scene_changed)
from trackreplay.trackers.colorpf.hold import VouchedMotion
from trackreplay.trackers.colorpf.intermediates import ColorPfIntermediates
from trackreplay.trackers.colorpf.likelihood import ColourModel, Measurement, box_histogram, mean_shift, measure
from trackreplay.trackers.colorpf.motion import position_sigma, standing_box, transition, vouched_prediction
from trackreplay.trackers.colorpf.redetect import scan, unique_best
from trackreplay.trackers.colorpf.reference import (BackgroundFrames, Reference, box_reference, marked_box,
                                                    subtract_and_mix)
from trackreplay.trackers.colorpf.size import (WeakPerspectiveSize, foot_points, ground_distance, horizon_side,
                                              region_area)
from trackreplay.trackers.colorpf.support import Support
from trackreplay.trackers.colorpf.template import TemplateModel, template_scores
from trackreplay.trackers.colorpf.timing import FrameClock, frames_for, noise_for, smoothing_for
from trackreplay.trackers.colorpf.warped import WarpedBackground, warped_band
from trackreplay.trackers.filters.particles import ParticleFilter
from trackreplay.trackers.frame import Frame
from trackreplay.trackers.geometry.ground_plane import GroundPlane
from trackreplay.trackers.lifecycle import Run, TrackLife

# reference.refuse_unseparated: the box sizes a single match is checked over, an octave each way in half octaves
# (nothing sets the size once eq. (7)'s background is refused: the target may have grown or shrunk since)
SINGLE_MATCH_SCALES = (0.5, 2 ** -0.5, 1.0, 2 ** 0.5, 2.0)
GREY_SHARE = 0.005  # fewer saturated pixels than this share around the marked box: a grey picture
GREY_CONTEXT = 3.0  # ... in the marked box times this per axis: where the particles' boxes will be (a coloured
# logo or timestamp elsewhere in a grey frame says nothing about the target's colours)
GREY_NOTICE = ("the marked box and its surroundings have no colour (under 0.5 % of the pixels within 3x the box "
               "saturated: a grey sequence), so H-S histograms carry nothing; ")
GREY_USES = {"hsv": "the brightness histogram of Perez et al. is used instead (likelihood.histogram = \"hsv\": H-S of "
                    "coloured pixels, V of the rest)",
             "gradient": "a grey-level and gradient-direction histogram is used instead (likelihood.histogram = "
                         "\"gradient\": grey level of flat pixels, direction of edges; likelihood.grey = \"hsv\" for "
                         "Perez et al.'s brightness histogram)"}
GREY_LAYOUT = ("a grey histogram drifts with the light and shadows share it, so the layout cue is on too (the "
               "marked box's grey template, NCC at weight {:g}, likelihood.grey_template)")
FORGET_NOTICE = ("from then on the background is not used (no foreground cue, region, hold or neighbour check, and "
                 "the marked box's own histogram is the reference again): a background that fails to explain a whole "
                 "frame is not this scene's (reference.forget_on_change)")
NO_MARK_NOTICE = "the log marks no target (/annotations/init is empty): the colour particle filter needs a marked box; nothing is tracked"
SCENE_NOTICE = ("a frame differs from the background over more than half its area (the camera moved or the scene "
                "changed): on such frames the foreground cue and the neighbour check are off")
NO_PLANE_NOTICE = ("no ground plane (/camera/ground_plane) in the log: the size estimate takes the distance as constant "
                   "(S' starts at the marked box's area, eq. (9) with Z = Z_0; with refine.mode \"foreground\" the "
                   "foreground region rescales it once the log's background exists)")


@dataclass(frozen=True, eq=False)
class ForegroundView:
    """This frame's eq. (7) background where the scene is now (None: none, or the scene changed), the
    brightness gain against it and, where it was resampled, its registration band."""

    background: np.ndarray | WarpedBackground | None
    gain: float
    band: Band | None


@dataclass(frozen=True, eq=False)
class SizeStage:
    """Eq. (9)'s area and distance at the estimate's foot, and eqs. (10)-(11)'s aspect update."""

    area: float
    distance: float
    update: AspectUpdate


@dataclass(frozen=True, eq=False)
class Score:
    """The estimate's colour score: its histogram, ``S`` against H_ref as built and the confidence;
    ``separated``: the mark outscores the background; ``telling``: and the reference was built against it."""

    confidence: float
    s_est: float
    current: np.ndarray
    separated: bool
    telling: bool
    separation: float = 0.0  # S_mark - S_back (the whole background's score; 0 without a background)


def start_mark(hints: tuple[InitRegion, ...]) -> tuple[InitRegion | None, str]:
    """The mark that starts the track and, when there are several, a sentence saying which."""
    if not hints:
        return None, ""
    first = min(hints, key=lambda r: r.frame)  # min keeps the first listed among equals
    if len(hints) == 1:
        return first, ""
    return first, (f"the log marks {len(hints)} boxes: the track starts from the first, on frame {first.frame} "
                   f"(label {first.label!r}); later marks are not used")


class ColorPfTracker(TrackerBase):
    """Seed 002 (docs/papers.md §3). ``step(frame)`` returns one track (id 1) from the marked frame on."""

    name = "colorpf"  # what the replay needs of it is declared in trackers/colorpf/__init__.py (SPEC)

    def __init__(self, config: ColorPfConfig, rng: np.random.Generator) -> None:
        self.config = config
        self.rng = rng
        self.model = ColourModel(config.likelihood)
        self.pf = ParticleFilter(config.n_particles, 4, rng)
        self.mark: InitRegion | None = None
        self.background: BackgroundFrames | None = None
        self.reference: Reference | None = None
        self.size: WeakPerspectiveSize | None = None
        self.aspect: AspectEstimate | None = None
        self.started = False
        # the track's life (trackers.lifecycle): lost after lost_after misses, restarted after reacquire_frames
        self.life = TrackLife(config.lifecycle)
        self.placed_run = Run()  # refine.mode = "foreground": placed frames in a row since the last measured one
        self.side = 0.0
        self.initial_wh = np.zeros(2)
        self._marked_image: np.ndarray | None = None
        self._told: set[str] = set()
        self._s_mark: float | None = None
        self.background_image: np.ndarray | None = None  # eq. (7)'s background, once there is one
        self.adapted: np.ndarray | None = None  # reference.update_rate > 0: the adapted H_ref (None: as built)
        self.layout: np.ndarray | None = None  # refine.mode = "foreground": foreground_region's layout
        self.template: TemplateModel | None = None  # likelihood.template > 0: the target's grey template
        self.velocity = np.zeros(2)  # motion.model = "constant_velocity": smoothed displacement per frame
        self.motion = VouchedMotion()  # hold.enabled: the last vouched estimate, the velocity between them, held frames
        self.support = Support(np.zeros(2))  # [colorpf.support]: frames since the last supported row, its box's size
        self._vouched_area = float("inf")  # refine.max_growth: the area of the last "measured" row's box (the mark on)
        self._too_small = False  # the marked box holds fewer than min_box_pixels pixels
        self._lost_unsupported = False  # the track is lost for lack of support (support.lost_unsupported)
        # camera.compensate: the camera's motion since the marked frame, snapped (the identity for a still camera)
        self.camera: CameraMotion | None = None
        self.camera_transform = NO_MOTION.copy()
        self._pending: list[str] = []
        self._box_reference: tuple[Reference, float] | None = None  # the marked box's own reference and S_mark
        self._refused = False  # reference.refuse_unseparated: eq. (7)'s reference was refused
        self._warp_cache: tuple[np.ndarray, np.ndarray, WarpedBackground] | None = None  # _warped_background's last
        self._lost_steps = 0  # redetect.every: frames tracked while lost since the track was last not lost
        self._band_cache: tuple[np.ndarray, Band | None] | None = None  # _band_of's last band and the warp it is of
        # frame_rate: each step's interval over the stated one (colorpf.timing; 1 at the stated rate)
        self.clock = FrameClock(config.frame_rate)
        self.intermediates = ColorPfIntermediates.idle()

    # --- notices ---------------------------------------------------------------------------------
    def _say(self, text: str) -> None:
        if text and text not in self._told:
            self._told.add(text)
            self._pending.append(text)

    def _notice(self) -> str:
        text, self._pending = "; ".join(self._pending), []
        return text

    # --- the step ---------------------------------------------------------------------------------
    def step(self, frame: Frame) -> list[TrackState]:
        """The frame's row: before the mark the frame is kept for eq. (7)'s background; at the mark the
        track starts (:meth:`_start`); then the camera's motion, the "early" reference once its median is
        ready, and the filter's stages (:meth:`_track`)."""
        self.clock.step(frame.t_ns)  # frame_rate: the constants that describe time, at this step's interval
        self.model.recent.clear()  # ColourModel.crop_index: a bin-index crop serves the frame it was made on alone
        if not self._find_mark(frame):
            return self._idle()
        assert self.mark is not None and self.background is not None
        self.background.set_frames(frames_for(self.config.reference.frames, self.clock.typical))  # the median's window, in time
        if not self.started:
            if frame.index < self.mark.frame:
                self.background.offer(frame.index, frame.image)
                return self._idle()
            return self._start(frame)
        if self.camera is not None:  # camera.compensate: the background and the cloud follow the scene
            self._follow_camera(frame.image)
        self.background.offer(frame.index, frame.image, self.camera_transform)
        mask = self._early_reference()
        out = self._track(frame, mask)
        self._leave_out(frame, out)
        return out

    def _find_mark(self, frame: Frame) -> bool:
        """The mark that starts the track (:func:`start_mark`, once); False while the log marks none."""
        if self.mark is None:
            self.mark, several = start_mark(frame.all_hints or frame.hints)
            if self.mark is None:
                self._say(NO_MARK_NOTICE)
                return False
            self._say(several)
            self.background = BackgroundFrames(self.config.reference, self.mark.frame)
        return True

    def _idle(self) -> list[TrackState]:
        self.intermediates = ColorPfIntermediates.idle(self._notice())
        return []

    def _early_reference(self) -> np.ndarray | None:
        """``reference.background = "early"``: once the median is ready, eq. (7)'s reference is rebuilt
        (the marked box's foreground mask is returned), the early rows revouched and ``S_mark`` rescored."""
        assert self.background is not None
        if not self.background.early_ready:
            return None
        marked = self._marked_image
        early = self.background.early_frames()  # (let go by early_model)
        box_ref = self.reference
        median = self.background.early_model()
        if box_ref is not None and self._s_mark is not None:
            self._box_reference = (box_ref, self._s_mark)  # forget_on_change: the reference and S_mark until now
        mask = self._rebuild_reference(median, "early")
        if self.config.hold.enabled and self.config.hold.early == "region":
            self._revouch(early)
        assert self.reference is not None
        if marked is not None and self.reference.kind != "box":  # the marked box against the new reference
            self._s_mark = self._mark_score(marked)
            if self.config.reference.refuse_unseparated and box_ref is not None and not self._mark_stands_out():
                self._refuse_reference(box_ref, marked)
                return None
        return mask

    def _mark_stands_out(self) -> bool:
        """The marked box scores at least ``min_separation`` above the whole background against the reference."""
        ref = self.reference
        assert ref is not None and self._s_mark is not None
        s_back = float(self.model.pooled_similarity(ref.h_back, ref.histogram))
        return self._s_mark - s_back >= self.config.min_separation

    def _refuse_reference(self, box_ref: Reference, marked: np.ndarray) -> None:
        """``reference.refuse_unseparated``: eq. (7)'s reference, against which the mark does not stand out from the
        background, is refused: the marked box's own histogram stays the reference, the background's histogram
        (``H_back``) only places the confidence, and nothing uses the background as foreground (cue, region, hold,
        neighbours); a colour match is then "measured" only as the picture's single match (:meth:`_single_match`)."""
        ref = self.reference
        assert ref is not None
        self._say(f"the marked box scores S = {self._s_mark:.2f} against eq. (7)'s reference, no more than the whole "
                  "background: the reference is refused, the marked box's own histogram stays (the background's "
                  "histogram places the confidence; no foreground cue, region or hold; a match is \"measured\" only "
                  "where it is the picture's single match: reference.refuse_unseparated)")
        self.reference = dataclasses.replace(box_ref, h_back=ref.h_back)
        self.adapted = self.layout = self.background_image = None
        self._s_mark = self._mark_score(marked)
        self._refused = True

    def _leave_out(self, frame: Frame, out: list[TrackState]) -> None:
        """``reference.exclude``: the target is in its tracked box on this frame (out of the early median)."""
        assert self.background is not None
        if out and out[0].x is not None:
            self.background.leave_out(np.array([out[0].x, out[0].y, out[0].w, out[0].h], dtype=np.float64),
                                      (frame.image.shape[1], frame.image.shape[0]), transform=self.camera_transform)

    def _follow_camera(self, image: np.ndarray) -> None:
        """``camera.compensate``: the camera's motion since the marked frame (snapped); the particle
        cloud moves with the scene since the last frame, and, without a ground plane, S' scales with it."""
        assert self.camera is not None
        height, width = image.shape[:2]
        t = snap(self.camera.update(image, self._context_box(self.pf.estimate(), image)), (width, height))
        if np.array_equal(t, self.camera_transform):
            return
        d = t @ np.linalg.inv(self.camera_transform)  # the last frame -> this one
        self.pf.particles[:, :2] = apply(d, self.pf.particles[:, :2])
        s = scale_of(d)
        if s != 1.0 and self.config.camera.scale_size:
            self.pf.particles[:, 2:4] *= s
            if self.size is not None and not self.size.has_distance:
                self.size.area0 *= s * s
        self.camera_transform = t

    def _context_box(self, estimate: np.ndarray, image: np.ndarray) -> np.ndarray:
        """The estimate's box times reference.exclude (at least 2) per axis, integer corners: no camera corners there."""
        box = np.asarray(estimate[:4], dtype=np.float64).copy()
        box[2:4] *= max(self.config.reference.exclude, 2.0)
        return marked_box(tuple(box), image.shape[1], image.shape[0])

    def _start(self, frame: Frame) -> list[TrackState]:
        """The marked frame (§2-§3): the marked box's pixels, the histogram, the reference (eq. (7) when a
        background exists), eq. (9)'s ``S`` and ``R_0``, the particles on the box; the frame is weighed."""
        cfg, mark = self.config, self.mark
        assert mark is not None and self.background is not None
        box = self._marked_pixels(frame.image)
        self._choose_histogram(frame.image)
        self.reference = box_reference(self.model, frame.image, box)
        self._box_reference = (self.reference, self._mark_score(frame.image))  # forget_on_change (a "before" background)
        mask = self._start_reference(frame.image, box)
        self._start_size(frame.ground_plane)
        self.initial_wh = np.array([mark.w, mark.h], dtype=np.float64)
        sigma = np.concatenate([position_sigma(self.initial_wh, cfg.noise, cfg.min_noise_px), [0.0, 0.0]])
        self.pf.initialise(np.array([mark.x, mark.y, mark.w, mark.h], dtype=np.float64), sigma)
        self.started = True
        if cfg.camera.compensate and self.background.source != "none":
            self.camera = CameraMotion(cfg.camera.min_corners, renew=cfg.camera.renew)
            self.camera.update(frame.image, self._context_box(self.pf.estimate(), frame.image))  # the key frame
        out = self._track(frame, mask, weigh_only=True)
        self.background.leave_out(np.array([mark.x, mark.y, mark.w, mark.h], dtype=np.float64),
                                  (frame.image.shape[1], frame.image.shape[0]), marked=box)
        return out

    def _marked_pixels(self, image: np.ndarray) -> np.ndarray:
        """The marked box's whole pixels (integer corners); a box covering none is the log's error, and
        one under ``min_box_pixels`` is followed but never "measured" (said)."""
        cfg, mark = self.config, self.mark
        assert mark is not None
        height, width = image.shape[:2]
        box = marked_box((mark.x, mark.y, mark.w, mark.h), width, height)
        if box[2] <= box[0] or box[3] <= box[1]:
            raise LogError(f"the box marked on frame {mark.frame} ({mark.w:g}x{mark.h:g} px round {mark.x:g},{mark.y:g}) "
                           f"covers no whole pixel of the {width}x{height} picture: mark the target with a box of at least a pixel")
        pixels = int((box[2] - box[0]) * (box[3] - box[1]))
        self._too_small = pixels < cfg.min_box_pixels
        if self._too_small:
            self._say(f"the box marked on frame {mark.frame} holds {pixels} pixels, too few for a colour histogram to tell "
                      f"the target by (min_box_pixels = {cfg.min_box_pixels}): it is followed, but its rows are \"predicted\", "
                      "never \"measured\"; mark a larger box if the target allows")
        return box

    def _choose_histogram(self, image: np.ndarray) -> None:
        """H-S (§3.1) unless the marked box and its surroundings are grey: then ``likelihood.grey``, the grey-level
        and gradient-direction histogram (``"gradient"``, its edge threshold from the surroundings) or Pérez et
        al.'s H-S + V (``"hsv"``), said."""
        cfg, mark = self.config, self.mark
        assert mark is not None
        height, width = image.shape[:2]
        x0, y0, x1, y1 = marked_box((mark.x, mark.y, GREY_CONTEXT * mark.w, GREY_CONTEXT * mark.h), width, height)
        context = image[y0:y1, x0:x1]
        likelihood = cfg.likelihood
        if likelihood.histogram == "hs" and saturated_share(context, likelihood.s_min) < GREY_SHARE:
            # no hue or saturation to histogram: every box would score alike, and confidently
            likelihood = dataclasses.replace(likelihood, histogram=likelihood.grey)
            self._say(GREY_NOTICE + GREY_USES[likelihood.grey])
            if likelihood.grey_template > 0 and likelihood.template == 0:  # the layout too (grey_template)
                likelihood = dataclasses.replace(likelihood, template=likelihood.grey_template, template_mask="kernel")
                self._say(GREY_LAYOUT.format(likelihood.grey_template))
            self.config = dataclasses.replace(cfg, likelihood=likelihood)  # the cues' weights (_cues) read it
        if likelihood.histogram == "gradient":  # edges from the target's surroundings' median magnitude (0.5)
            self.model = ColourModel(likelihood, edge_threshold(context, likelihood.edge_quantile))
        elif likelihood is not cfg.likelihood:
            self.model = ColourModel(likelihood)

    def _start_reference(self, image: np.ndarray, box: np.ndarray) -> np.ndarray | None:
        """Eq. (7) now when the background was there "before" the mark (the mask returned), later for an
        "early" one (the marked frame kept); else the marked box's own histogram stays (said)."""
        assert self.background is not None
        background, source = self.background.at_start(image)
        if source == "before":
            return self._rebuild_reference(background, "before", image, box)
        if source == "early":
            self._marked_image = image
            self._marked_box = box
        else:
            self._say(self._no_background("the log has no usable background"
                                          if self.config.reference.background != "none" else "reference.background = \"none\""))
        return None

    def _start_size(self, plane: GroundPlane | None) -> None:
        """Eq. (9): ``S`` from the marked box's area at its foot's distance; ``R_0`` from the box."""
        cfg, mark = self.config, self.mark
        assert mark is not None
        foot = foot_points(np.array([[mark.x, mark.y]]), mark.h)
        if plane is not None:
            self.side = float(horizon_side(plane, foot)[0])
        distance0 = float(ground_distance(plane, foot, self.side)[0])
        if cfg.size.mode == "geometry" and not np.isfinite(distance0):
            self._say(NO_PLANE_NOTICE if plane is None else
                      "the marked box's foot is not on the ground plane: the size estimate takes the distance as constant")
        self.size = WeakPerspectiveSize(cfg.size.r_s, mark.w * mark.h, distance0)
        self.aspect = AspectEstimate(cfg.aspect, mark.h / mark.w)

    def _mark_score(self, image: np.ndarray) -> float:
        """``S`` of the marked box (on the marked frame) against the current reference."""
        assert self.mark is not None and self.reference is not None
        m = self.mark
        h = box_histogram(self.model, image, np.array([m.x, m.y, m.w, m.h], dtype=np.float64))
        return float(self.model.pooled_similarity(h, self.reference.histogram))

    def _no_background(self, why: str) -> str:
        return (f"no background for the reference histogram ({why}): the reference is the marked box's own "
                "histogram (target and whatever else the box holds), not eq. (7)")

    def _rebuild_reference(self, background: np.ndarray | None, source: str, image: np.ndarray | None = None,
                           box: np.ndarray | None = None) -> np.ndarray | None:
        """Background subtraction on the marked frame and eq. (7); returns the foreground mask."""
        image = self._marked_image if image is None else image
        box = self._marked_box if box is None else box
        self._marked_image = None
        if background is None or image is None or background.shape != image.shape:
            self._say(self._no_background("the background frames do not match the marked frame"))
            return None
        ref, why = subtract_and_mix(self.model, self.config.reference, image, background, box, source)
        if ref is None:
            self._say(self._no_background(f"{source} background: {why}"))
            return None
        if source == "early" and self.config.reference.exclude > 0:
            assert self.background is not None
            self._say(f"reference: eq. (7) from the median of the first {self.background.early_count} frames from the "
                      "mark on, each without its tracked box (the target was in the picture from the start); until "
                      "then the marked box's own histogram")
        elif source == "early":
            self._say(f"reference: eq. (7) from the median of {self.config.reference.frames} frames from the mark on "
                      "(the target was in the picture from the start); until then the marked box's own histogram")
        self.reference = ref
        self.adapted = None
        if self.config.refine.mode == "foreground" and ref.mask.size and self.mark is not None:
            # the marked box on its own foreground, for foreground_region
            self.layout = region_layout(ref.mask, ref.mask_offset,
                                        np.array([self.mark.x, self.mark.y, self.mark.w, self.mark.h]),
                                        self.config.refine.spread, self.config.refine.clip)
        self.background_image = background  # likelihood.foreground: what differs from it is foreground
        return ref.mask

    def _refine_foreground(self, image: np.ndarray, background: np.ndarray, gain: float,
                           estimate: np.ndarray, band: Band | None = None) -> tuple[np.ndarray, bool]:
        """``refine.mode = "foreground"``: the estimate's centre on the foreground region it sits on
        (:func:`.foreground.foreground_region`), the cloud moved with it; without a ground plane the
        size follows the region's box, smoothed (``refine.size_follows``: the area S', the aspect kept;
        or, "box", w and h from the estimate's, the aspect with them). No region: the estimate as it is."""
        cfg, ref = self.config, self.reference
        assert ref is not None and self.size is not None and self.aspect is not None
        layout = self.layout if cfg.refine.layout else IDENTITY
        if layout is None:
            return estimate, False
        region, _ = foreground_region(image, background, estimate, cfg.reference.threshold, cfg.reference.open_px,
                                      gain, ref.p_detect / ref.p_square, layout, window=cfg.refine.window,
                                      factor=cfg.refine.factor, min_part=cfg.refine.min_part, band=band,
                                      spread=cfg.refine.spread, clip=cfg.refine.clip)
        if region is None:
            return estimate, False
        self.pf.particles[:, :2] += region[:2] - estimate[:2]  # the cloud moves with the estimate
        if cfg.size.mode == "geometry" and not self.size.has_distance and cfg.refine.size_rate > 0:
            a = cfg.refine.size_rate
            if cfg.refine.size_follows == "area":  # S' from the state and the region's area; R the aspect stage's
                self.size.area0 = region_area(self.size.area0, region[2:4], a)
                if cfg.refine.max_growth is not None:  # no more than max_growth per side past the colour's word
                    self.size.area0 = min(self.size.area0, cfg.refine.max_growth ** 2 * self._vouched_area)
                wh = np.array(box_from_area(self.size.area0, self.aspect.ratio), dtype=np.float64)  # eq. (12)
            else:  # "box"
                wh = (1.0 - a) * estimate[2:4] + a * region[2:4]
                self.size.area0 = float(wh[0] * wh[1])  # S' without a plane (eq. 9 with Z = Z_0)
                self.aspect.ratio = float(wh[1] / wh[0])
            self.pf.particles[:, 2:4] *= wh / estimate[2:4]
        return self.pf.estimate(), True

    def _hold(self, image: np.ndarray, background: np.ndarray, gain: float, prev: np.ndarray,
              estimate: np.ndarray, index: int, band: Band | None = None) -> tuple[np.ndarray, bool]:
        """``hold.enabled``: when a box of the estimate's size beside it holds more foreground than the
        marked box did (the neighbour check's condition: a larger moving region, whose colour and
        foreground match the target's as well), the estimate's centre on frame ``index`` is the
        prediction (eq. (2) with the track's velocity as drift), the cloud moved with it; at most
        ``hold.max_frames`` frames in a row. The prediction (``hold.anchor``): the last vouched estimate
        plus the velocity times the frames since (none when that was more than ``hold.max_frames``
        frames ago), or ``prev + v``."""
        cfg, ref = self.config, self.reference
        assert ref is not None
        horizon = frames_for(cfg.hold.max_frames, self.clock.typical)  # frame_rate: the same duration
        motion = self.motion
        if not motion.held.within(horizon) or motion.steps == 0:
            # (no velocity measured yet, e.g. right after the mark: holding would freeze the box where it
            # was marked while the target walks off; a review saw otb_crossing marked on frame 60 held there)
            return estimate, False
        shares = neighbour_shares(image, background, estimate, cfg.reference.threshold, cfg.reference.open_px, gain,
                                  band=band)
        if shares.max() <= ref.p_detect / ref.p_square:
            motion.held.reset()
            return estimate, False
        vouched = cfg.hold.anchor == "vouched"
        if vouched and (motion.last is None or index - motion.last[0] > horizon):
            return estimate, False  # no vouched position recent enough to predict from
        motion.held.extend()
        if vouched:  # in the marked frame's view (as _vouch keeps it), then into this one (camera.compensate)
            assert motion.last is not None
            centre = vouched_prediction(*motion.last, motion.velocity, index)
            target = apply(self.camera_transform, centre)[0]
        else:  # the velocity into this view (camera.compensate)
            target = prev[:2] + self.camera_transform[:2, :2] @ motion.velocity
        self.pf.particles[:, :2] += target - estimate[:2]  # the cloud moves with it
        return self.pf.estimate(), True

    def _revouch(self, frames: dict[int, np.ndarray]) -> None:
        """``hold.early = "region"``: once eq. (7)'s background exists, the estimates made before it (colour
        alone, against the marked box's own histogram) are vouched for by the foreground region on the
        frames the median was taken over, as later ones are: the hold's velocity and anchor are refitted
        from the placed ones only (none placed: no velocity, no anchor)."""
        rows = self.motion.take_early_rows()
        ref, cfg, background = self.reference, self.config, self.background_image
        if (cfg.refine.mode != "foreground" or ref is None or ref.kind == "box" or background is None
                or ref.p_square <= 0 or self.layout is None or self.mark is None):
            return  # no region to vouch with: the colour's rows stand, as they would have
        self.motion.forget()
        layout = self.layout if cfg.refine.layout else IDENTITY
        for index, box in rows:
            image = frames.get(index)
            if image is None or image.shape != background.shape:
                continue
            gain = brightness_gain(image, background)
            if scene_changed(image, background, cfg.reference.threshold, gain):
                continue
            region, _ = foreground_region(image, background, box, cfg.reference.threshold, cfg.reference.open_px,
                                          gain, ref.p_detect / ref.p_square, layout, window=cfg.refine.window,
                                          factor=cfg.refine.factor, min_part=cfg.refine.min_part,
                                          spread=cfg.refine.spread, clip=cfg.refine.clip)
            if region is not None:
                self._vouch(index, region, True)

    def _vouch(self, index: int, estimate: np.ndarray, vouched: bool) -> None:
        """``hold.enabled``: the track's velocity from consecutive vouched estimates (exponentially smoothed)."""
        if not vouched:
            return
        # frame_rate: the same memory in time
        self.motion.vouch(index, estimate, smoothing_for(self.config.hold.smoothing, self.clock.ratio))

    # --- the step's stages (§3-§4) ---------------------------------------------------------------------
    def _track(self, frame: Frame, mask: np.ndarray | None, weigh_only: bool = False) -> list[TrackState]:
        """One frame of the filter: select and predict (eq. 2), weigh (eqs. 3-5 and our cues), estimate
        (eq. 6), refine or hold, size and aspect (eqs. 9-12), confidence, adapt, status. ``weigh_only``:
        the marked frame (the particles start on the mark: nothing is selected, predicted or refined)."""
        assert self.reference is not None and self.size is not None and self.aspect is not None
        image, plane = frame.image, frame.ground_plane
        prev = self.pf.estimate()
        working = self.reference.histogram if self.adapted is None else self.adapted
        view = self._foreground_view(image)
        if not weigh_only:
            self._predict(prev, plane)
            self._lost_unsupported = self._lost_unsupported and self.life.lost  # cleared once found again
            self._lost_steps = self._lost_steps if self.life.lost else 0  # redetect.every: from the first lost frame
            if self.config.redetect.enabled and self.life.lost and self._scan_due():
                self._redetect(image, view, prev)
        m = measure(self.model, image, self.pf.particles, working)  # eqs. (4)-(5)
        estimate = self._weigh(self._cues(m.likelihood, image, view, prev, mask))
        placed = held = False
        if not weigh_only:
            estimate, placed = self._refine(image, view, working, estimate)
            if self.config.hold.enabled and not placed and self._vouchable(view):
                estimate, held = self._hold(image, view.background, view.gain, prev, estimate, frame.index, view.band)
            self._follow_velocity(prev, estimate)
        size = self._size_and_aspect(estimate, m.likelihood, plane, weigh_only)
        score = self._score(image, estimate, weigh_only)
        if not weigh_only:
            self._adapt(image, estimate, working, score)
        status = self._status(frame.index, image, view, estimate, score, placed, held, weigh_only)
        supported, unsupported = weigh_only or status == "measured" or placed, self.support.unsupported
        status, shown, confidence = self._unsupported(status, estimate, score.confidence, supported)
        evidence = self._evidence(status, supported, score, estimate, unsupported) if status != "lost" else None
        if self.config.calibrate and evidence is not None:
            confidence = calibrated(evidence)
        if status == "measured" or weigh_only:
            self._vouched_area = float(estimate[2] * estimate[3])
        if self.config.hold.enabled and not weigh_only:
            self._remember(frame.index, estimate, status == "measured" or placed)
        self.intermediates = self._intermediates(m, shown, score, size, mask, status, evidence)
        return self._rows(status, shown, prev, confidence, weigh_only)

    def _scan_due(self) -> bool:
        """``redetect.every``: the lost track's scan is due on its first lost frame, then every ``every`` frames
        (at ``frame_rate``: the same duration at another frame rate)."""
        due = self._lost_steps % frames_for(self.config.redetect.every, self.clock.typical) == 0
        self._lost_steps += 1
        return due

    def _redetect(self, image: np.ndarray, view: ForegroundView, prev: np.ndarray) -> None:
        """``redetect.enabled``, while lost: a scan of the whole picture at the last supported size against H_ref
        as built (:func:`.redetect.scan`), each box's confidence by the status's rule (:meth:`_score`'s ``c``), a box
        that stands out from eq. (7)'s background where it exists on this frame. Nothing when the mark's
        lead over the background (S_mark - S_back) is under the scanned scores' standard deviation (a match
        is then the picture's own variation), the mark is too small or the track was lost for lack of support. When one box
        alone matches (:func:`.redetect.unique_best`) and beats the cloud's last estimate ``prev`` on this
        frame, ``redetect.share`` of the cloud is drawn around it with eq. (2)'s position noise."""
        cfg, ref = self.config, self.reference
        assert ref is not None
        if self._too_small or self._s_mark is None or self._lost_unsupported:
            return  # lost for lack of support: the colour matched where the cloud was and could not vouch
        wh = self.support.wh
        sigma = noise_for(position_sigma(wh, cfg.noise, cfg.min_noise_px), self.clock.ratio)
        boxes, similarity = scan(self.model, image, ref.histogram, wh, cfg.redetect.stride, cfg.redetect.max_boxes)
        s_back = float(self.model.pooled_similarity(ref.h_back, ref.histogram))
        if self._s_mark - s_back < max(cfg.min_separation, float(similarity.std())):
            # the mark stands out from the background by less than the scanned boxes' scores vary from box to
            # box: c >= measured_fraction (half the mark's lead) is then reached by the picture's own variation
            # (otb_human3: a lead of 0.056 against a spread of 0.13-0.15), and a match found so vouches for little
            return
        confidence = np.clip((similarity - s_back) / max(self._s_mark - s_back, 1e-6), 0.0, 1.0)
        if view.background is not None and self.reference.p_square > 0:
            # eq. (7)'s background on this frame: a box must also stand out from it (the target moves; a
            # static look-alike in the background does not): more foreground inside than in its ring
            contrast = foreground_contrast(image, view.background, boxes[:, :2], boxes[0, 2:4], cfg.reference.threshold,
                                           cfg.reference.open_px, view.gain, band=view.band)
            confidence = np.where(contrast > 0.0, confidence, 0.0)
        best = unique_best(boxes, confidence, cfg.measured_fraction)
        if best is None or confidence[best] <= self._score(image, prev, False).confidence:
            return  # no single match, or the cloud is where the colour matches as well
        box = boxes[best]
        self.pf.inject(cfg.redetect.share, box, np.concatenate([sigma, [0.0, 0.0]]))

    def _evidence(self, status: str, supported: bool, score: Score, estimate: np.ndarray,
                  unsupported: int) -> RowEvidence:
        """What ``calibrate`` reads of the row (:mod:`.calibration`; in the intermediates either way)."""
        share, spread = cloud_evidence(self.pf.weights, self.pf.particles, estimate)
        return RowEvidence(score.confidence, status == "measured", status == "predicted" and supported,
                           score.separation, share, spread, unsupported)

    def _unsupported(self, status: str, estimate: np.ndarray, confidence: float,
                     supported: bool) -> tuple[str, np.ndarray, float]:
        """Ours (``[colorpf.support]``, :mod:`.support`): a row without support ("measured" or placed by a
        region) turns "lost" after ``lost_unsupported`` such frames in a row; until then ("predicted") the
        box it reports is at most the last supported one's size and its confidence falls. Returns the
        status, the row's box and its confidence (the filter's own estimate and state are left as they are)."""
        cfg, support = self.config.support, self.support
        support.note(supported, estimate[2:4])
        if supported:
            return status, estimate, confidence
        # frame_rate: the same duration
        limit = frames_for(cfg.lost_unsupported, self.clock.typical) if cfg.lost_unsupported > 0 else None
        if support.expired(limit) and status != "lost":
            self._lost_unsupported = True  # redetect: not a loss of the colour's (see _redetect)
            status = self.life.lose()  # as a miss: restarted by reacquire_frames matches, as after colour's misses
        if status != "predicted":
            return status, estimate, confidence
        if cfg.size_holds:
            factor = support.shrink(estimate[2:4])
            if factor < 1.0:
                estimate = estimate.copy()
                estimate[2:4] *= factor
        if cfg.confidence_falls:
            confidence = support.confidence(confidence, limit)
        return status, estimate, confidence

    def _predict(self, prev: np.ndarray, plane: GroundPlane | None) -> None:
        """Select by the previous weights (systematic resampling), then eq. (2)'s transition."""
        cfg = self.config
        assert self.aspect is not None
        self.pf.resample()
        drift = self.velocity if cfg.motion.model == "constant_velocity" else None
        # frame_rate: eq. (2)'s random walk spreads with the square root of the step's interval
        sigma = noise_for(position_sigma(prev[2:4], cfg.noise, cfg.min_noise_px), self.clock.ratio)
        self.pf.predict(transition(
            sigma=sigma, size=cfg.size, ratio=self.aspect.ratio,
            box_wh=prev[2:4], model=self.size, plane=plane, side=self.side, initial_wh=self.initial_wh,
            drift=drift))  # eq. (2)

    def _foreground_view(self, image: np.ndarray) -> ForegroundView:
        """Eq. (7)'s background where the scene is now (camera.compensate), its brightness gain and
        registration band; none on a frame that differs from it over most of its area."""
        cfg = self.config
        background, gain, band = self.background_image, 1.0, None
        if background is not None:  # camera.compensate: the background (marked frame's place) where the scene is now
            background = self._warped_background(background)
        uses_foreground = cfg.likelihood.foreground > 0 or cfg.neighbour_check or cfg.refine.mode == "foreground"
        if background is not None and uses_foreground:
            gain = brightness_gain(image, background)  # a uniform illumination change is not foreground
            if scene_changed(image, background, cfg.reference.threshold, gain):
                self._say(SCENE_NOTICE)
                background = None  # no foreground cue and no neighbour check on this frame
                if cfg.reference.forget_on_change:  # ... nor on any later one: the background is not this scene's
                    self._forget_background()
            else:  # resampled (not a whole-pixel shift): its edges may be off by a fraction of a pixel
                band = self._band_of(background)
        return ForegroundView(background, gain, band)

    def _warped_background(self, background: np.ndarray) -> np.ndarray | WarpedBackground:
        """Eq. (7)'s background where the scene is now: itself under the identity (a still camera), else a
        :class:`.warped.WarpedBackground` (warped where it is read: the whole warp's pixels, a crop's but for a rare
        one-level rounding), kept while neither the background nor the camera's transform changes (a probe that
        finds the scene unmoved keeps it)."""
        if np.array_equal(self.camera_transform, NO_MOTION):
            return background
        kept = self._warp_cache
        if kept is not None and kept[0] is background and np.array_equal(kept[1], self.camera_transform):
            return kept[2]
        warped = WarpedBackground(background, self.camera_transform)
        self._warp_cache = (background, self.camera_transform.copy(), warped)
        return warped

    def _band_of(self, warped: np.ndarray | WarpedBackground) -> Band | None:
        """:func:`.foreground.registration_band` of this frame's background (a :class:`.warped.WarpedBackground`'s
        band made crop by crop as it is read), kept with it."""
        if self._band_cache is not None and self._band_cache[0] is warped:
            return self._band_cache[1]
        mode = self.config.reference.registration_tolerance
        if isinstance(warped, WarpedBackground):
            band = warped_band(warped) if mode == "resampled" and resamples(self.camera_transform) else None
        else:
            band = registration_band(warped, self.camera_transform, mode)
        self._band_cache = (warped, band)
        return band

    def _forget_background(self) -> None:
        """``reference.forget_on_change``: the background is no longer this scene's: nothing uses it as foreground
        from now on, and an eq. (7) reference made with it gives way to the marked box's own histogram (its
        ``H_back`` no longer the picture's), with the mark's own score."""
        self._say(FORGET_NOTICE)
        self.background_image = self.layout = None
        if self._box_reference is not None and self.reference is not None and self.reference.kind != "box":
            self.reference, self._s_mark = self._box_reference
            self.adapted = None

    def _vouchable(self, view: ForegroundView) -> bool:
        """A foreground region can place or hold the estimate: a background on this frame, a marked box
        with foreground, and the track not lost (no re-acquisition by region)."""
        assert self.reference is not None
        return view.background is not None and self.reference.p_square > 0 and not self.life.lost

    def _cues(self, likelihood: np.ndarray, image: np.ndarray, view: ForegroundView, prev: np.ndarray,
              mask: np.ndarray | None) -> np.ndarray:
        """Ours: eq. (5)'s likelihood times the foreground centre-surround cue and the layout (template) cue."""
        cfg = self.config
        if cfg.likelihood.foreground > 0 and view.background is not None:
            contrast = foreground_contrast(image, view.background, self.pf.particles[:, :2], prev[2:4],
                                           cfg.reference.threshold, cfg.reference.open_px, view.gain, band=view.band)
            likelihood = likelihood * np.exp(cfg.likelihood.foreground * contrast)
        if cfg.likelihood.template > 0:
            if self.template is None:  # the marked box, on the marked frame (this one)
                assert self.mark is not None
                corners = marked_box((self.mark.x, self.mark.y, self.mark.w, self.mark.h), *image.shape[1::-1])
                self.template = TemplateModel(image, corners, cfg.likelihood.template_mask)
            if mask is not None:  # eq. (7)'s foreground of the marked box, just made
                self.template.set_foreground(mask)
            if self.template.template is not None:
                ncc = template_scores(image, self.template.template, self.pf.particles[:, :2], prev[2:4],
                                      cfg.likelihood.template_side, self.template.weights)
                likelihood = likelihood * np.exp(cfg.likelihood.template * np.maximum(ncc, 0.0))
        return likelihood

    def _weigh(self, likelihood: np.ndarray) -> np.ndarray:
        """Eq. (3), pi = L (after selection), and eq. (6)'s estimate."""
        self.pf.weights = np.full(self.pf.n, 1.0 / self.pf.n)
        self.pf.weigh(lambda _: likelihood)
        return self.pf.estimate()

    def _refine(self, image: np.ndarray, view: ForegroundView, working: np.ndarray,
                estimate: np.ndarray) -> tuple[np.ndarray, bool]:
        """``refine.mode``: mean shift, or the foreground region (True: it placed the estimate)."""
        cfg = self.config
        if cfg.refine.mode == "meanshift":
            refined, _ = mean_shift(self.model, image, estimate, working, cfg.refine.iterations)
            self.pf.particles[:, :2] += refined[:2] - estimate[:2]  # the cloud moves with the estimate
            return self.pf.estimate(), False
        if cfg.refine.mode == "foreground" and self._vouchable(view):
            assert view.background is not None
            return self._refine_foreground(image, view.background, view.gain, estimate, view.band)
        return estimate, False

    def _follow_velocity(self, prev: np.ndarray, estimate: np.ndarray) -> None:
        """``motion.model = "constant_velocity"``'s drift: the estimate's displacement, smoothed."""
        s = smoothing_for(self.config.motion.smoothing, self.clock.ratio)
        self.velocity = s * self.velocity + (1.0 - s) * (estimate[:2] - prev[:2])

    def _size_and_aspect(self, estimate: np.ndarray, likelihood: np.ndarray, plane: GroundPlane | None,
                         weigh_only: bool) -> SizeStage:
        """Eq. (9)'s area and distance at the estimate's foot; eqs. (10)-(11)'s aspect ``R_t``."""
        cfg = self.config
        assert self.aspect is not None
        area_a, distance_a = standing_box(estimate[None, :2], estimate[3], self.size, plane, self.side, self.aspect.ratio)
        area, distance = float(area_a[0]), float(distance_a[0])
        if cfg.size.mode == "geometry" and cfg.aspect.mode == "likelihood" and not weigh_only:
            update = self.aspect.update(self.pf.particles[:, :2], likelihood, estimate, area)  # eqs. (10)-(11)
        else:
            update = AspectUpdate(float("nan"), self.aspect.ratio, True)
        return SizeStage(area, distance, update)

    def _score(self, image: np.ndarray, estimate: np.ndarray, weigh_only: bool) -> Score:
        """The confidence: the estimate's ``S`` between the background's score and the marked box's."""
        cfg, ref = self.config, self.reference
        assert ref is not None
        current = box_histogram(self.model, image, estimate)
        s_est = float(self.model.pooled_similarity(current, ref.histogram))  # against H_ref as built
        if weigh_only or self._s_mark is None:
            self._s_mark = s_est  # the marked box's own score (the estimate is the mark here)
        s_back = float(self.model.pooled_similarity(ref.h_back, ref.histogram))
        separation = self._s_mark - s_back
        separated = separation >= cfg.min_separation
        # the confidence tells the target from the background only with a background-built reference
        # whose mark stands out from it; only then may the reference adapt (reference.update_rate)
        telling = ref.kind != "box" and separated
        if not separated:
            # the background scores (nearly) as well as the mark: it cannot scale the confidence
            self._say(f"the marked box scores S = {self._s_mark:.2f} against the reference and the background "
                      f"{s_back:.2f}: H-S colour barely tells this target from the background, so the confidence "
                      "is S relative to the mark's alone (as without a background) and says little: such frames are "
                      "\"predicted\", not \"measured\"")
            s_back = 0.0
        confidence = float(np.clip((s_est - s_back) / max(self._s_mark - s_back, 1e-6), 0.0, 1.0))
        return Score(confidence, s_est, current, separated, telling, separation)

    def _adapt(self, image: np.ndarray, estimate: np.ndarray, working: np.ndarray, score: Score) -> None:
        """Ours: the reference (Nummiaro et al.'s adaptive model) and the template follow a confident estimate."""
        cfg = self.config
        if not score.telling or score.confidence < cfg.reference.update_above:
            return
        rate = cfg.reference.update_rate
        if rate > 0 and score.current.sum() > 0:
            self.adapted = (1.0 - rate) * working + rate * score.current
        if self.template is not None and cfg.likelihood.template_rate > 0:
            self.template.blend(image, estimate, cfg.likelihood.template_rate)

    def _status(self, index: int, image: np.ndarray, view: ForegroundView, estimate: np.ndarray, score: Score,
                placed: bool, held: bool, weigh_only: bool) -> str:
        """The row's status and the track's life (:mod:`trackreplay.trackers.lifecycle`): "measured" on a
        colour match that vouches, "predicted" while held, placed or unsupported, "lost" from the
        ``lost_after``-th miss in a row until the colour has matched again on ``reacquire_frames`` frames."""
        cfg, life = self.config, self.life
        matched = score.confidence >= cfg.measured_fraction
        if matched and life.reacquiring(index, estimate[:2], estimate[2:4]):
            return "lost"  # lost, and the colour matches again: not yet on reacquire_frames frames in a row
        if held:  # the estimate is the motion prediction: whatever the colour says there, nothing saw it (nor vouches)
            if matched:  # bounded by hold.max_frames; a colour match there is no miss towards "lost" either
                life.supported()
            return life.held()
        if matched and not weigh_only and (not score.separated or self._too_small):
            # the background scores about as well as the mark, or the box is too small for a histogram: the
            # colour match vouches for little; not a miss either
            life.supported()
            return "predicted"
        if matched:
            self.placed_run.reset()
            status = life.supported()
            if not weigh_only and (self._beside_larger_region(image, view, estimate)
                                   or not self._layout_agrees(image, estimate) or not self._single_match(image, estimate)):
                return "predicted"
            return status
        if placed and cfg.refine.keeps_track and self.placed_run.within(cfg.refine.keep_frames):
            self.placed_run.extend()
            return life.held()  # the foreground region places the target: not a miss towards "lost"
        return life.missed()

    def _layout_agrees(self, image: np.ndarray, estimate: np.ndarray) -> bool:
        """``likelihood.layout_vouches``: where the layout (template) cue is on, the estimate's box must correlate
        with the target's template (NCC > 0; a box not wholly in the picture scores 0) for its colour match to
        vouch; True where the cue is off. Only the status changes (the misses towards "lost" are colour's)."""
        cfg = self.config.likelihood
        if not cfg.layout_vouches or cfg.template <= 0 or self.template is None or self.template.template is None:
            return True
        ncc = template_scores(image, self.template.template, estimate[None, :2], estimate[2:4], cfg.template_side,
                              self.template.weights)
        return bool(ncc[0] > 0.0)

    def _single_match(self, image: np.ndarray, estimate: np.ndarray) -> bool:
        """``reference.refuse_unseparated``: where eq. (7)'s reference was refused (no background vouches for a match), a
        colour match is "measured" only when no box of the estimate's size apart from it (a scan of the picture,
        :func:`.redetect.scan`) matches too by the same rule (:func:`.redetect.unique_best`'s look-alike)."""
        if not self._refused or self._s_mark is None:
            return True
        cfg, ref = self.config, self.reference
        assert ref is not None
        s_back = float(self.model.pooled_similarity(ref.h_back, ref.histogram))
        for scale in SINGLE_MATCH_SCALES:  # nothing here sets the size: the target may be a look-alike's size
            boxes, similarity = scan(self.model, image, ref.histogram, estimate[2:4] * scale, cfg.redetect.stride,
                                     cfg.redetect.max_boxes)
            confidence = np.clip((similarity - s_back) / max(self._s_mark - s_back, 1e-6), 0.0, 1.0)
            apart = np.any(np.abs(boxes[:, :2] - estimate[:2]) >= estimate[2:4], axis=1)
            if apart.any() and confidence[apart].max() >= cfg.measured_fraction:
                return False
        return True

    def _beside_larger_region(self, image: np.ndarray, view: ForegroundView, estimate: np.ndarray) -> bool:
        """``neighbour_check``: a neighbour holds more foreground than the marked box did: the estimate is on
        or against a larger moving region; its colour matches, its position is not vouched for. Only the
        status changes (the misses towards "lost" are colour's)."""
        cfg, ref = self.config, self.reference
        assert ref is not None
        if not cfg.neighbour_check or view.background is None or ref.p_square <= 0:
            return False
        shares = neighbour_shares(image, view.background, estimate, cfg.reference.threshold,
                                  cfg.reference.open_px, view.gain, band=view.band)
        return bool(shares.max() > ref.p_detect / ref.p_square)

    def _remember(self, index: int, estimate: np.ndarray, vouched: bool) -> None:
        """``hold.enabled``: the estimate in the marked frame's view (camera.compensate: the velocity is the
        target's, not the camera's) for the hold's velocity, and, before eq. (7)'s background, for ``_revouch``."""
        assert self.reference is not None and self.background is not None
        moved = self.camera is not None and not np.array_equal(self.camera_transform, NO_MOTION)
        scene = np.concatenate([apply(np.linalg.inv(self.camera_transform), estimate[:2])[0], estimate[2:4]]) \
            if moved else estimate
        self._vouch(index, scene, vouched)
        if self.config.hold.early == "region" and self.reference.kind == "box" and self.background.source == "early":
            box = scene.copy()  # the box too in the marked frame's view (the early median's frames)
            box[2:4] /= scale_of(self.camera_transform)
            self.motion.early_rows.append((index, box))

    def _intermediates(self, m: Measurement, estimate: np.ndarray, score: Score, size: SizeStage,
                       mask: np.ndarray | None, status: str, evidence: RowEvidence | None) -> ColorPfIntermediates:
        ref, cfg = self.reference, self.config
        assert ref is not None
        return ColorPfIntermediates(
            "track", self.pf.particles.copy(), self.pf.weights.copy(), m.similarity, m.likelihood, estimate,
            ref.histogram.reshape(self.model.shape), score.current.reshape(self.model.shape), score.s_est,
            size.area if cfg.size.mode == "geometry" else float("nan"), size.distance, size.update.measured,
            size.update.ratio, size.update.kept, ref.kind, ref.background,
            mask if mask is not None else np.zeros((0, 0), bool),
            ref.mask_offset.copy() if mask is not None else np.zeros(2, np.int64), status, self._notice(), evidence)

    @staticmethod
    def _rows(status: str, estimate: np.ndarray, prev: np.ndarray, confidence: float,
              weigh_only: bool) -> list[TrackState]:
        """The track's row: no position when lost; no velocity on the marked frame."""
        if status == "lost":
            return [TrackState(1, status="lost", confidence=confidence)]
        x, y, w, h = (float(v) for v in estimate)
        vx = vy = None
        if not weigh_only:
            vx, vy = x - float(prev[0]), y - float(prev[1])
        return [TrackState(1, x=x, y=y, w=w, h=h, vx=vx, vy=vy, status=status, confidence=confidence)]

__all__ = ["ColorPfTracker", "start_mark", "box_from_area"]
