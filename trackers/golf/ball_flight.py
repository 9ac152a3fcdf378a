"""The golf ball's flight: one physical model for the synthesiser, the offline flight fit and the landing EKF.

The paper (seed 000, §2.3; see docs/papers.md) predicts the ball "in 3-D real space" with an extended
Kalman filter and takes "the moment the ball meets the plane assumed to be the ground" as the landing;
it prints no equations of motion. These are ours (a golf ball's usual aerodynamics), numbered here
and cited by every user. World frame: metres, Z up, the ground is ``Z = 0``; positions are the ball's
centre, so it touches the ground at ``Z = r`` (§2.3's ground plane).

- **(B1)** in the air, per unit mass: ``a = −g ẑ − k C_d |v| v + k C_L |v|² (ŵ × v̂)``, ``k = ρ A / 2m``
  (gravity, quadratic drag, Magnus lift), :func:`acceleration`;
- **(B2)** the spinning ball's lift: ``C_L = S / (1 + 2S)``, spin factor ``S = r|ω| / |v|``; the spin
  decays as ``ω(t) = ω₀ exp(−t/τ)`` (:func:`spin_lift_coefficient`, :class:`SpinLift`);
- **(B3)** the fit's lift law (spin unknown): ``C_L = C_L0 + C_L1 (v₀/|v| − 1)``, growing as the ball
  slows as (B2) does (:class:`FittedLift`);
- **(B4)** an impact: the normal speed reverses with restitution ``e``; a Coulomb friction impulse along
  the contact point's slip ``v_h + ω × (−r ẑ)``, ``j_t = min(μ (1 + e)|v_z|, (2/7)|slip|)`` (the cap
  stops the slip: a solid sphere, ``I = (2/5) m r²``), turns the spin by ``r j_t (ẑ × û) / (2/5 r²)``
  (:func:`friction_impulse`, :func:`impact`);
- **(B5)** a hop that would rise less than ``min_hop`` (``v_z² / 2g``, :func:`hop_height`) becomes a roll:
  rolling without slipping (``v ← v − (2/7) slip``, :func:`no_slip`), then ``s(t) = s₀ t − ½ a_r t²`` with
  ``a_r = μ_r g`` until it rests at ``t = s₀ / a_r`` (:func:`roll_distance`).

The users keep their own integrators, each for its reason (scipy has no fixed-step RK4, and an
adaptive ``solve_ivp`` would move every result):

- the synthesiser (the truth, ``recorder.synth.golf.flight``) integrates (B1)+(B2) through
  :func:`acceleration` with classical Runge–Kutta at 1 ms, refines each ground contact, and applies
  :func:`impact` and (B5);
- the fit (``replay.analysis.flight``) integrates (B1)+(B3) in the air and (B1)+(B2) in the hops with
  RK4 at 1/60 s written out inline (its whole cost: a call per evaluation made it ~2x slower), checked
  against :func:`acceleration` with :class:`FittedLift` by its tests; (B4) and (B5) in its own
  parameters (surface spin speed ``b = rω``) through :func:`friction_impulse`, :func:`no_slip`,
  :func:`hop_height` and :func:`roll_distance`;
- the landing EKF (``trackers.golf.landing``) steps (B1) without lift (lift and wind are its process
  noise) through :func:`acceleration` with Heun's method, its ``F`` from :func:`drag_jacobian`; its bounce
  is a coarse (B4): vertical speed times ``−e``, horizontal speed times a retention.

The functions work on plain floats (the integrators call them 2-4x per step, where numpy's per-call
overhead would dominate), in the order of operations each user's results were produced with: moving
the physics here changed no result by a bit. Where the fit's order differs (its rounding of ``k``,
its inline stages, ``k S / (1 + 2S)`` in the hops) it keeps its own.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TypeVar

import numpy as np

GRAVITY = 9.81  # m/s²
PHASES = ("tee", "air", "bounce", "roll", "rest")
"""Phase codes of a flight: index into this tuple."""
TEE, AIR, BOUNCE, ROLL, REST = range(5)
NO_SLIP = 2.0 / 7.0  # (B4, B5): the share of a solid sphere's contact slip that one impulse removes to stop it

Vec3 = tuple[float, float, float]
Scalar = TypeVar("Scalar", float, np.ndarray)  # a float, or numpy's elementwise the same arithmetic


@dataclass(frozen=True)
class BallModel:
    """A regulation golf ball and its surroundings (SI units): the constants of (B1)-(B5)."""

    mass: float = 0.04593  # kg (rules: at most 45.93 g)
    diameter: float = 0.04267  # m (rules: at least 42.67 mm)
    drag_cd: float = 0.25
    lift: bool = True  # Magnus lift from backspin/sidespin (B1, B2)
    spin_decay_s: float = 25.0  # e-folding time τ of the spin (B2)
    air_density: float = 1.2  # kg/m^3
    gravity: float = GRAVITY  # m/s^2
    restitution: float = 0.4  # normal coefficient of restitution at a bounce (B4)
    friction: float = 0.4  # Coulomb friction coefficient at a bounce (B4)
    rolling_resistance: float = 0.2  # rolling deceleration = this * g (B5)
    min_hop: float = 0.01  # m: a bounce rising less than this becomes a roll (B5)

    @property
    def radius(self) -> float:
        return self.diameter / 2.0

    @property
    def area(self) -> float:
        return math.pi * self.radius**2

    @property
    def k(self) -> float:
        """``ρ A / 2m`` (1/m) of (B1): drag acceleration ``k C_d |v|²``."""
        return 0.5 * self.air_density * self.area / self.mass


def spin_lift_coefficient(s: float) -> float:
    """(B2) ``C_L = S / (1 + 2S)`` of spin factor ``S = r|ω| / |v|``."""
    return s / (1.0 + 2.0 * s)


@dataclass(frozen=True)
class SpinLift:
    """(B1) with (B2): the Magnus term's factor ``c`` in ``c (ω × v)`` for a ball spinning at ``|ω|``:
    ``k C_L |v|² (ω̂ × v̂) = k C_L |v| (ω × v) / |ω|``."""

    k: float  # ρ A / 2m
    radius: float

    def __call__(self, speed: float, spin: float) -> float:
        return self.k * spin_lift_coefficient(self.radius * spin / speed) * speed / spin


@dataclass(frozen=True)
class FittedLift:
    """(B1) with (B3): ``k C_L |v|`` per unit spin axis, ``C_L = C_L0 + C_L1 (v₀/|v| − 1)`` (``k_cl0 = k C_L0``,
    ``k_cl1 = k C_L1``); ``spin`` is the axis' length (1 for a unit axis)."""

    k_cl0: float
    k_cl1: float
    v0: float  # launch speed, m/s

    def __call__(self, speed: float, spin: float) -> float:
        return (self.k_cl0 + self.k_cl1 * (self.v0 / max(speed, 1e-6) - 1.0)) * speed / spin


