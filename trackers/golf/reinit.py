"""Where the particles start again: the re-initialisation policy (seed 000, §2.3 and ours).

Checked in this order before each frame's select + predict; the first that applies replaces it:

1. **EKF landing** (paper §2.3): the 3-D filter's prediction crossed the ground plane
   (:meth:`BallisticEkf.advance`); the samples are spread around the contact point projected into
   this frame, as wide as the EKF's own uncertainty there and wide enough to still cover where the
   samples had the ball (a contact predicted a few frames early must not lose it).
   **After the landing** (ours, ``after_landing_frames``): a landing predicted while the ball is being
   measured re-initialises nothing (a ball still found where the motion model expects it has not
   been lost to it); for that many frames after it, a ball missed on the frame before (not yet lost)
   is searched for around the 3-D filter's own prediction, which bounces (a hop the image motion model
   cannot follow), until the ball is measured at the end of such a gap.
2. **Image parabola** (ours, no encoders: no 3-D filter): once the ball has been missed for a few
   frames while descending, a parabola ``y(t)`` and a line ``x(t)`` through the last measurements
   bracket where it met the ground and bounced (:func:`image_parabola_landing`). Once per loss.
3. **Lost centre** (ours, ``lost = "centre"``, or ``"auto"`` when the camera was following the
   ball): after ``max_predicted_frames`` misses the ball is "lost"; a broadcast operator keeps
   following it, so the samples are spread over the middle of the picture each frame (the search
   region is then the largest allowed). What is found there must still be confirmed over several
   frames (:mod:`.validate`) before it is ``measured``.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np

from trackreplay.trackers.geometry.homography import apply_homography
from trackreplay.trackers.geometry.ptz import PtzCamera, pose_homography
from trackreplay.trackers.golf.config import ReinitConfig, SearchConfig
from trackreplay.trackers.golf.landing import BallisticEkf
from trackreplay.trackers.golf.search_region import filling_sigma
from trackreplay.trackers.lifecycle import TrackLife

NAN2 = np.full(2, np.nan)


@dataclass(frozen=True, eq=False)
class Reinit:
    """The re-initialisation stage's intermediates (also what the particles are reset to)."""

    kind: str  # "", "start", "ekf_landing", "after_landing", "image_parabola" or "lost_centre"
    point: np.ndarray  # (2,) centre of the new samples (NaN: none this frame)
    sigma: np.ndarray  # (2,) their position spread in x and y (NaN: none)

    @classmethod
    def none(cls) -> Reinit:
        return cls("", NAN2, NAN2)


def image_parabola_landing(history: np.ndarray, now: float, min_points: int = 5) -> tuple[np.ndarray, np.ndarray] | None:
    """Where the descent ends, from the image track alone (no encoders, no 3-D filter).

    ``history`` rows are ``(frame, x, y)`` of past measurements. A parabola ``y(t)`` and a line
    ``x(t)`` are fitted; if the ball was descending (image y growing) the positions at the last
    measurement and at ``now`` bound where it met the ground and bounced. Returns the midpoint of
    the two and the half-distance between them per axis (the re-initialisation centre and spread),
    or None when the track was not descending or is too short.
    """
    if len(history) < min_points:
        return None
    t = history[:, 0] - history[-1, 0]
    cy = np.polyfit(t, history[:, 2], 2)
    cx = np.polyfit(t, history[:, 1], 1)
    if cy[1] <= 0.0:  # dy/dt at the last measurement: not descending
        return None
    dt = float(now - history[-1, 0])
    end = np.array([np.polyval(cx, dt), np.polyval(cy, dt)])
    last = np.array([np.polyval(cx, 0.0), np.polyval(cy, 0.0)])
    return 0.5 * (last + end), 0.5 * np.abs(end - last)


