"""The camera's motion since the marked frame (ours, ``camera.compensate``).

Eq. (7)'s background, the foreground cue, the region refinement and the hold all assume a fixed
camera. A hand-held, panning or zooming camera (most OTB-style clips) moves the scene a fraction
of a pixel to a few pixels per frame: the early median is then a smear, and the frame differs from
it along every edge, yet over less than half the frame, so :func:`.foreground.scene_changed` does
not switch the cues off and they fire on edges (measured on otb_crossing panned at 0.5 px/frame:
AUC 0.66 -> 0.44, docs/colorpf_robustness.md).

:class:`CameraMotion` measures a similarity transform (scale, rotation, translation) from the
marked frame to each frame: Shi-Tomasi corners of a key frame (outside the tracked box, whose
target moves on its own) followed by pyramidal Lucas-Kanade into each frame (brightness-matched to
the key frame: LK assumes constant brightness, an illumination change is not motion), and a
least-squares similarity refitted on the corners within 3x the median residual (other movers are a
minority of the corners; the project's one fitter, :func:`..geometry.view_change.fit_similarity`,
"medians", with the parameters here). Always against the key frame, not chained frame
to frame, so a still camera has no drift (chained, otb_crossing's still camera wandered 0.6 px in
120 frames); LK starts each corner where it was last found (the motion since the last frame is
small). The key frame is renewed when fewer than half of its corners are still tracked, and (``renew =
"deformation"``) once the scale and rotation since it deform an LK window by half a pixel
(:func:`window_deformation`: LK matches a translated window, and a zooming camera's corners stay
"tracked" long after their windows stopped matching). A probe of a
few corners comes first: when they have not moved since last found, the last transform stands (a
still camera costs the probe alone; docs/colorpf_robustness.md's table is unchanged by it); after a frame on
which the scene moved, every corner is followed in one LK call and the probe read from it (the same answers,
one pair of image pyramids fewer).

:func:`snap`: a transform that moves no pixel of the frame by half a pixel or more through its
scale and rotation is taken as a translation rounded to whole pixels (a still camera is then
exactly the identity: its trajectory is unchanged). Deterministic: no random draw.
"""

from __future__ import annotations

import cv2
import numpy as np

from trackreplay.trackers.appearance.color import to_grey
from trackreplay.trackers.geometry.view_change import apply, at_full_size, fit_similarity
from trackreplay.trackers.median import median

MAX_CORNERS = 120  # LK cost is linear in it; 120 vs 200: the robustness table within seed noise (zoom 0.59 vs 0.60)
QUALITY = 0.01
# maxLevel 1: LK starts from the last position, so it searches only the motion since the last
# frame; coarser levels average a 15 px window over 60-120 px, where one large mover (a passing
# car) then drags the corners around it. 10 iterations, not 20: the same robustness table
# (docs/colorpf_robustness.md, pan/zoom rows within 0.012 AUC) at 0.7x the cost; 11 px windows
# cost half but lost 0.02-0.04 AUC on the pan and zoom rows
LK = {"winSize": (15, 15), "maxLevel": 1, "criteria": (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 10, 0.03)}
IDENTITY = np.eye(3)
PROBE = 24  # corners followed first: when they have not moved, the full measurement is skipped
STILL_PX = 0.2  # ... "not moved": their median displacement since last found, well under snap's half pixel
HALVE_FROM = 640  # frames at least this wide are measured at half size
# renew="deformation": the key frame is renewed once the scale and rotation since it move a corner of the
# LK window by this much relative to its centre (snap's half pixel, on the window; 15 px: a ~6.7 % scale)
MAX_DEFORMATION_PX = 0.5
# The fit (geometry.view_change.fit_similarity, "medians"): its least-squares refits, and how far from
# the points' median a point must lie to say anything about scale and rotation
FIT_ROUNDS = 3
MIN_BASELINE = 20.0  # px


def scale_of(transform: np.ndarray) -> float:
    return float(np.sqrt(abs(np.linalg.det(transform[:2, :2]))))


