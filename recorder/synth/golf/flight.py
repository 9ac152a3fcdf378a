"""Golf-ball flight, bounce and roll: the physical truth of a synthetic tee shot.

World frame as everywhere in PTZ scenes: metres, Z up, ground plane Z = 0. Positions are the
ball's centre, so the ball touches the ground when Z = radius.

The physics is the shared model of :mod:`trackreplay.trackers.golf.ball_flight` (the ball's constants
:class:`BallModel`, equations (B1)-(B5)): in the air gravity, quadratic drag and Magnus lift with
``C_L = S / (1 + 2S)`` of a spin that decays exponentially (B1, B2), integrated here with classical
Runge–Kutta at a fine fixed step (1 ms); ground contacts are located inside a step by secant
refinement. At a contact the normal velocity reverses with restitution and a Coulomb friction
impulse, capped at the one that stops the contact point slipping, slows the ball and changes its
spin (B4). Once a hop would rise less than ``min_hop`` the ball rolls without slipping and
decelerates with rolling resistance ``μ_r g`` until it rests (B5). Time 0 is the moment of launch;
before it the ball sits at the launch position.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np

from trackreplay.trackers.golf.ball_flight import (
    AIR, BOUNCE, PHASES, REST, ROLL, TEE, BallModel, SpinLift, acceleration, hop_height, impact, no_slip, roll_distance,
)

__all__ = ["AIR", "BOUNCE", "PHASES", "REST", "ROLL", "TEE", "BallModel", "Flight", "Launch", "Trajectory", "simulate_shot"]


@dataclass(frozen=True)
class Launch:
    """How the ball leaves the club. Angles in degrees; azimuth 0 = +X, counter-clockwise."""

    speed: float = 50.0  # m/s
    elevation: float = 18.0
    azimuth: float = 0.0
    backspin_rpm: float = 6000.0
    sidespin_rpm: float = 0.0  # positive curves the ball to the left (a draw for a right-hander)
    position: tuple[float, float, float] | None = None  # ball centre; None = on the ground at the origin

    def start(self, ball: BallModel) -> np.ndarray:
        return np.array(self.position if self.position is not None else (0.0, 0.0, ball.radius), dtype=np.float64)

    def velocity(self) -> np.ndarray:
        el, az = math.radians(self.elevation), math.radians(self.azimuth)
        return self.speed * np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])

    def spin(self) -> np.ndarray:
        """Angular velocity (rad/s): backspin about the horizontal axis to the right of the line."""
        az = math.radians(self.azimuth)
        right = np.array([math.sin(az), -math.cos(az), 0.0])
        rpm = 2.0 * math.pi / 60.0
        return self.backspin_rpm * rpm * right + self.sidespin_rpm * rpm * np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True, eq=False)
class Flight:
    """A trajectory sampled at given times (seconds since launch)."""

    t: np.ndarray  # (N,)
    position: np.ndarray  # (N, 3) ball centre, m
    velocity: np.ndarray  # (N, 3) m/s
    phase: np.ndarray  # (N,) int8 codes into PHASES
    landing_time: float
    landing_point: np.ndarray

    def phase_names(self) -> list[str]:
        return [PHASES[int(p)] for p in self.phase]


@dataclass
class _AirSegment:
    t: np.ndarray
    p: np.ndarray
    v: np.ndarray
    phase: int


@dataclass(frozen=True, eq=False)
class _RollSegment:
    t0: float
    p0: np.ndarray
    direction: np.ndarray  # unit, horizontal
    speed0: float
    decel: float

    @property
    def t_rest(self) -> float:
        return self.t0 + (self.speed0 / self.decel if self.decel > 0 else math.inf)


@dataclass(frozen=True, eq=False)
class Trajectory:
    """The whole shot as continuous segments; ``sample`` evaluates it at any times."""

    ball: BallModel
    launch: Launch
    segments: tuple = field(repr=False)
    landing_time: float  # first ground contact, s after launch
    landing_point: np.ndarray
    landing_velocity: np.ndarray
    apex_time: float
    apex_point: np.ndarray
    bounce_times: tuple[float, ...]  # every ground contact that reversed the ball upwards
    bounce_apexes: tuple[float, ...]  # centre height above resting height of each hop, m
    roll_start: float
    rest_time: float
    rest_point: np.ndarray

    @property
    def carry(self) -> float:
        return float(np.linalg.norm(self.landing_point[:2] - self.launch.start(self.ball)[:2]))

    def sample(self, times: np.ndarray | list[float]) -> Flight:
        """Positions, velocities and phases at ``times`` (seconds since launch)."""
        t = np.atleast_1d(np.asarray(times, dtype=np.float64))
        pos = np.empty((len(t), 3))
        vel = np.zeros((len(t), 3))
        phase = np.empty(len(t), dtype=np.int8)
        start = self.launch.start(self.ball)
        pre = t < 0.0
        pos[pre] = start
        phase[pre] = TEE
        done = pre.copy()
        for seg in self.segments:
            if isinstance(seg, _AirSegment):
                sel = ~done & (t >= seg.t[0]) & (t <= seg.t[-1])
                if sel.any():
                    pos[sel], vel[sel] = _hermite(seg, t[sel])
                    phase[sel] = seg.phase
            else:
                sel = ~done & (t >= seg.t0)
                if sel.any():
                    dt = np.minimum(t[sel] - seg.t0, seg.t_rest - seg.t0)
                    dist = roll_distance(seg.speed0, seg.decel, dt)
                    pos[sel] = seg.p0 + dist[:, None] * seg.direction
                    speed = np.maximum(seg.speed0 - seg.decel * dt, 0.0)
                    vel[sel] = speed[:, None] * seg.direction
                    phase[sel] = np.where(t[sel] >= seg.t_rest, REST, ROLL)
            done |= sel
        if not done.all():  # only when the simulation was cut off before rest
            last = self.segments[-1]
            pos[~done] = last.p[-1] if isinstance(last, _AirSegment) else self.rest_point
            phase[~done] = REST
        return Flight(t, pos, vel, phase, self.landing_time, self.landing_point.copy())


def _hermite(seg: _AirSegment, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Cubic Hermite interpolation of position (and its derivative) between integration steps."""
    i = np.clip(np.searchsorted(seg.t, t, side="right") - 1, 0, len(seg.t) - 2)
    t0, t1 = seg.t[i], seg.t[i + 1]
    h = (t1 - t0)[:, None]
    s = ((t - t0) / (t1 - t0))[:, None]
    p0, p1, v0, v1 = seg.p[i], seg.p[i + 1], seg.v[i] * h, seg.v[i + 1] * h
    s2, s3 = s * s, s * s * s
    pos = (2 * s3 - 3 * s2 + 1) * p0 + (s3 - 2 * s2 + s) * v0 + (-2 * s3 + 3 * s2) * p1 + (s3 - s2) * v1
    dpos = (6 * s2 - 6 * s) * p0 + (3 * s2 - 4 * s + 1) * v0 + (-6 * s2 + 6 * s) * p1 + (3 * s2 - 2 * s) * v1
    return pos, dpos / h


