"""The hole around the shot: course layout, ball-like distractors, a bird, and an occluder.

Everything is fixed in the world (metres, Z up) and placed from the seed and the shot, so the
renderer can draw it consistently under any camera pose and the ground truth can ask whether the
ball is hidden.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from trackreplay.recorder.synth.golf.flight import Trajectory
from trackreplay.recorder.synth.golf.occluders import Occluder


@dataclass(frozen=True, eq=False)
class Course:
    """Ground regions in the shot's own coordinates: ``along`` the launch line from the tee, ``across`` to the left."""

    tee: np.ndarray  # (2,) world XY of the tee
    axis: np.ndarray  # (2,) unit vector along the hole
    fairway_half_width: float
    fairway_bend: float  # across-offset of the centreline per 100 m along (a gentle dog-leg)
    green_centre: np.ndarray  # (2,) along/across
    green_radii: tuple[float, float]
    bunker_centre: np.ndarray  # (2,) along/across
    bunker_radii: tuple[float, float]
    teebox: tuple[float, float, float]  # along min, along max, half width
    stripe_width: float  # mowing stripes across the fairway, m
    treeline_radius: float  # distant trees on a circle around the tee, m
    treeline_height: tuple[float, float]  # min, max height, m
    treeline_phases: np.ndarray  # (K,) phases of the height profile harmonics

    def to_local(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        tx, ty = float(self.tee[0]), float(self.tee[1])
        ax, ay = float(self.axis[0]), float(self.axis[1])  # Python floats keep float32 arrays float32
        dx, dy = x - tx, y - ty
        along = dx * ax + dy * ay
        across = dy * ax - dx * ay
        return along, across

    def treeline_profile(self, azimuth: np.ndarray) -> np.ndarray:
        """Height of the distant tree line (m) as a periodic function of azimuth about the tee (rad).

        A sum of a few harmonics, tabulated finely and interpolated (the renderer asks per pixel).
        """
        table = self._profile_table()
        n = len(table) - 1
        pos = np.mod(np.asarray(azimuth, dtype=np.float64), 2.0 * math.pi) * (n / (2.0 * math.pi))
        return np.interp(pos, np.arange(n + 1), table).astype(np.float32)

    def _profile_table(self) -> np.ndarray:
        cached = self.__dict__.get("_table")
        if cached is not None:
            return cached
        az = np.linspace(0.0, 2.0 * math.pi, 1 << 16)
        k = np.arange(1, len(self.treeline_phases) + 1)
        amp = 1.0 / k**0.8
        wave = sum(a * np.sin(kk * az + ph) for kk, a, ph in zip(k * 7, amp, self.treeline_phases)) / amp.sum()
        # Individual crowns: rounded bumps a few metres wide.
        for kk, a, ph in zip((181, 389, 797), (0.35, 0.2, 0.1), self.treeline_phases):
            wave = wave + a * (np.abs(np.sin(kk * az + 2.0 * ph)) ** 0.5 - 0.6)
        lo, hi = self.treeline_height
        table = lo + (hi - lo) * (0.5 + 0.5 * wave)
        object.__setattr__(self, "_table", table)
        return table


@dataclass(frozen=True, eq=False)
class Blob:
    """A ball-like distractor: a sphere, fixed or moving in a straight line (a bird)."""

    kind: str  # "tee-marker", "ball", "bird"
    position: np.ndarray  # (3,) at time t0
    radius: float
    colour: tuple[float, float, float]  # BGR 0..255 when fully lit
    velocity: np.ndarray = field(default_factory=lambda: np.zeros(3))
    t0: float = 0.0
    aspect: float = 1.0  # width / height of the drawn blob (birds are wider)

    def at(self, t: np.ndarray | float) -> np.ndarray:
        tt = np.atleast_1d(np.asarray(t, dtype=np.float64))
        return self.position + (tt - self.t0)[:, None] * self.velocity


@dataclass(frozen=True, eq=False)
class World:
    course: Course
    blobs: tuple[Blob, ...]
    occluder: Occluder | None
    sun: np.ndarray  # unit vector towards the sun
    cloud_height: float = 1500.0


def build_course(rng: np.random.Generator, traj: Trajectory) -> Course:
    az = math.radians(traj.launch.azimuth)
    axis = np.array([math.cos(az), math.sin(az)])
    tee = traj.launch.start(traj.ball)[:2]

    def local(p: np.ndarray) -> np.ndarray:
        d = p[:2] - tee
        return np.array([d @ axis, -d[0] * axis[1] + d[1] * axis[0]])

    land, rest = local(traj.landing_point), local(traj.rest_point)
    green = land + 0.6 * (rest - land) + np.array([0.0, rng.uniform(-3.0, 3.0)])
    spread = float(np.linalg.norm(rest - land))
    green_r = (0.5 * spread + 12.0, 14.0 + float(rng.uniform(0.0, 4.0)))
    side = 1.0 if rng.random() < 0.5 else -1.0
    bunker = green + np.array([rng.uniform(-8.0, 4.0), side * (green_r[1] + 6.0)])
    return Course(
        tee=tee.astype(np.float64), axis=axis, fairway_half_width=float(rng.uniform(14.0, 18.0)), fairway_bend=float(rng.uniform(-3.0, 3.0)),
        green_centre=green, green_radii=green_r, bunker_centre=bunker, bunker_radii=(7.0, 3.5),
        teebox=(-8.0, 6.0, 6.0), stripe_width=8.0, treeline_radius=max(350.0, float(np.linalg.norm(rest)) + 120.0),
        treeline_height=(10.0, 24.0), treeline_phases=rng.uniform(0.0, 2.0 * math.pi, 6),
    )


def build_blobs(rng: np.random.Generator, traj: Trajectory, course: Course, camera: np.ndarray,
                ball_at, launch_at: float) -> tuple[Blob, ...]:
    """Tee markers and a spare ball near the tee, balls near the green, and a bird in the sky."""
    axis = np.append(course.axis, 0.0)
    left = np.array([-course.axis[1], course.axis[0], 0.0])
    tee = np.append(course.tee, 0.0)
    white = (238.0, 240.0, 242.0)
    blobs = [
        Blob("tee-marker", tee + 1.2 * axis + 2.6 * left + [0, 0, 0.045], 0.045, white),
        Blob("tee-marker", tee + 1.2 * axis - 2.6 * left + [0, 0, 0.045], 0.045, white),
        Blob("ball", tee - 0.8 * axis + 1.3 * left + [0, 0, 0.0213], 0.0213, white),
    ]
    rest = traj.rest_point
    for _ in range(3):
        along = rng.uniform(-12.0, 10.0)
        across = rng.choice([-1.0, 1.0]) * rng.uniform(2.5, 9.0)
        p = rest + along * axis + across * left
        blobs.append(Blob("ball", np.array([p[0], p[1], 0.0213]), 0.0213, (228.0, 232.0, 235.0)))
    # A small pale bird crossing the view during the climb, beyond the ball.
    tb = launch_at + 0.55 * traj.apex_time
    b = ball_at(tb)
    d = b - camera
    rng_b = float(np.linalg.norm(d))
    d = d / rng_b
    side = np.cross(d, [0.0, 0.0, 1.0])
    side /= np.linalg.norm(side) or 1.0
    offset = math.radians(rng.uniform(1.0, 2.0)) * rng.choice([-1.0, 1.0])
    pos = camera + 1.6 * rng_b * (d + offset * side)
    speed = rng.uniform(8.0, 12.0)
    vel = -np.sign(offset) * speed * side + np.array([0.0, 0.0, rng.uniform(-0.5, 0.5)])
    blobs.append(Blob("bird", pos, 0.06, (205.0, 208.0, 210.0), vel, tb, aspect=2.2))
    return tuple(blobs)


def sun_direction() -> np.ndarray:
    d = np.array([-0.45, 0.35, 0.82])
    return d / np.linalg.norm(d)