def acceleration(v: Vec3, drag: float, gravity: float, w: Vec3 = (0.0, 0.0, 0.0),
                 lift: Callable[[float, float], float] | None = None) -> Vec3:
    """(B1): gravity, quadratic drag ``−drag |v| v`` (``drag = k C_d``) and, with ``lift``, the Magnus
    term ``lift(|v|, |ω|) (ω × v)`` of spin ``w`` (rad/s, or a spin axis), per unit mass."""
    vx, vy, vz = v
    speed = math.sqrt(vx * vx + vy * vy + vz * vz)
    d = drag * speed
    ax, ay, az = -d * vx, -d * vy, -d * vz - gravity
    if lift is None or speed < 1e-9:
        return ax, ay, az
    wx, wy, wz = w
    spin = math.sqrt(wx * wx + wy * wy + wz * wz)
    if spin > 1e-9:
        c = lift(speed, spin)
        ax += c * (wy * vz - wz * vy)
        ay += c * (wz * vx - wx * vz)
        az += c * (wx * vy - wy * vx)
    return ax, ay, az


EYE3 = np.eye(3)
EYE3.flags.writeable = False


def drag_jacobian(v: np.ndarray, drag: float) -> np.ndarray:
    """``∂a/∂v`` of (B1)'s drag: ``d(−k |v| v)/dv = −k (|v| I + v vᵀ / |v|)`` (3 x 3)."""
    speed = math.sqrt(float(v @ v))
    if speed < 1e-9 or drag == 0.0:
        return np.zeros((3, 3))
    return -drag * (speed * EYE3 + v[:, None] * v[None, :] / speed)


def hop_height(vz: float, gravity: float) -> float:
    """(B5): how high a ball leaving the ground at vertical speed ``vz`` rises, ``v_z² / 2g``."""
    return vz * vz / (2.0 * gravity)


def friction_impulse(coulomb: float, slip: float) -> float:
    """(B4): the friction impulse per unit mass, the Coulomb limit ``μ (1 + e)|v_z|`` (``coulomb``) capped
    at the impulse that stops a contact point slipping at speed ``slip`` (a solid sphere: 2/7 of it)."""
    return min(coulomb, NO_SLIP * slip)


def no_slip(v: Scalar, slip: Scalar) -> Scalar:
    """(B5): the velocity (float or array) once friction has stopped the contact point slipping."""
    return v - NO_SLIP * slip


def roll_distance(speed0: float, decel: float, dt: Scalar) -> Scalar:
    """(B5): distance rolled ``s₀ t − ½ a_r t²`` after ``dt`` s (floats or arrays; ``dt`` up to the rest)."""
    return speed0 * dt - 0.5 * decel * dt * dt


def impact(ball: BallModel, v: np.ndarray, w: np.ndarray, restitution: float) -> tuple[np.ndarray, np.ndarray]:
    """(B4): velocity and spin (rad/s) after a ground impact with restitution ``restitution``."""
    r = ball.radius
    vz = v[2]
    jn = (1.0 + restitution) * abs(vz)  # normal impulse per unit mass
    # Horizontal velocity of the contact point: v + w x (-r e_z) = v + (-r w_y, r w_x).
    slip = v[:2] + np.array([-r * w[1], r * w[0]])
    s = float(np.hypot(*slip))
    v_new = np.array([v[0], v[1], -restitution * vz])
    w_new = w.copy()
    if s > 1e-12:
        jt = friction_impulse(ball.friction * jn, s)
        u = slip / s
        v_new[:2] -= jt * u
        # Torque of the friction impulse about the centre: (-r e_z) x (-jt u) m = r jt (e_z x u) m.
        inertia = 0.4 * r * r  # per unit mass
        w_new += r * jt * np.array([-u[1], u[0], 0.0]) / inertia
    return v_new, w_new