@functools.lru_cache(maxsize=16)
def _air_terms(ball: BallModel) -> tuple[float, SpinLift | None]:
    """(B1)'s drag factor ``k C_d`` and (B2)'s lift of ``ball`` (None: no lift)."""
    k = ball.k
    return k * ball.drag_cd, SpinLift(k, ball.radius) if ball.lift else None


def _rk4(ball: BallModel, p: np.ndarray, v: np.ndarray, w0: np.ndarray, t: float, h: float) -> tuple[np.ndarray, np.ndarray]:
    """One classical Runge–Kutta step of (B1)+(B2) (:mod:`trackreplay.trackers.golf.ball_flight`) from time
    ``t`` (since the spin was ``w0``); the spin decays exactly. Hand-written rather than scipy's
    ``solve_ivp``: a fixed 1 ms step with a secant-refined contact inside it is the synthetic truth
    every golden log was rendered from (an adaptive scipy step would move it)."""
    def spin(tt: float) -> tuple[float, float, float]:
        f = math.exp(-tt / ball.spin_decay_s)
        return w0[0] * f, w0[1] * f, w0[2] * f

    drag, lift = _air_terms(ball)
    g = ball.gravity
    px, py, pz = float(p[0]), float(p[1]), float(p[2])
    v1 = (float(v[0]), float(v[1]), float(v[2]))
    wm = spin(t + 0.5 * h)
    a1 = acceleration(v1, drag, g, spin(t), lift)
    v2 = tuple(v1[i] + 0.5 * h * a1[i] for i in range(3))
    a2 = acceleration(v2, drag, g, wm, lift)
    v3 = tuple(v1[i] + 0.5 * h * a2[i] for i in range(3))
    a3 = acceleration(v3, drag, g, wm, lift)
    v4 = tuple(v1[i] + h * a3[i] for i in range(3))
    a4 = acceleration(v4, drag, g, spin(t + h), lift)
    p_new = np.array([q + h / 6.0 * (v1[i] + 2 * v2[i] + 2 * v3[i] + v4[i]) for i, q in enumerate((px, py, pz))])
    v_new = np.array([v1[i] + h / 6.0 * (a1[i] + 2 * a2[i] + 2 * a3[i] + a4[i]) for i in range(3)])
    return p_new, v_new