class ReinitPolicy:
    """Decides, once per frame, whether and where the particles start again.

    ``search`` is the search region's table (the largest region bounds the spread). Whether the
    track is missed or lost is the track's life's (:class:`~trackreplay.trackers.lifecycle.TrackLife`).
    """

    def __init__(self, cfg: ReinitConfig, search: SearchConfig) -> None:
        self.cfg = cfg
        self.search = search
        self.history: deque = deque(maxlen=cfg.parabola_history)  # (frame, x, y) of past measurements
        self.parabola_used = False
        self.landed_at: int | None = None  # the frame of the last predicted landing (after_landing_frames)
        self.followed_landing = False  # the samples were sent after the 3-D filter since the landing

    def measured(self, index: int, x: float, y: float) -> None:
        """The ball was measured at ``(x, y)`` in frame ``index``."""
        self.history.append((index, x, y))
        self.parabola_used = False
        if self.followed_landing:  # found again after a gap the landing's search bridged: later misses are not the landing's
            self.landed_at, self.followed_landing = None, False

    def at_rest(self, frames: int, tolerance_px: float) -> bool:
        """The last ``frames`` measurements were on consecutive frames and all within
        ``tolerance_px`` of their mean, and the ball did not come into them fast (the measurement
        on the frame before, if any, within ``3 * tolerance_px``): the ball was lying still when
        last seen. (A clip with repeated frames, 30 fps shown at 60, shows a ball in flight at the
        same place twice; taken as struck on the next miss, its samples' velocities opened up and
        a wrong blob 60 px off was measured.)"""
        history = np.array(self.history, float).reshape(-1, 3)
        recent = history[-frames:]
        if len(recent) < frames or recent[-1, 0] - recent[0, 0] != frames - 1:
            return False
        mean = recent[:, 1:].mean(axis=0)
        if not bool(np.all(np.hypot(*(recent[:, 1:] - mean).T) <= tolerance_px)):
            return False
        before = history[-frames - 1] if len(history) > frames else None
        return before is None or before[0] != recent[0, 0] - 1 or bool(np.hypot(*(before[1:] - mean)) <= 3.0 * tolerance_px)

    def centre_search(self, camera: PtzCamera | None, previous: PtzCamera | None, width: int, height: int,
                      pose_change: np.ndarray | None = None) -> bool:
        """Whether a lost ball is searched for mid-picture (``lost``: "centre", or "auto" when the
        camera follows the ball, :meth:`follows`)."""
        if self.cfg.lost != "auto":
            return self.cfg.lost == "centre"
        return self.follows(camera, previous, width, height, pose_change)

    def follows(self, camera: PtzCamera | None, previous: PtzCamera | None, width: int, height: int,
                pose_change: np.ndarray | None = None) -> bool:
        """Whether an operator's camera follows the ball: its pose (``previous`` -> ``camera``) moved
        the picture's centre by more than half a pixel, or the last measurements were all in the
        central half of the picture. ``pose_change``: ``pose_homography(previous, camera)`` when
        the caller has it."""
        if camera is not None and previous is not None:
            centre = np.array([[(width - 1) / 2.0, (height - 1) / 2.0]])
            if pose_change is None:
                pose_change = pose_homography(previous, camera)
            moved = apply_homography(pose_change, centre)[0] - centre[0]
            if float(np.hypot(*moved)) > 0.5:
                return True
        recent = np.array(self.history, float).reshape(-1, 3)[-4:, 1:]
        if not len(recent):
            return False
        centre = np.array([(width - 1) / 2.0, (height - 1) / 2.0])
        return bool(np.all(np.abs(recent - centre) <= 0.25 * np.array([width, height])))

    def _landing_now(self, index: int, misses: int, landing: np.ndarray | None) -> np.ndarray | None:
        """The contact point to re-initialise at on this frame (None: none): a new landing's, unless the
        ball was measured on the frame before and ``after_landing_frames`` is on."""
        if landing is None:
            return None
        self.landed_at, self.followed_landing = index, False
        return None if misses == 0 and self.cfg.after_landing_frames > 0 else landing

    def _after_landing(self, index: int, size: tuple[int, int], scale: float, life: TrackLife, camera: PtzCamera | None,
                       ekf: BallisticEkf) -> Reinit | None:
        """``after_landing_frames``: around the 3-D filter's prediction, projected into this frame, while
        the ball is missed (not yet lost) after a landing (None: not now, or the prediction is outside
        the picture)."""
        if (self.landed_at is None or not life.misses or life.lost or camera is None or not ekf.initialised
                or index - self.landed_at > self.cfg.after_landing_frames):  # once lost: the fallbacks below
            return None
        centre = camera.project_points(ekf.kf.x[:3].reshape(1, 3))[0]
        width, height = size
        if not (np.all(np.isfinite(centre)) and 0 <= centre[0] <= width - 1 and 0 <= centre[1] <= height - 1):
            return None
        sigma = np.sqrt(np.maximum(np.diag(ekf.image_covariance(camera)), 0.0))
        sigma = np.clip(sigma, self.cfg.min_sigma_px * scale, filling_sigma(self.search.max_px * scale, self.search))
        self.followed_landing = True
        return Reinit("after_landing", centre, sigma)

    def choose(self, *, index: int, size: tuple[int, int], scale: float, life: TrackLife, landing: np.ndarray | None,
               camera: PtzCamera | None, previous: PtzCamera | None, ekf: BallisticEkf, estimate: np.ndarray) -> Reinit:
        """The re-initialisation for frame ``index`` of ``size`` (w, h) px, or ``Reinit.none()``.

        ``life``: the track's misses in a row and whether it is lost; ``landing`` is the EKF's ground
        contact this frame (None: none), ``estimate`` the particles' last estimate (x, y).
        """
        cfg = self.cfg
        width, height = size
        misses = life.misses
        landing = self._landing_now(index, misses, landing)
        if landing is not None and camera is not None and cfg.landing:
            centre = camera.project_points(landing.reshape(1, 3))[0]
            if np.all(np.isfinite(centre)):
                centre = np.clip(centre, 0, [width - 1, height - 1])
                cov = ekf.image_covariance(camera)
                sigma = np.maximum(np.sqrt(np.maximum(np.diag(cov), 0.0)), 0.5 * np.abs(estimate - centre))
                sigma = np.clip(sigma, cfg.min_sigma_px * scale, filling_sigma(self.search.max_px * scale, self.search))
                return Reinit("ekf_landing", centre, sigma)
        if cfg.landing:
            after = self._after_landing(index, size, scale, life, camera, ekf)
            if after is not None:
                return after
        if cfg.landing and not ekf.initialised and not self.parabola_used and misses >= cfg.parabola_misses:
            found = image_parabola_landing(np.array(self.history, float).reshape(-1, 3), float(index))
            if found is not None:
                centre, half = found
                self.parabola_used = True
                return Reinit("image_parabola", centre, np.maximum(half, cfg.min_sigma_px * scale))
        if life.lost and self.centre_search(camera, previous, width, height):
            centre = np.array([(width - 1) / 2.0, (height - 1) / 2.0])
            sigma = filling_sigma(min(self.search.max_px * scale, width, height), self.search)
            return Reinit("lost_centre", centre, np.full(2, sigma))
        return Reinit.none()
