"""Honest status: is the selected blob the ball? (ours, on top of the paper's §2.1 gate)

The blob gate (:mod:`.blobs`) only asks whether a blob *looks* like the ball. This stage asks
whether it can *be* the ball given the motion model, and gives every frame a confidence:

- **validation gate** around the particles' predicted mean: radius ``gate_sigmas * s`` with
  ``s = sqrt(σx² + σy²) + D/2`` (the samples' spread after eq. (1) and the ball diameter), ``s``
  at most ``max_spread_px + D`` so a cloud spread wide after a loss does not accept anything in
  the picture. Only shape-accepted blobs inside the gate are the observation ``z_t`` of eq. (2);
- **confidence** of the in-gate blob nearest the prediction, ``L = fit * exp(-d² / 2s²)`` (``fit`` from
  its area and roundness against the targets, ``d`` its distance from the prediction), times its share
  ``L / ΣL`` of the in-gate blobs' likelihoods (each blob's ``L`` alike), the probability that it,
  of them, is the ball (PDA's association probability without a missed-detection term). A blob within a
  ball diameter of it is a piece of the same ball (a ball split by a seam's shadow), not a rival, and is
  left out of the sum. Alone in the gate it keeps ``L``; beside a look-alike as near it holds half (a
  shuttle among a player's white socks: on the wide-angle rally the track then stays ``predicted``
  instead of following a sock).
  ``measured`` needs ``min_confidence``, and
  ``min_fit`` from the shape alone (a speck a fifth of the ball's area right on the predicted path
  is not the ball: the edge of a cup's liner after the ball merged with it); below, the row is
  ``predicted`` and nothing (targets, EKF, LUTs) learns from the blob;
- **merged nearer** (verdict ``merged_nearer``): a blob refused for its shape alone that lies nearer
  the prediction than the candidate and has the ball's area more nearly is the ball merged with
  something (rolling over the cup's white liner); the candidate beside it is then not ``measured``;
- **no jumps without evidence**: a shape-accepted blob outside the gate, or any blob once the
  track is lost, or while the prediction has left the picture, starts or extends a *tentative*
  track. Only when it has been seen on ``confirm_frames`` consecutive frames, each within
  ``confirm_px + D`` of the constant-velocity extrapolation of the previous ones, is it accepted:
  the particles start again there (re-initialisation kind ``"confirmed"``), provided the tentative
  blobs agree with *each other*: their areas within ``area_tolerance`` of one another and their
  roundness within the shape tolerance of a disc (``confirm_fit`` of :func:`track_fit`). The
  targets are not asked: after a loss they are stale (a receding ball under a zooming lens, a
  streak's fragments), and the ball's size starts again from the confirmed blobs. When another
  accepted blob of a similar size (to the track's or to the ball's as last seen) is in view, nothing
  is confirmed (verdict ``ambiguous``): after a loss the tracker cannot tell its ball from a spare one;
- **gone**: when the predicted mean is more than a ball diameter outside the picture nothing in
  the picture is accepted directly (the ball left it); when it is outside by less, only a blob the
  edge cuts (:func:`cut_by_edge`: what is left of a ball leaving); the track is ``predicted`` and then
  ``lost`` (no position) after ``max_predicted_frames`` misses, like any other miss. When the
  camera does not follow the ball (``entry_only``), a tentative track must then start within
  ``entry_margin_px`` (+ 2 D) of the picture's edge: the ball comes back in through it.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from trackreplay.trackers.geometry.homography import apply_homography
from trackreplay.trackers.golf.blobs import CIRCULARITY, ELONGATED, EXCESS, STILL, GatedBlobs, roundness, shape_tolerance
from trackreplay.trackers.golf.config import BlobConfig, ValidateConfig

MERGED_SHAPES = (CIRCULARITY, EXCESS, ELONGATED)  # blobs refused for their shape, not their size
VERDICTS = ("measured", "confirmed", "no_candidate", "low_confidence", "outside_gate", "outside_image", "lost", "start",
            "ambiguous", "merged_nearer", "too_near", "seen_before", "unconfirmed")


@dataclass(frozen=True, eq=False)
class Validation:
    """The validation stage's intermediates."""

    verdict: str  # one of VERDICTS: why this frame is (not) measured
    confidence: float  # of the ball blob considered (0: none)
    fit: float  # its area/roundness fit to the targets
    motion: float  # its agreement with the predicted position
    gate_px: float  # validation gate radius around the prediction
    candidate: int  # the blob row considered (-1: none)
    tentative: np.ndarray  # (n, 3) frame, x, y of the unconfirmed track (0 rows: none)
    in_gate: np.ndarray  # (K,) bool: blobs inside the gate that measure eq. (2)

    @classmethod
    def empty(cls) -> Validation:
        return cls("", 0.0, 0.0, 0.0, math.nan, -1, np.zeros((0, 3)), np.zeros(0, bool))