def snap(transform: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """The transform, or a whole-pixel translation when its linear part moves no pixel of a frame of
    ``size`` (width, height) by half a pixel or more (about the frame's centre)."""
    half = np.array([size[0], size[1]]) / 2.0
    linear = transform[:2, :2] - np.eye(2)
    if np.abs(linear).sum(axis=1).max() * half.max() < 0.5:
        t = np.round(apply(transform, half[None])[0] - half)
        return np.array([[1.0, 0.0, t[0]], [0.0, 1.0, t[1]], [0.0, 0.0, 1.0]])
    return transform


def window_deformation(transform: np.ndarray, window: tuple[int, int] = LK["winSize"]) -> float:
    """How far (px) ``transform``'s scale and rotation move a corner of an LK window relative to its
    centre: LK matches the window as a translated copy, which holds while this is well under a pixel."""
    half = np.array(window, np.float64) / 2.0
    return float((np.abs(transform[:2, :2] - np.eye(2)) @ half).max())


def resamples(transform: np.ndarray) -> bool:
    """:func:`warp` interpolates between pixels: ``transform`` is not a whole-pixel translation (a
    scale, a rotation or a sub-pixel shift). The identity and whole-pixel shifts copy pixels exactly."""
    exact = np.array_equal(transform[:2, :2], np.eye(2)) and np.array_equal(transform[:2, 2], np.round(transform[:2, 2]))
    return not exact


def warp(image: np.ndarray, transform: np.ndarray) -> np.ndarray:
    """``image`` carried by ``transform`` (content at p goes to T p), the uncovered border repeating the
    edge; a whole-pixel translation copies pixels exactly, the identity returns ``image`` itself."""
    if np.array_equal(transform, IDENTITY):
        return image
    return cv2.warpAffine(image, transform[:2], (image.shape[1], image.shape[0]),
                          flags=cv2.INTER_LINEAR if resamples(transform) else cv2.INTER_NEAREST,
                          borderMode=cv2.BORDER_REPLICATE)


def shift_image(image: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """``image`` moved by ``offset`` ``(dx, dy)`` (whole pixels copied exactly, fractions bilinear; the edge repeated)."""
    dx, dy = (float(v) for v in offset)
    return warp(image, np.array([[1.0, 0.0, dx], [0.0, 1.0, dy], [0.0, 0.0, 1.0]]))


class CameraMotion:
    """The similarity ``T`` (3x3) from the first frame given to each frame: a static point at p in
    the first frame is at ``T p`` in the frame. Frames :data:`HALVE_FROM` px wide or wider are measured
    at half size (the cost of a 720x480 frame is then a 360x240 one's; T is scaled back)."""

    def __init__(self, min_corners: int = 20, min_distance: int = 8, renew: str = "deformation") -> None:
        self.min_corners = min_corners
        self.renew = renew
        self.min_distance = min_distance
        self._key: np.ndarray | None = None
        self._key_mean = 1.0
        self._corners: np.ndarray | None = None  # (n, 1, 2) float32 in the key frame
        self._last: np.ndarray | None = None  # where they were found in the last frame (LK's first guess)
        self._key_transform = IDENTITY.copy()  # in the measured (possibly halved) frame's pixels
        self._transform = IDENTITY.copy()
        self._factor = 1
        self._probed: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None  # this frame's probe: picks, LK's answer
        # the scene moved at the last measurement (a moving camera: the full measurement is likely again), so
        # every corner is followed in one LK call and the probe read from it (LK follows each point on its own:
        # the same answers as the probe's call and the rest's, one call's image pyramids fewer)
        self._moving = False
        self._followed: tuple[np.ndarray, np.ndarray] | None = None  # this frame's every corner, followed

    @property
    def transform(self) -> np.ndarray:
        if self._factor == 1:
            return self._transform.copy()
        return at_full_size(self._transform, 1.0 / self._factor)

    def _rekey(self, g: np.ndarray, box: np.ndarray | None) -> None:
        mask = np.full(g.shape, 255, np.uint8)
        if box is not None:  # the tracked box (x0, y0, x1, y1): its target moves on its own
            x0, y0, x1, y1 = (int(v) // self._factor for v in box)
            mask[max(y0, 0):max(y1 + 1, 0), max(x0, 0):max(x1 + 1, 0)] = 0
        self._key, self._key_transform = g, self._transform.copy()
        self._key_mean = max(float(g[::4, ::4].mean()), 1.0)
        self._corners = cv2.goodFeaturesToTrack(g, MAX_CORNERS, QUALITY, self.min_distance, mask=mask, blockSize=5)
        self._last = None if self._corners is None else self._corners.copy()

    def _unmoved(self, matched: np.ndarray) -> bool:
        """Whether a spread-out probe of :data:`PROBE` corners, followed from where they were last
        found, moved less than :data:`STILL_PX` (median): the scene has not moved since the last
        measurement, which then stands (a still camera costs a probe, not a measurement). A slow
        drift adds up against those positions until it shows, so the transform lags it by less than
        :data:`STILL_PX`, under the half pixel :func:`snap` rounds away."""
        assert self._corners is not None and self._last is not None
        if len(self._corners) < 2 * PROBE:
            return False
        pick = np.linspace(0, len(self._corners) - 1, PROBE).round().astype(np.int64)
        last = self._last[pick]
        if self._moving:  # it moved at the last measurement: every corner followed at once, the probe read from it
            everyone, everyone_status, _ = cv2.calcOpticalFlowPyrLK(
                self._key, matched, self._corners, self._last.copy(), flags=cv2.OPTFLOW_USE_INITIAL_FLOW, **LK)
            self._followed = (everyone, everyone_status)
            moved, status = everyone[pick], everyone_status[pick]
        else:
            moved, status, _ = cv2.calcOpticalFlowPyrLK(self._key, matched, self._corners[pick], last.copy(),
                                                        flags=cv2.OPTFLOW_USE_INITIAL_FLOW, **LK)
        self._probed = (pick, moved, status)
        ok = status.ravel() == 1
        if 2 * ok.sum() < PROBE:
            return False
        return median(np.hypot(*(moved[ok, 0] - last[ok, 0]).T)) < STILL_PX

    def _follow(self, matched: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """LK of every corner from where it was last found: (n, 1, 2) positions and (n, 1) status. LK
        follows each point on its own (the same images and first guess give the same answer in any
        call), so the probe's corners are taken from the probe and only the others are followed."""
        assert self._corners is not None and self._last is not None
        if self._followed is not None:  # followed with the probe (_unmoved)
            return self._followed
        if self._probed is None:
            moved, status, _ = cv2.calcOpticalFlowPyrLK(self._key, matched, self._corners, self._last.copy(),
                                                        flags=cv2.OPTFLOW_USE_INITIAL_FLOW, **LK)
            return moved, status
        pick, probe_moved, probe_status = self._probed
        rest = np.ones(len(self._corners), bool)
        rest[pick] = False
        moved = np.empty((len(self._corners), 1, 2), np.float32)
        status = np.empty((len(self._corners), 1), np.uint8)
        moved[pick], status[pick] = probe_moved.reshape(-1, 1, 2), probe_status.reshape(-1, 1)
        moved[rest], status[rest], _ = cv2.calcOpticalFlowPyrLK(
            self._key, matched, self._corners[rest], self._last[rest], flags=cv2.OPTFLOW_USE_INITIAL_FLOW, **LK)
        return moved, status

    def update(self, image: np.ndarray, box: np.ndarray | None = None) -> np.ndarray:
        """The frame's transform; ``box``: the tracked box's corners (left out of a new key frame's corners)."""
        g = to_grey(image)
        if self._key is None:
            self._factor = 2 if g.shape[1] >= HALVE_FROM else 1
        if self._factor > 1:
            g = cv2.resize(g, (g.shape[1] // self._factor, g.shape[0] // self._factor), interpolation=cv2.INTER_AREA)
        if self._key is None or self._key.shape != g.shape:
            self._rekey(g, box)
            return self.transform
        corners = self._corners
        if corners is None or len(corners) < self.min_corners:  # too little texture: no measurement
            self._rekey(g, box)
            return self.transform
        gain = self._key_mean / max(float(g[::4, ::4].mean()), 1.0)
        matched = cv2.convertScaleAbs(g, alpha=gain)  # the key's brightness
        self._probed = self._followed = None
        if self._unmoved(matched):
            self._moving = False
            return self.transform
        self._moving = True
        moved, status = self._follow(matched)
        height, width = g.shape
        inside = ((moved[:, 0, 0] >= 0) & (moved[:, 0, 0] <= width - 1) & (moved[:, 0, 1] >= 0)
                  & (moved[:, 0, 1] <= height - 1))
        ok = (status.ravel() == 1) & inside
        step = None
        if ok.sum() >= self.min_corners:
            fit = fit_similarity(corners[ok], moved[ok], rounds=FIT_ROUNDS, min_baseline=MIN_BASELINE)
            step = fit.transform  # key -> this frame
            self._transform = step @ self._key_transform
        # a corner lost now moves with the scene from here on
        if step is not None:
            guess = apply(step, corners).reshape(-1, 1, 2).astype(np.float32)
            self._last = np.where(ok[:, None, None], moved, guess)
        if 2 * ok.sum() < len(corners) or (self.renew == "deformation" and step is not None
                                            and window_deformation(step) >= MAX_DEFORMATION_PX):
            self._rekey(g, box)
        return self.transform
