"""Per-frame ground truth of the ball, and the ball regions a user would mark for the colour LUTs."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from trackreplay.recorder.synth.golf.flight import AIR, REST, ROLL, TEE
from trackreplay.recorder.synth.golf.occluders import coverage
from trackreplay.schemas.records import GroundTruthFrame, GroundTruthObject, InitRegion

if TYPE_CHECKING:
    from trackreplay.recorder.synth.golf.scene import GolfShot

BALL_ID = 1


@dataclass(frozen=True)
class FrameTruth:
    frame: int
    t: float  # log-clock seconds
    position: np.ndarray  # (3,) ball centre, world metres
    phase: int  # code into flight.PHASES
    uv: tuple[float, float] | None  # image position of the centre; None when out of frame
    in_frame: bool
    occluded: bool
    diameter: float  # apparent diameter, px
    velocity_px: tuple[float, float] | None  # px/frame, including the camera's own motion
    background: str  # what lies behind the ball along the line of sight: "sky", "trees" or "ground"

    @property
    def visible(self) -> bool:
        return self.in_frame and not self.occluded

    def record(self, t_ns: int) -> GroundTruthFrame:
        x, y, z = (float(c) for c in self.position)
        if self.uv is None:
            obj = GroundTruthObject(BALL_ID, X=x, Y=y, Z=z, visible=False)
        else:
            vx, vy = self.velocity_px if self.velocity_px is not None else (None, None)
            obj = GroundTruthObject(BALL_ID, x=self.uv[0], y=self.uv[1], w=self.diameter, h=self.diameter,
                                    X=x, Y=y, Z=z, vx=vx, vy=vy, visible=self.visible)
        return GroundTruthFrame(self.frame, t_ns, (obj,))


@dataclass(frozen=True)
class Annotation:
    region: InitRegion
    background: str  # "sky" or "ground"


def _project(shot: GolfShot, t: float, point: np.ndarray) -> np.ndarray:
    return shot.camera_at(t).project_points(point)[0]


def background_behind(shot: GolfShot, position: np.ndarray, t: float) -> str:
    """Sky, the distant tree line or the ground behind the ball as the camera sees it."""
    course = shot.world.course
    c = shot.cfg.camera_xyz
    d = position - c
    dh = math.hypot(d[0], d[1])
    if dh < 1e-9:
        return "sky" if d[2] > 0 else "ground"
    slope = d[2] / dh
    ch = c[:2] - course.tee
    u = d[:2] / dh
    b = float(ch @ u)
    s = -b + math.sqrt(b * b - (float(ch @ ch) - course.treeline_radius**2))  # horizontal run to the tree line
    z = c[2] + slope * s
    if z < 0.0:
        return "ground"
    hit = ch + s * u
    height = float(course.treeline_profile(np.array([math.atan2(hit[1], hit[0])]))[0])
    return "trees" if z <= height else "sky"


def frame_truth(shot: GolfShot, k: int) -> FrameTruth:
    cfg = shot.cfg
    t = float(shot.frame_times[k])
    cam = shot.camera_at(t)
    flight = shot.trajectory.sample([t - cfg.launch_at])
    p = flight.position[0]
    rng = float(np.linalg.norm(p - cam.position))
    diameter = 2.0 * cam.intrinsics.fx * cfg.ball.radius / rng
    uv = cam.project_points(p)[0]
    in_frame = bool(np.isfinite(uv).all() and -0.5 <= uv[0] < cfg.width - 0.5 and -0.5 <= uv[1] < cfg.height - 0.5)
    occluded = False
    occ = shot.world.occluder
    if occ is not None and occ.distance(cam.position, t) < rng:
        ray = ((p - cam.position) / rng)[None, :]
        occluded = bool(coverage(occ, cam.position, ray, 1.0 / cam.intrinsics.fx, t)[0] >= 0.5)
    vel = None
    if in_frame:
        dt = 1e-3
        ta, tb = t - dt, t + dt
        if shot.cut_time is not None and ta < shot.cut_time <= tb:
            ta = t if t >= shot.cut_time else ta
            tb = tb if t >= shot.cut_time else t
        ends = shot.ball_at(np.array([ta, tb]))
        ua, ub = _project(shot, ta, ends[0]), _project(shot, tb, ends[1])
        v = (ub - ua) / (tb - ta) / cfg.fps
        vel = (float(v[0]), float(v[1]))
    return FrameTruth(
        k, t, p.copy(), int(flight.phase[0]), (float(uv[0]), float(uv[1])) if in_frame else None, in_frame, occluded,
        float(diameter), vel, background_behind(shot, p, t),
    )


def _clear_of_distractors(shot: GolfShot, truth: FrameTruth, margin: float) -> bool:
    assert truth.uv is not None
    for blob in shot.world.blobs:
        uv = _project(shot, truth.t, blob.at(truth.t)[0])
        if np.isfinite(uv).all() and math.hypot(uv[0] - truth.uv[0], uv[1] - truth.uv[1]) < margin:
            return False
    return True


def choose_annotations(shot: GolfShot, n_sky: int = 3, n_ground: int = 3) -> list[Annotation]:
    """Ball boxes a user would mark: clearly over sky in flight, and over grass on the tee and rolling.

    Only frames where the ball is visible, well inside the image, at least 2.5 px across (at 720
    lines; 1.5 px at least), nearly still in the image (little motion blur) and away from the
    distractors qualify.
    """
    cfg = shot.cfg
    border = 12.0
    min_diameter = max(1.5, 2.5 * cfg.height / 720.0)

    def ok(tr: FrameTruth) -> bool:
        if not tr.visible or tr.uv is None or tr.velocity_px is None:
            return False
        u, v = tr.uv
        if not (border <= u < cfg.width - border and border <= v < cfg.height - border):
            return False
        if tr.diameter < min_diameter or math.hypot(*tr.velocity_px) > max(1.0, 0.5 * tr.diameter):
            return False
        return _clear_of_distractors(shot, tr, 6.0 * tr.diameter + 10.0)

    sky = [tr for tr in shot.truth if tr.phase == AIR and tr.background == "sky" and ok(tr)]
    tee = [tr for tr in shot.truth if tr.phase == TEE and tr.background == "ground" and ok(tr)]
    rolling = [tr for tr in shot.truth if tr.phase in (ROLL, REST) and tr.background == "ground" and ok(tr)]
    picks: list[tuple[FrameTruth, str]] = []

    def spread(cands: list[FrameTruth], n: int, qs: tuple[float, ...]) -> list[FrameTruth]:
        if not cands or n <= 0:
            return []
        idx = sorted({int(round(q * (len(cands) - 1))) for q in qs[:n]})
        return [cands[i] for i in idx]

    picks += [(tr, "sky") for tr in spread(sky, n_sky, (0.2, 0.5, 0.8, 0.35, 0.65))]
    ground = tee[:1] + spread(rolling, n_ground - min(1, len(tee)), (0.3, 0.9, 0.6))
    picks += [(tr, "ground") for tr in ground]
    out = []
    for tr, bg in sorted(picks, key=lambda p: p[0].frame):
        assert tr.uv is not None
        side = float(max(2.0, math.ceil(tr.diameter)))
        t_ns = int(round(tr.frame * 1e9 / cfg.fps))
        out.append(Annotation(InitRegion(tr.frame, t_ns, tr.uv[0], tr.uv[1], side, side, "ball"), bg))
    return out