def _fly(ball: BallModel, p: np.ndarray, v: np.ndarray, w0: np.ndarray, t0: float, spin_t0: float, dt: float,
         t_max: float, phase: int) -> tuple[_AirSegment, bool]:
    """Integrate until the centre comes down to Z = radius (True) or ``t_max`` (False).

    ``w0`` is the spin at ``spin_t0``; the spin at t is ``w0 exp(-(t - spin_t0)/decay)``.
    """
    r = ball.radius
    ts, ps, vs = [t0], [p.copy()], [v.copy()]
    t = t0
    while t < t_max:
        p1, v1 = _rk4(ball, p, v, w0, t - spin_t0, dt)
        if p1[2] <= r and v1[2] < 0.0:
            # Secant refinement of the contact time inside this step.
            lo, hi, zlo, zhi = 0.0, dt, p[2] - r, p1[2] - r
            h = dt
            for _ in range(40):
                h = lo + (hi - lo) * zlo / (zlo - zhi) if zlo != zhi else 0.5 * (lo + hi)
                ph, _ = _rk4(ball, p, v, w0, t - spin_t0, h)
                z = ph[2] - r
                if abs(z) < 1e-10 or hi - lo < 1e-12:
                    break
                if z > 0:
                    lo, zlo = h, z
                else:
                    hi, zhi = h, z
            ph, vh = _rk4(ball, p, v, w0, t - spin_t0, h)
            ph[2] = r
            if h > 1e-12:
                ts.append(t + h)
                ps.append(ph)
                vs.append(vh)
            else:
                vs[-1] = vh
            return _AirSegment(np.array(ts), np.array(ps), np.array(vs), phase), True
        t += dt
        p, v = p1, v1
        ts.append(t)
        ps.append(p.copy())
        vs.append(v.copy())
    return _AirSegment(np.array(ts), np.array(ps), np.array(vs), phase), False


def simulate_shot(launch: Launch, ball: BallModel = BallModel(), *, bounce: bool = True, dt: float = 1e-3,
                  t_max: float = 60.0) -> Trajectory:
    """Integrate a shot from launch until the ball rests (or ``t_max`` seconds).

    ``bounce=False``: the first contact has no restitution (the ball checks into the turf and
    rolls out).
    """
    r = ball.radius
    p = launch.start(ball)
    v = launch.velocity()
    w = launch.spin()
    segments: list = []
    bounce_times: list[float] = []
    hops: list[float] = []
    t = 0.0
    spin_t0 = 0.0
    phase = AIR
    landing_time = math.nan
    landing_point = p.copy()
    landing_velocity = v.copy()
    if p[2] <= r and v[2] <= 0.0:  # a ball launched along or into the ground: straight to rolling
        landing_time, p[2] = 0.0, r
        contacted = True
    else:
        seg, contacted = _fly(ball, p, v, w, t, spin_t0, dt, t_max, phase)
        segments.append(seg)
        t, p, v = float(seg.t[-1]), seg.p[-1].copy(), seg.v[-1].copy()
        landing_time, landing_point, landing_velocity = t, p.copy(), v.copy()
    w = w * math.exp(-(t - spin_t0) / ball.spin_decay_s)
    spin_t0 = t
    first = True
    while contacted:
        e = ball.restitution if (bounce or not first) else 0.0
        v, w = impact(ball, v, w, e)
        first = False
        hop = hop_height(v[2], ball.gravity)
        if v[2] <= 0.0 or hop < ball.min_hop or t >= t_max:
            break
        bounce_times.append(t)
        seg, contacted = _fly(ball, p, v, w, t, spin_t0, dt, t_max, BOUNCE)
        segments.append(seg)
        hops.append(float(seg.p[:, 2].max() - r))
        w = w * math.exp(-(float(seg.t[-1]) - spin_t0) / ball.spin_decay_s)
        t, p, v = float(seg.t[-1]), seg.p[-1].copy(), seg.v[-1].copy()
        spin_t0 = t
    roll_start = t
    if contacted:
        # Roll without slipping from here: the friction impulse that stops the slip.
        vh = np.array([v[0], v[1]])
        slip = vh + np.array([-r * w[1], r * w[0]])
        vh = no_slip(vh, slip)
        speed = float(np.hypot(*vh))
        direction = np.array([vh[0] / speed, vh[1] / speed, 0.0]) if speed > 1e-9 else np.array([1.0, 0.0, 0.0])
        p0 = np.array([p[0], p[1], r])
        roll = _RollSegment(t, p0, direction, speed, ball.rolling_resistance * ball.gravity)
        segments.append(roll)
        rest_time = roll.t_rest
        rest_point = p0 + direction * (speed * (rest_time - t) - 0.5 * roll.decel * (rest_time - t) ** 2)
    else:
        rest_time, rest_point = t, p.copy()
    first_seg = segments[0] if segments and isinstance(segments[0], _AirSegment) else None
    if first_seg is not None:
        k = int(np.argmax(first_seg.p[:, 2]))
        apex_time, apex_point = float(first_seg.t[k]), first_seg.p[k].copy()
    else:
        apex_time, apex_point = 0.0, launch.start(ball)
    return Trajectory(
        ball, launch, tuple(segments), landing_time, landing_point, landing_velocity, apex_time, apex_point,
        tuple(bounce_times), tuple(hops), roll_start, float(rest_time), np.asarray(rest_point, dtype=np.float64),
    )