def beyond_edges(point: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """Which edges (left, top, right, bottom) ``point`` lies beyond: outside the picture, whose
    pixels' centres span ``0 … width - 1`` and whose pixels reach half a pixel further."""
    width, height = size
    x, y = float(point[0]), float(point[1])
    return np.array([x < -0.5, y < -0.5, x > width - 0.5, y > height - 0.5])


def cut_by_edge(bbox: np.ndarray, predicted: np.ndarray, size: tuple[int, int], tolerance: float) -> np.ndarray:
    """Which blobs (boxes ``x0, y0, w, h``) can be a ball predicted at ``predicted``: all of them while
    the prediction is inside the picture; once its centre is beyond an edge, only those reaching
    within ``tolerance`` px of that edge. A ball leaving the picture shows at most the part the edge
    cuts; a blob wholly inside is something else (a review: after an iron shot climbed out through
    the top, the corner of a broadcast's white logo box 11 px below the edge was measured for 44 frames)."""
    edges = beyond_edges(predicted, size)
    boxes = np.asarray(bbox, float).reshape(-1, 4)
    if not edges.any():
        return np.ones(len(boxes), bool)
    width, height = size
    reach = np.stack([boxes[:, 0] <= tolerance, boxes[:, 1] <= tolerance,
                      boxes[:, 0] + boxes[:, 2] >= width - tolerance, boxes[:, 1] + boxes[:, 3] >= height - tolerance], axis=1)
    return (reach & edges).any(axis=1)


def blob_fit(gated: GatedBlobs, k: int, cfg: BlobConfig, scale: float) -> float:
    """How well blob ``k`` fits the target area and roundness, in (0, 1]."""
    slack = cfg.area_slack_px * scale * scale
    ratio = math.log((float(gated.blobs.area[k]) + slack) / (float(gated.targets[0]) + slack)) / math.log(cfg.area_tolerance)
    r = float(roundness(gated.blobs)[k])
    tol = float(shape_tolerance(gated.blobs.area[k], cfg, scale))
    short = max(0.0, float(gated.targets[1]) - r) / tol if math.isfinite(r) else 1.0
    return math.exp(-0.5 * ratio * ratio) * math.exp(-0.5 * short * short)


def track_fit(areas: np.ndarray, rounds: np.ndarray, cfg: BlobConfig, scale: float, min_area: float = 2.0) -> float:
    """How well the blobs of a tentative track agree with one another and with a disc, in [0, 1]:
    the spread of their log-areas (in units of ``log area_tolerance``) and how far their median
    roundness falls short of a disc's (in units of the shape tolerance). 0 when a blob has fewer
    than ``min_area`` pixels: a single pixel has no shape, and noise specks are single pixels."""
    if np.asarray(areas, float).size and float(np.min(areas)) < min_area:
        return 0.0
    slack = cfg.area_slack_px * scale * scale
    la = np.log(np.asarray(areas, float) + slack)
    spread = float(la.max() - la.min()) / math.log(cfg.area_tolerance) if la.size else 0.0
    r = float(np.nanmedian(rounds)) if np.isfinite(rounds).any() else 0.0
    tol = float(shape_tolerance(np.median(areas), cfg, scale))
    short = max(0.0, 1.0 - cfg.circularity_tolerance - r) / tol
    return math.exp(-0.5 * spread * spread) * math.exp(-0.5 * short * short)


@dataclass
class Tentative:
    """One unconfirmed track: (frame, x, y) rows as each frame saw them, the (area, roundness) of
    each blob, and the rows' points as the latest pose sees them (``in_view``: the camera's own
    motion since taken out, :meth:`Validator.follow_camera`)."""

    rows: list[tuple[int, float, float]]
    shapes: list[tuple[float, float]]
    in_view: list[tuple[float, float]] = field(default_factory=list)
    repeats: list[bool] = field(default_factory=list)  # the row's frame showed the picture before it again
    seeded: bool = False  # its first row is the mark's (:meth:`Validator.seed_at`): the ball's own start

    def __post_init__(self) -> None:
        if not self.in_view:
            self.in_view = [row[1:] for row in self.rows]
        if not self.repeats:
            self.repeats = [False] * len(self.rows)

    def add(self, index: int, point: tuple[float, float], shape: tuple[float, float], repeat: bool = False) -> None:
        self.rows.append((index, *point))
        self.in_view.append(point)
        self.shapes.append(shape)
        self.repeats.append(repeat)

    def expected(self) -> np.ndarray:
        """Constant-velocity extrapolation of its last two points to the next frame (its last point
        when it has one), in the latest pose's pixels: the ball's motion against the world, so a
        camera sweeping after it does not bend the track. Rows frames apart (a track seeded at the
        mark, whose next sighting came later) give the step per frame."""
        last = np.array(self.in_view[-1])
        if len(self.in_view) < 2:
            return last
        frames = max(self.rows[-1][0] - self.rows[-2][0], 1)
        return last + (last - np.array(self.in_view[-2])) / frames


SCENERY_PLACES = 4


class Validator:
    """Decides per frame whether the ball was seen, with tentative tracks for jumps.

    Several tentative tracks are kept at once (at most ``max_tentative``): every shape-accepted blob
    that no track takes starts one, so a distractor nearer the prediction does not stop the ball's
    own track from forming. A track's second blob may be up to ``confirm_first_step_px`` (+ D) from
    its first (the speed is not known yet: a ball falling back into the picture moves tens of px
    per frame); every later one within ``confirm_px`` (+ D) of the constant-velocity extrapolation.
    """

    def __init__(self, cfg: ValidateConfig, blobs: BlobConfig) -> None:
        self.cfg = cfg
        self.blobs = blobs
        self.tracks: list[Tentative] = []
        self.best: Tentative | None = None  # the longest live track (shown; confirmed from)
        self.scenery: set[int] = set()  # this frame's blobs on still tracks in a fixed view
        self.anchor: tuple[int, float, float] | None = None  # the mark (frame, x, y) while the ball's speed is unknown

    def reset(self) -> None:
        self.tracks = []
        self.best = None
        self.scenery = set()
        self.anchor = None

    def seed_at(self, index: int, point: tuple[float, float]) -> None:
        """The user marked the ball at ``point`` on frame ``index``: until it is seen again within a
        diameter of there (at rest, or slow) or a track from the mark is confirmed, its speed is
        unknown, and a blob away from the mark is no measurement of it (:meth:`validate`). Every
        blob within reach on the ``confirm_frames`` frames after the mark starts a tentative track
        from the mark itself (:meth:`_branch_from_mark`): the mark is the track's first row."""
        self.anchor = (int(index), float(point[0]), float(point[1]))

    def _first_step(self, index: int, point: np.ndarray, diameter: float) -> bool:
        """``point`` is a step of unknown speed: away from the mark (more than a diameter) while no
        step of the ball's has been seen since it (a single mark gives no velocity: the blob nearest a
        prediction that stays at the mark is as likely a player's shoe as the shuttle). Once no path
        from the mark is left and none can start (``confirm_frames`` after it), the samples, drawn by
        the in-gate blobs meanwhile, are all there is to go on: the gate measures as before."""
        if self.anchor is not None and index - self.anchor[0] > self.cfg.confirm_frames and not any(
                t.seeded and t.rows[-1][0] == index - 1 for t in self.tracks):
            self.anchor = None
        if self.anchor is None or index == self.anchor[0]:
            return False
        return math.hypot(float(point[0]) - self.anchor[1], float(point[1]) - self.anchor[2]) > diameter

    def follow_camera(self, homography: np.ndarray) -> None:
        """The pose changed by ``homography`` (last frame's pixels -> this frame's): the tentative
        tracks' points are carried along, so their extrapolation (:meth:`Tentative.expected`) is
        the ball's own motion, not the sweep of a camera following it."""
        if not self.tracks:
            return
        points = apply_homography(homography, np.array([p for t in self.tracks for p in t.in_view], float))
        start = 0
        for track in self.tracks:
            n = len(track.in_view)
            track.in_view = [(float(x), float(y)) for x, y in points[start:start + n]]
            start += n

    def next_point(self, diameter: float, scale: float) -> tuple[np.ndarray, float] | None:
        """Where the longest tentative track expects its next blob, and how far from there it may
        be (None: no track): the search region must reach it, or the evidence it waits for is
        never looked at (a ball hopping out of the samples' reach)."""
        if self.best is None:
            return None
        reach = self.cfg.confirm_px if len(self.best.rows) > 1 else self.cfg.confirm_first_step_px
        return self.best.expected(), reach * scale + diameter

    def gate(self, spread: np.ndarray, diameter: float, scale: float,
             size: tuple[int, int] | None = None) -> tuple[float, float]:
        """``(s, radius)``: the motion scale and the gate radius for this frame; the radius at most a
        quarter of the picture's shorter side when ``size`` is given."""
        s = min(float(np.hypot(*spread)), self.cfg.max_spread_px * scale) + 0.5 * diameter
        if size is not None:
            s = min(s, min(size) / (4.0 * self.cfg.gate_sigmas))
        return s, self.cfg.gate_sigmas * s

    def seen_in_gate(self, *, gated: GatedBlobs, predicted: np.ndarray, spread: np.ndarray, diameter: float,
                     size: tuple[int, int], scale: float, lost: bool) -> tuple[Validation | None, np.ndarray, bool]:
        """The in-gate blob nearest the prediction, its confidence shared with look-alikes in the gate (module
        docstring), as a "measured", "low_confidence" or "merged_nearer" validation
        (None: no blob in the gate), the in-gate mask and whether the prediction left the picture.
        Changes nothing (the tracker also asks it of the other LUT's silhouette)."""
        width, height = size
        s, radius = self.gate(spread, diameter, scale, size)
        ok = gated.accepted
        c = gated.blobs.centroid
        d = np.hypot(c[:, 0] - predicted[0], c[:, 1] - predicted[1]) if len(c) else np.zeros(0)
        outside = bool(predicted[0] < -diameter or predicted[1] < -diameter or predicted[0] > width - 1 + diameter
                       or predicted[1] > height - 1 + diameter)
        in_gate = ok & (d <= radius) & (not outside) & (not lost)
        if in_gate.any() and not outside:
            in_gate &= cut_by_edge(gated.blobs.bbox, predicted, size, 0.5 * diameter)
            outside = not in_gate.any() and bool(beyond_edges(predicted, size).any())
        if not in_gate.any():
            return None, in_gate, outside
        rows = np.flatnonzero(in_gate)
        fits = np.array([blob_fit(gated, int(j), self.blobs, scale) for j in rows])
        motions = np.exp(-0.5 * (d[rows] / s) ** 2)
        like = fits * motions
        best = int(np.argmin(d[rows]))  # §2.1: the accepted blob nearest the prediction is the ball
        k, fit, motion = int(rows[best]), float(fits[best]), float(motions[best])
        # a look-alike is another object: a blob within a ball's diameter of this one is a piece of it
        apart = np.hypot(c[rows, 0] - c[k, 0], c[rows, 1] - c[k, 1]) > diameter
        confidence = fit * motion * float(like[best] / (like[best] + like[apart].sum()))
        verdict = "measured" if confidence >= self.cfg.min_confidence and fit >= self.cfg.min_fit else "low_confidence"
        if verdict == "measured" and self._merged_nearer(gated, k, d, scale):
            verdict = "merged_nearer"
        return Validation(verdict, confidence, fit, motion, radius, k, np.zeros((0, 3)), in_gate), in_gate, outside

    def _merged_nearer(self, gated: GatedBlobs, k: int, d: np.ndarray, scale: float) -> bool:
        """A blob refused for its shape alone lies nearer the prediction than candidate ``k`` and has
        the ball's area more nearly than ``k``: the ball merged with something (a ball rolling over
        the cup's white liner is one oval with it), so ``k`` (a piece of the liner beside it) is not
        taken for the ball on a guess."""
        nearer = d < d[k]
        if not nearer.any():  # the usual frame: nothing nearer, no np.isin (~60 % of this stage's cost)
            return False
        merged = np.isin(gated.reason, MERGED_SHAPES) & nearer
        if not merged.any():
            return False
        slack = self.blobs.area_slack_px * scale * scale
        off = np.abs(np.log((gated.blobs.area + slack) / (float(gated.targets[0]) + slack)))
        return bool((off[merged] < off[k]).any())

    def validate(self, *, index: int, gated: GatedBlobs, predicted: np.ndarray, spread: np.ndarray, diameter: float,
                 size: tuple[int, int], scale: float, lost: bool, entry_only: bool = False,
                 seen: tuple[Validation | None, np.ndarray, bool] | None = None, repeat: bool = False) -> Validation:
        """The frame's verdict. ``entry_only``: the camera does not follow the ball, so once the
        prediction has left the picture a new tentative track may only start near the border (a
        ball comes back into a fixed view through its edge, not out of a white cap mid-picture).
        ``seen``: what :meth:`seen_in_gate` already answered for these same arguments (it changes
        nothing, so the answer is the same; None: asked here)."""
        cfg = self.cfg
        _, radius = self.gate(spread, diameter, scale, size)
        ok = gated.accepted
        if seen is None:
            seen = self.seen_in_gate(gated=gated, predicted=predicted, spread=spread, diameter=diameter, size=size,
                                     scale=scale, lost=lost)
        found, in_gate, outside = seen
        if found is not None and found.verdict == "measured":
            if not self._first_step(index, gated.blobs.centroid[found.candidate], diameter):
                anchor = self.anchor if self.anchor is not None and self.anchor[0] == index else None
                self.reset()
                self.anchor = anchor  # (the mark's own frame: the speed is still unknown)
                return found
            found = dataclasses.replace(found, verdict="unconfirmed", confidence=0.0)
        verdict = "outside_image" if outside else "lost" if lost else "outside_gate" if ok.any() else "no_candidate"
        border = None
        if outside and entry_only:
            border = (size, cfg.entry_margin_px * scale + 2.0 * diameter)
        # A blob seen only with low confidence (off the prediction: a bounce, a hop) starts or extends a
        # tentative track like any other, so that seen on confirm_frames frames it is confirmed; while
        # the ball's size is known (a blob in the gate, not lost) only if its shape fits the ball's (min_fit).
        evidence = gated.accepted
        if found is not None:  # a blob whose shape says it is not the ball is no evidence for it
            evidence = evidence.copy()
            for j in np.flatnonzero(evidence):
                evidence[j] = blob_fit(gated, int(j), self.blobs, scale) >= cfg.min_fit
        k, fit = self._extend(index, gated, predicted, diameter, scale, border, must_move=entry_only, evidence=evidence,
                              repeat=repeat)
        if k >= 0 and fit >= cfg.confirm_fit:
            if self._ambiguous(gated, k, scale) if not self.best.seeded else self._rival_from_mark(diameter):
                return Validation("ambiguous", 0.0, fit, 0.0, radius, k, self._rows(), in_gate)
            return Validation("confirmed", fit, fit, 0.0, radius, k, self._rows(), in_gate)
        if found is not None:
            return dataclasses.replace(found, tentative=self._rows())
        return Validation(verdict, 0.0, 0.0, 0.0, radius, k, self._rows(), in_gate)

    def _ambiguous(self, gated: GatedBlobs, k: int, scale: float) -> bool:
        """Another shape-accepted blob this frame looks as much like the tentative ball, or like the ball
        as last seen (area within ``area_tolerance`` of the tentative blobs' median or of the targets'):
        after a loss the tracker cannot tell which of two such balls is its own (a spare ball, a tee
        marker), so it confirms neither. The targets count because the tentative track may be the
        look-alike: a player's white shoe walking off after a rally while the shuttle lies on the floor."""
        others = np.flatnonzero(gated.accepted | (gated.reason == STILL))  # still scenery is a look-alike too
        others = others[others != k]
        if not others.size or self.best is None:
            return False
        slack = self.blobs.area_slack_px * scale * scale
        typical = float(np.nanmedian(np.array(self.best.shapes, float).reshape(-1, 2)[:, 0]))
        area = gated.blobs.area[others] + slack
        like = np.minimum(np.abs(np.log(area / (typical + slack))), np.abs(np.log(area / (float(gated.targets[0]) + slack))))
        return bool((like <= math.log(self.blobs.area_tolerance)).any())

    def _rival_from_mark(self, diameter: float) -> bool:
        """Another track from the mark is alive this frame on a blob more than a diameter from the one to
        confirm: two paths leave the mark, and until one of them ends the tracker cannot tell which
        is its ball (a player's shoe moves away from a shuttle's mark too)."""
        best = self.best
        return any(t.seeded and t is not best and t.rows[-1][0] == best.rows[-1][0]
                   and math.hypot(t.rows[-1][1] - best.rows[-1][1], t.rows[-1][2] - best.rows[-1][2]) > diameter
                   for t in self.tracks)

    def confirmed_velocity(self) -> tuple[np.ndarray, float]:
        """The confirmed track's velocity for the next frame (px/frame): its last step plus the
        change between its last two steps (a ball slowing at the top of a hop changes speed by
        ~10 px/frame each frame), and that change's size (how unsure the velocity is). Steps between
        distinct pictures only: a frame that showed the picture before it again (a clip retimed by
        repeating frames) adds a zero step, and the last step's change then doubled the velocity: such a
        track's velocity is its mean over the frames it spans (the pictures come unevenly, so their steps
        per frame say nothing of the ball's acceleration), unsure by how far its steps between distinct
        pictures stray from that mean."""
        t = self._rows()
        # (only when a repeated picture is among the rows the last step and its change are read from: one
        # long ago leaves them as they are)
        if self.best is not None and any(self.best.repeats[max(1, len(t) - 3):]):
            distinct = t[[j for j in range(len(t)) if j == 0 or not self.best.repeats[j]]]
            mean = (distinct[-1, 1:] - distinct[0, 1:]) / max(distinct[-1, 0] - distinct[0, 0], 1.0)
            per_frame = np.diff(distinct[:, 1:], axis=0) / np.maximum(np.diff(distinct[:, 0]), 1.0)[:, None]
            return mean, float(np.max(np.hypot(*(per_frame - mean).T))) if len(per_frame) else 0.0
        steps = np.diff(t[:, 1:], axis=0) / np.maximum(np.diff(t[:, 0]), 1.0)[:, None]
        if len(steps) < 2:
            return (steps[-1] if len(steps) else np.zeros(2)), 0.0
        change = steps[-1] - steps[-2]
        return steps[-1] + change, float(np.hypot(*change))

    def _rows(self) -> np.ndarray:
        return np.array(self.best.rows if self.best is not None else [], float).reshape(-1, 3)

    def _still(self, track: Tentative, min_move: float) -> bool:
        """The track has two or more blobs and its last ``confirm_frames`` moved less than ``min_move`` px."""
        if len(track.rows) < 2:
            return False
        rows = track.rows[-self.cfg.confirm_frames:]
        return math.hypot(rows[-1][1] - rows[0][1], rows[-1][2] - rows[0][2]) < min_move

    def _fit(self, track: Tentative, scale: float, min_move: float = 0.0) -> float:
        """The track fit of the last ``confirm_frames`` distinct pictures of the track (0: fewer). A row
        taken on a frame that showed the picture before it again (``repeat``: a clip with repeated
        frames, 30 fps at 50 or 60) is no new sighting (a review: ball and cup liner "seen" on three
        frames that were two pictures, then liner pieces measured after the ball dropped)."""
        n = self.cfg.confirm_frames
        distinct = [j for j in range(len(track.rows)) if j == 0 or not track.repeats[j]]
        if len(distinct) < n:
            return 0.0
        last = distinct[-n:]
        rows = np.array([track.rows[j] for j in last], float)
        if min_move > 0 and float(np.hypot(*(rows[-1, 1:] - rows[0, 1:]))) < min_move:
            return 0.0
        shapes = np.array([track.shapes[j] for j in last], float).reshape(-1, 2)
        shapes = shapes[np.isfinite(shapes[:, 0])]  # the mark's row (a seeded track) has no blob's shape
        return track_fit(shapes[:, 0], shapes[:, 1], self.blobs, scale, self.cfg.confirm_min_area_px)

    def _extend(self, index: int, gated: GatedBlobs, predicted: np.ndarray, diameter: float, scale: float,
                border: tuple[tuple[int, int], float] | None = None, must_move: bool = False,
                evidence: np.ndarray | None = None, repeat: bool = False) -> tuple[int, float]:
        """Continue the tentative tracks with this frame's shape-accepted blobs (each track takes the
        blob nearest its extrapolation, longest tracks first; a blob extends one track), start a track
        from every blob left over (only within ``border = ((width, height), margin)`` of the picture's
        edge when given), and drop tracks that missed this frame. Returns the blob row of the best
        track that can be confirmed (``confirm_frames`` long, its track fit; of several, the one whose
        blobs' area is nearest the targets'; -1: none) and that fit.
        ``must_move``: the view is fixed, so a track that stays put over its confirm frames (less
        than a ball diameter) is part of the scene, not a ball in play, and is not confirmed.
        ``evidence``: the blobs that may extend or start a track (default: the shape-accepted ones)."""
        ok = np.flatnonzero(gated.accepted if evidence is None else evidence)
        rounds = roundness(gated.blobs)
        kept, free = self._continue_tracks(index, gated, rounds, ok, diameter, scale, repeat)
        kept += self._branch_from_mark(index, gated, rounds, ok, diameter, scale)
        kept += self._new_tracks(index, gated, rounds, ok[free], predicted, border)
        min_move = diameter if must_move else 0.0
        kept = self._keep(kept, must_move, min_move)
        return self._ready(kept, gated, scale, min_move)

    def _continue_tracks(self, index: int, gated: GatedBlobs, rounds: np.ndarray, ok: np.ndarray, diameter: float,
                         scale: float, repeat: bool) -> tuple[list[tuple[Tentative, int]], np.ndarray]:
        """The tracks live on the frame before, longest first, each extended by the free blob of ``ok``
        nearest its extrapolation when within reach: the (track, blob row) pairs, and which of ``ok``
        no track took. A track from the mark (``seeded``) takes its blob whether or not another took it,
        and leaves it free: the paths from the mark are hypotheses about one ball, not rival claims."""
        cfg, c = self.cfg, gated.blobs.centroid
        live = sorted((t for t in self.tracks if index - t.rows[-1][0] == 1), key=lambda t: -len(t.rows))
        free = np.ones(len(ok), bool)
        kept: list[tuple[Tentative, int]] = []
        for track in live:
            if not ok.size or not (free.any() or track.seeded):
                continue
            reach = (cfg.confirm_px if len(track.rows) > 1 else cfg.confirm_first_step_px) * scale + diameter
            expected = track.expected()
            dist = np.hypot(c[ok, 0] - expected[0], c[ok, 1] - expected[1])
            dist = dist if track.seeded else np.where(free, dist, np.inf)
            j = int(np.argmin(dist))
            if dist[j] <= reach:
                free[j] = free[j] and track.seeded
                k = int(ok[j])
                track.add(index, (float(c[k, 0]), float(c[k, 1])), (float(gated.blobs.area[k]), float(rounds[k])), repeat)
                kept.append((track, k))
        return kept, free

    def _branch_from_mark(self, index: int, gated: GatedBlobs, rounds: np.ndarray, ok: np.ndarray, diameter: float,
                          scale: float) -> list[tuple[Tentative, int]]:
        """On the ``confirm_frames`` frames after the mark, while the ball's speed is unknown, a track from
        the mark to every blob of ``ok`` within ``confirm_first_step_px`` (+ D) per frame since it,
        nearest the mark first (the blob may also extend or start another track)."""
        if self.anchor is None:
            return []
        frame, x, y = self.anchor
        gap = index - frame
        if not 0 < gap <= self.cfg.confirm_frames or not ok.size:
            return []
        c = gated.blobs.centroid[ok]
        dist = np.hypot(c[:, 0] - x, c[:, 1] - y)
        near = np.flatnonzero(dist <= self.cfg.confirm_first_step_px * scale * gap + diameter)
        return [(Tentative([(frame, x, y), (index, float(c[j, 0]), float(c[j, 1]))],
                           [(math.nan, math.nan), (float(gated.blobs.area[ok[j]]), float(rounds[ok[j]]))], seeded=True),
                 int(ok[j])) for j in near[np.argsort(dist[near], kind="stable")]]

    @staticmethod
    def _new_tracks(index: int, gated: GatedBlobs, rounds: np.ndarray, starts: np.ndarray, predicted: np.ndarray,
                    border: tuple[tuple[int, int], float] | None) -> list[tuple[Tentative, int]]:
        """A new track from each blob row of ``starts`` (within ``border`` of the edge when given),
        nearest the prediction first."""
        c = gated.blobs.centroid
        if border is not None and starts.size:
            (width, height), margin = border
            x, y = c[starts, 0], c[starts, 1]
            starts = starts[(x < margin) | (y < margin) | (x > width - 1 - margin) | (y > height - 1 - margin)]
        order = np.argsort(np.hypot(c[starts, 0] - predicted[0], c[starts, 1] - predicted[1]), kind="stable")
        return [(Tentative([(index, float(c[k, 0]), float(c[k, 1]))], [(float(gated.blobs.area[k]), float(rounds[k]))]),
                 int(k)) for k in starts[order]]

    def _keep(self, kept: list[tuple[Tentative, int]], must_move: bool,
              min_move: float) -> list[tuple[Tentative, int]]:
        """The tracks kept for the next frame (the longest first is :attr:`best`), at most
        ``max_tentative``. In a fixed view a track that stays put is scenery (a tee, a marker, a cap):
        never confirmed (still a rival in :meth:`_ambiguous`: a look-alike in view keeps a new track from
        confirmation). Scenery has places of its own (up to SCENERY_PLACES x max_tentative), so it
        neither crowds out a ball's new track nor, dropped and restarted, comes back each frame as a
        new rival."""
        self.scenery = {k for track, k in kept if must_move and self._still(track, min_move)}
        kept = ([tk for tk in kept if tk[1] not in self.scenery][:self.cfg.max_tentative]
                + [tk for tk in kept if tk[1] in self.scenery][:SCENERY_PLACES * self.cfg.max_tentative])
        self.tracks = [t for t, _ in kept]
        self.best = self.tracks[0] if self.tracks else None
        return kept

    def _ready(self, kept: list[tuple[Tentative, int]], gated: GatedBlobs, scale: float,
               min_move: float) -> tuple[int, float]:
        """The blob row and track fit of the track to confirm: of several that could be, one from the mark
        (:meth:`_branch_from_mark`) before any other (while the ball's speed is unknown, none other), then the one most
        like the ball last seen (its area), then :attr:`best`; else the longest track's (-1: none)."""
        fits = [self._fit(track, scale, min_move) for track, _ in kept]
        ready = [j for j, fit in enumerate(fits) if fit >= self.cfg.confirm_fit]
        # a path from the mark first: the ball's own; while its speed is unknown (the anchor), only such a path:
        # the blob the gate would have measured is "unconfirmed", and a track elsewhere must not win by default
        ready = [j for j in ready if kept[j][0].seeded] or ([] if self.anchor is not None else ready)
        if ready:
            slack = self.blobs.area_slack_px * scale * scale
            target = float(gated.targets[0]) + slack
            unlike = [abs(math.log((float(np.nanmedian(np.array(kept[j][0].shapes)[:, 0])) + slack) / target)) for j in ready]
            j = ready[int(np.argmin(unlike))]
            self.best = kept[j][0]
            return kept[j][1], fits[j]
        return (kept[0][1], fits[0] if self.anchor is None else 0.0) if kept else (-1, 0.0)

    def confirmed_shape(self) -> tuple[float, float]:
        """Median area and roundness of the confirmed tentative blobs: the ball's new targets."""
        shapes = np.array(self.best.shapes if self.best is not None else [], float).reshape(-1, 2)
        shapes = shapes[np.isfinite(shapes[:, 0])]
        return float(np.median(shapes[:, 0])), float(np.nanmedian(shapes[:, 1])) if np.isfinite(shapes[:, 1]).any() else 0.9
