"""The golf ball's 3-D flight from one PTZ camera, fitted offline over the whole shot (issue 13).

The golf tracker records, per measured frame, the line of sight from the camera to the ball
(``dx, dy, dz``: PTZ encoders + lens table) and the ball's apparent size (``w, h``, px). One
camera gives directions, not distances; but a ball in flight obeys known physics, so the whole
set of directions pins the flight down. :func:`fit_flight` finds, by nonlinear least squares
(``scipy.optimize.least_squares``), the shot that best explains every line of sight:

- **flight**: launch time ``t0`` and point ``p0`` (on the ground), launch velocity (speed, elevation,
  azimuth), drag coefficient ``C_d`` and lift coefficient ``C_L = C_L0 + C_L1 (v0/|v| − 1)`` (lift
  grows as the ball slows: the spin parameter ``rω/|v|``) with the spin axis' tilt (sidespin),
  gravity ``g`` fixed at 9.81 m/s²: ``a = −g ẑ − k C_d |v| v + k C_L |v| (ŵ × v)``,
  ``k = ρ A / 2m`` for a regulation ball: equations (B1) and (B3) of the shared ball model
  (:mod:`trackreplay.trackers.golf.ball_flight`, whose constants and phases it uses); before ``t0`` the
  ball rests at ``p0``;
- **bounce and roll**: at each ground contact (centre at ``Z = D/2``) the vertical speed reverses
  with restitution ``e``; a Coulomb friction impulse (``μ`` times the normal one, at most what stops
  the contact point slipping: a solid sphere) slows the horizontal speed and turns the backspin
  (surface speed ``b = rω`` at the first impact, a fitted parameter) towards topspin (B4); hops with
  drag and the Magnus lift of that spin (B1, B2); when a hop would rise less than 1 cm the ball rolls
  without slipping along its last direction, decelerating at ``a_roll`` until it rests (B5). One
  horizontal retention for every impact (the earlier model) cannot be right: the first impact
  stops the slip and costs the ball about half its horizontal speed, the later ones almost
  nothing; its misfit of the hops and roll moved a 149 m landing by 4.7 % of carry.

The ground is known (``Z = 0``), so once the ball rolls its line of sight alone places it (the
ray meets the ground; the camera's zoom makes that precise to decimetres at 180 m), and the
landing point is continuous with the hops and the roll that follow it: fitting the whole shot
jointly lets the frames after the landing pin the landing, where the lines of sight of the
flight, seen from behind the tee, leave the range weak. The residuals stay angles (no explicit
ground intersection): a rolling ball's modelled Z is the ball's radius, so the angle already says
how far along the ground it is, with the right weight for a ray that grazes the ground.

Residuals: per measured frame, the angle between the measured and the modelled line of sight in
pixels of that frame (``fx · angle / σ_px``), and the log ratio of the measured apparent size
to the modelled one (``f D / r``) over ``σ_size`` — the size gives the range where the lines of
sight alone leave it weak (a camera behind the tee looks along the flight). A soft-L1 loss keeps a
wrong blob from pulling the fit. Launch point and time come from the frames before the ball moves
(its line of sight meets the ground there); the launch is held within one frame after the last
frame that measured the ball on the tee (the tracker loses the ball at the launch, and may find
it again only 1-2 s later: left free, launch time, speed and lift trade off along that gap — on
the default tee shot the fit launched 0.6 s late at 52 m/s instead of 46). The launch velocity
starts from a few guesses and the best is refined with every parameter free. Only ``measured``
rows are observations (``predicted`` and ``lost`` rows are the tracker's own guesses).

The report gives launch speed and angles, apex, carry, landing point (world metres), time of
flight, the bounce/roll parameters and rest point, each with a 1-σ uncertainty from the fit's
covariance (``(JᵀJ)⁻¹ s²``, propagated by finite differences) or a delete-a-block jackknife over
time (refits without each of ``K`` blocks of frames) for the reported quantities: the jackknife
carries model error, which the covariance does not); :func:`flight_rows` exports the
fitted 3-D trajectory at frame times as ``X, Y, Z`` rows of the trajectory table.

Without PTZ encoders and a lens table there are no lines of sight: :class:`FlightUnavailable`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from functools import lru_cache

import numpy as np
import polars as pl
from scipy.optimize import least_squares

from trackreplay.replay.core.trajectory import COLUMNS, SCHEMA
from trackreplay.schemas.errors import TrackreplayError
from trackreplay.trackers.geometry.ptz import PtzCamera
from trackreplay.trackers.golf.ball_flight import (
    AIR, BOUNCE, GRAVITY, PHASES, REST, ROLL, TEE, BallModel, friction_impulse, hop_height, no_slip, roll_distance,
)

G = GRAVITY
MIN_HOP_M = BallModel().min_hop


class FlightUnavailable(TrackreplayError):
    """The trajectory or log has no lines of sight (no PTZ encoders / lens table): no 3-D."""


def air_k(ball: BallModel) -> float:
    """(B1)'s ``k = ρ A / 2m`` (1/m) of ``ball``: drag acceleration ``k C_d |v|²``. The fit's own rounding
    (1 ulp above :attr:`BallModel.k` for the regulation ball), kept so that its results stay bit for bit."""
    return ball.air_density * math.pi * (ball.diameter / 2) ** 2 / (2.0 * ball.mass)


@dataclass(frozen=True)
class FlightConfig:
    ball: BallModel = BallModel()  # mass, diameter and air density (the fit's C_d, C_L and bounce are fitted)
    sigma_px: float = 1.0  # line-of-sight noise, px of the frame
    sigma_size: float = 0.35  # apparent size, relative (log)
    use_size: bool = True
    step_s: float = 1.0 / 60.0  # integration step (RK4; 1/120 s changes a 149 m landing by < 1 mm at 4x the cost)
    max_time_s: float = 30.0
    loss: str = "soft_l1"
    f_scale: float = 3.0  # residuals beyond ~3 σ count linearly
    jackknife_blocks: int = 10  # delete-a-block jackknife for the 1-σ (0: the fit's covariance only)
    jackknife_nfev: int = 100  # function evaluations per jackknife refit (warm-started at the fit)
    hop_lift: bool = True  # Magnus lift from the spin left after an impact, in the hops
    spin_decay_s: float = BallModel().spin_decay_s  # (B2) e-folding time of the spin in the hops (0: none)
    confidence_weight: bool = False  # weight each frame's residuals by the tracker's confidence


# Parameter vector: names, in order.
NAMES = ("t0", "X0", "Y0", "Z0", "speed", "elevation", "azimuth", "cd", "cl", "cl_slope", "spin_tilt",
         "restitution", "friction", "landing_spin", "roll_decel")


@dataclass(frozen=True)
class Value:
    value: float
    std: float

    def __format__(self, spec: str) -> str:
        return f"{format(self.value, spec)} ± {format(self.std, spec)}"


@dataclass(frozen=True)
class FlightReport:
    """One shot, world metres (Z up), seconds on the log clock; every value with its 1-σ."""

    launch_time: Value
    launch_point: tuple[Value, Value, Value]
    launch_speed: Value  # m/s
    launch_elevation: Value  # degrees above horizontal
    launch_azimuth: Value  # degrees, counter-clockwise from +X
    drag_cd: Value
    lift_cl: Value  # at launch
    lift_cl_slope: Value  # C_L = C_L0 + slope (v0/|v| − 1): lift grows as the ball slows (spin parameter ∝ 1/|v|)
    spin_tilt: Value  # degrees: 0 = pure backspin
    apex_height: Value  # m, ball centre above the ground
    apex_time: Value
    carry: Value  # horizontal distance launch -> first ground contact, m
    landing_point: tuple[Value, Value, Value]
    landing_time: Value
    time_of_flight: Value
    restitution: Value
    friction: Value  # Coulomb coefficient at an impact
    landing_spin: Value  # backspin surface speed r·ω at the first impact, m/s
    roll_decel: Value  # m/s²
    rest_point: tuple[Value, Value, Value]
    rest_time: Value
    frames_used: int
    rms_px: float  # line-of-sight residual, px (frames not down-weighted by the robust loss)
    size_rms: float  # apparent-size residual, log ratio
    notes: tuple[str, ...] = field(default_factory=tuple)

    def as_dict(self) -> dict:
        return asdict(self)

    def describe(self) -> str:
        def p3(v: tuple[Value, Value, Value]) -> str:
            return "(" + ", ".join(f"{c.value:.2f}" for c in v) + ") ± (" + ", ".join(f"{c.std:.2f}" for c in v) + ") m"

        lines = [
            f"launch       t {self.launch_time:.3f} s at {p3(self.launch_point)}",
            f"             speed {self.launch_speed:.1f} m/s, elevation {self.launch_elevation:.2f}°, azimuth {self.launch_azimuth:.2f}°",
            f"air          C_d {self.drag_cd:.3f}, C_L {self.lift_cl:.3f} + {self.lift_cl_slope:.3f} (v0/|v| - 1), spin tilt {self.spin_tilt:.1f}°",
            f"apex         {self.apex_height:.2f} m at {self.apex_time:.2f} s",
            f"landing      {p3(self.landing_point)} at {self.landing_time:.3f} s",
            f"carry        {self.carry:.2f} m, time of flight {self.time_of_flight:.3f} s",
            f"bounce/roll  restitution {self.restitution:.2f}, friction {self.friction:.2f}, landing backspin r·ω {self.landing_spin:.1f} m/s, "
            f"roll deceleration {self.roll_decel:.2f} m/s²",
            f"rest         {p3(self.rest_point)} at {self.rest_time:.2f} s",
            f"fit          {self.frames_used} frames, line-of-sight RMS {self.rms_px:.2f} px, size RMS {self.size_rms:.2f} (log)",
        ]
        return "\n".join(lines + [f"note         {n}" for n in self.notes])


# --- the model ---------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class Shot:
    """A simulated shot: positions on a fine time grid (s on the log clock), phases, events."""

    t: np.ndarray
    p: np.ndarray  # (N, 3)
    v: np.ndarray  # (N, 3)
    phase: np.ndarray  # (N,) int codes into PHASES
    landing_time: float
    landing_point: np.ndarray
    apex_time: float
    apex_point: np.ndarray
    rest_time: float
    rest_point: np.ndarray

    def at(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Positions (cubic Hermite between grid points) and phase codes at ``times``."""
        times = np.asarray(times, dtype=np.float64)
        t, p, v = self.t, self.p, self.v
        i = np.clip(np.searchsorted(t, times, side="right") - 1, 0, len(t) - 2)
        h = (t[i + 1] - t[i])[:, None]
        s = np.clip((times - t[i]) / np.where(h[:, 0] > 0, h[:, 0], 1.0), 0.0, 1.0)[:, None]
        s2, s3 = s * s, s * s * s
        pos = ((2 * s3 - 3 * s2 + 1) * p[i] + (s3 - 2 * s2 + s) * h * v[i] + (-2 * s3 + 3 * s2) * p[i + 1]
               + (s3 - s2) * h * v[i + 1])
        before, after = times <= t[0], times >= t[-1]  # t[0] is the launch: the ball waits at p[0] before it
        pos[before], pos[after] = p[0], p[-1]
        phase = self.phase[np.clip(np.searchsorted(t, times, side="left"), 0, len(t) - 1)]
        phase = np.where(before, TEE, np.where(after, REST, phase))
        return pos, phase


def _fly(p, v, t, h, kd, kl, w, contact_z, t_end, phase, out):
    """RK4 until the centre comes down to ``contact_z`` (returns the contact state) or ``t_end``.

    The acceleration is (B1) with (B3)'s lift (``kl = (k C_L0, k C_L1, v0)``, ``C_L = C_L0 + C_L1 (v0/|v| − 1)``:
    ``a = −g ẑ − kd |v| v + k C_L |v| (ŵ × v)``), the shared model's
    :func:`~trackreplay.trackers.golf.ball_flight.acceleration` with
    :class:`~trackreplay.trackers.golf.ball_flight.FittedLift`, written out once per RK4 stage, four
    times: this loop is the fit's whole cost, and a call per evaluation, even to a local closure,
    made it ~15 % slower (a module-level function, ~2x); scipy's ``solve_ivp`` (adaptive steps,
    a Python call per evaluation) would be slower still and move every fitted number.
    ``tests/replay/analysis/test_flight_ground.py`` checks the four copies against the shared one."""
    sqrt = math.sqrt
    px, py, pz = p
    vx, vy, vz = v
    l0, l1, v0 = kl
    wx, wy, wz = w
    h2, h6 = 0.5 * h, h / 6.0
    out.append((t, px, py, pz, vx, vy, vz, phase))
    while t < t_end:
        s = sqrt(vx * vx + vy * vy + vz * vz)
        L = (l0 + l1 * (v0 / (s if s > 1e-6 else 1e-6) - 1.0)) * s
        ds = kd * s
        ax1 = L * (wy * vz - wz * vy) - ds * vx
        ay1 = L * (wz * vx - wx * vz) - ds * vy
        az1 = L * (wx * vy - wy * vx) - ds * vz - G
        bx, by, bz = vx + h2 * ax1, vy + h2 * ay1, vz + h2 * az1
        s = sqrt(bx * bx + by * by + bz * bz)
        L = (l0 + l1 * (v0 / (s if s > 1e-6 else 1e-6) - 1.0)) * s
        ds = kd * s
        ax2 = L * (wy * bz - wz * by) - ds * bx
        ay2 = L * (wz * bx - wx * bz) - ds * by
        az2 = L * (wx * by - wy * bx) - ds * bz - G
        cx, cy, cz = vx + h2 * ax2, vy + h2 * ay2, vz + h2 * az2
        s = sqrt(cx * cx + cy * cy + cz * cz)
        L = (l0 + l1 * (v0 / (s if s > 1e-6 else 1e-6) - 1.0)) * s
        ds = kd * s
        ax3 = L * (wy * cz - wz * cy) - ds * cx
        ay3 = L * (wz * cx - wx * cz) - ds * cy
        az3 = L * (wx * cy - wy * cx) - ds * cz - G
        dx, dy, dz = vx + h * ax3, vy + h * ay3, vz + h * az3
        s = sqrt(dx * dx + dy * dy + dz * dz)
        L = (l0 + l1 * (v0 / (s if s > 1e-6 else 1e-6) - 1.0)) * s
        ds = kd * s
        ax4 = L * (wy * dz - wz * dy) - ds * dx
        ay4 = L * (wz * dx - wx * dz) - ds * dy
        az4 = L * (wx * dy - wy * dx) - ds * dz - G
        nx = px + h6 * (vx + 2 * bx + 2 * cx + dx)
        ny = py + h6 * (vy + 2 * by + 2 * cy + dy)
        nz = pz + h6 * (vz + 2 * bz + 2 * cz + dz)
        nvx = vx + h6 * (ax1 + 2 * ax2 + 2 * ax3 + ax4)
        nvy = vy + h6 * (ay1 + 2 * ay2 + 2 * ay3 + ay4)
        nvz = vz + h6 * (az1 + 2 * az2 + 2 * az3 + az4)
        if nz <= contact_z and nvz < 0:
            return _contact((px, py, pz, vx, vy, vz), (nx, ny, nz, nvx, nvy, nvz), t, h, contact_z, phase, out)
        t += h
        px, py, pz, vx, vy, vz = nx, ny, nz, nvx, nvy, nvz
        out.append((t, px, py, pz, vx, vy, vz, phase))
    return (px, py, pz), (vx, vy, vz), t, False


def _contact(before: tuple, after: tuple, t: float, h: float, contact_z: float, phase: int, out: list[tuple]):
    """:func:`_fly`'s ground contact inside the step from state ``before`` (at ``t``) to ``after``: linear in
    the step; its row appended to ``out``; :func:`_fly`'s return."""
    px, py, pz, vx, vy, vz = before
    nx, ny, nz, nvx, nvy, nvz = after
    f = (pz - contact_z) / (pz - nz) if pz != nz else 1.0
    t += f * h
    qx, qy = px + f * (nx - px), py + f * (ny - py)
    qv = (vx + f * (nvx - vx), vy + f * (nvy - vy), vz + f * (nvz - vz))
    out.append((t, qx, qy, contact_z, *qv, phase))
    return (qx, qy, contact_z), qv, t, True


@lru_cache(maxsize=512)
def _flight(Z0: float, speed: float, el: float, az: float, cd: float, cl: float, cl1: float, tilt: float,
            k: float, contact: float, h: float, max_time: float) -> tuple[np.ndarray, bool]:
    """The flight from launch time 0 at (0, 0, Z0) to the first contact (or ``max_time``): rows
    ``t, X, Y, Z, vX, vY, vZ, phase`` (read-only). Launch time and point only shift it, so the
    finite-difference Jacobian's columns for them — and for the bounce and roll parameters — reuse
    the one flight (7 of the 15 simulations of each Jacobian integrate no flight)."""
    el_r, az_r, tilt_r = math.radians(el), math.radians(az), math.radians(tilt)
    v0 = (speed * math.cos(el_r) * math.cos(az_r), speed * math.cos(el_r) * math.sin(az_r), speed * math.sin(el_r))
    right = (math.sin(az_r), -math.cos(az_r), 0.0)
    w = (math.cos(tilt_r) * right[0], math.cos(tilt_r) * right[1], math.sin(tilt_r))  # unit spin axis
    out: list[tuple] = []
    _, _, _, hit = _fly((0.0, 0.0, Z0), v0, 0.0, h, k * cd, (k * cl, k * cl1, speed), w, contact, max_time, AIR, out)
    air = np.array(out)
    air.flags.writeable = False
    return air, hit


def simulate(theta: np.ndarray, cfg: FlightConfig, t_end: float) -> Shot:
    """The shot of parameter vector ``theta`` (see ``NAMES``) up to log time ``t_end``: the flight to the
    first contact (:func:`_air`), then impacts, hops and the roll to rest (:func:`_bounces`)."""
    air, hit = _air(theta, cfg, t_end)
    t = float(air[-1, 0])
    p, v = tuple(air[-1, 1:4]), tuple(air[-1, 4:7])
    out: list[tuple] = []
    apex_i = int(np.argmax(air[:, 3]))
    apex_time, apex_point = float(air[apex_i, 0]), air[apex_i, 1:4].copy()
    landing_time, landing_point = (t, np.array(p)) if hit else (math.nan, np.full(3, np.nan))
    rest_time, rest_point = _bounces(theta, cfg, t_end, t, p, v, out) if hit else (math.nan, np.full(3, np.nan))
    arr = np.concatenate([air, np.array(out, dtype=np.float64).reshape(-1, 8)])
    order = np.argsort(arr[:, 0], kind="stable")
    arr = arr[order]
    keep = np.concatenate([[True], np.diff(arr[:, 0]) > 1e-12])
    arr = arr[keep]
    return Shot(arr[:, 0], arr[:, 1:4], arr[:, 4:7], arr[:, 7].astype(np.int8), landing_time, landing_point,
                apex_time, apex_point, rest_time, rest_point)


def _air(theta: np.ndarray, cfg: FlightConfig, t_end: float) -> tuple[np.ndarray, bool]:
    """The flight (:func:`_flight`) from launch time ``t0`` at ``(X0, Y0, Z0)`` as rows ``t, X, Y, Z, vX,
    vY, vZ, phase`` on the log clock, cut at ``t_end``; True when the ball came down before it."""
    t0, X0, Y0, Z0, speed, el, az, cd, cl, cl1, tilt = (float(v) for v in theta[:11])
    h = cfg.step_s
    air, hit = _flight(Z0, speed, el, az, cd, cl, cl1, tilt, air_k(cfg.ball), cfg.ball.diameter / 2, h,
                       max(cfg.max_time_s, t_end - t0 + h))
    air = air + np.array([t0, X0, Y0, 0.0, 0.0, 0.0, 0.0, 0.0])
    if hit and air[-1, 0] > t_end:  # the log ends before the ball comes down
        hit = False
        air = air[:max(1, int(np.searchsorted(air[:, 0], t_end, side="left")) + 1)]
    return air, hit


def _bounces(theta: np.ndarray, cfg: FlightConfig, t_end: float, t: float, p: tuple, v: tuple,
             out: list[tuple]) -> tuple[float, np.ndarray]:
    """From a ground contact at time ``t`` (centre ``p``, velocity ``v``): impacts (:func:`_impact`), hops
    and the roll (:func:`_roll`) up to ``t_end``, as rows appended to ``out``; the rest time and point
    (NaN: not at rest by ``t_end``)."""
    az, cd, e, mu, b, a_roll = (float(theta[i]) for i in (6, 7, 11, 12, 13, 14))
    k, contact, h = air_k(cfg.ball), cfg.ball.diameter / 2, cfg.step_s
    az_r = math.radians(az)
    hops, hit = 0, True
    while hit and t < t_end:
        vh1, (ux, uy), b, vz = _impact(v, b, e, mu, az_r)
        if hop_height(vz, G) < MIN_HOP_M or hops > 20:
            return _roll(p, vh1, b, (ux, uy), t, a_roll, t_end, h, contact, out)
        hops += 1
        # A hop: drag, and Magnus lift from the spin b about the horizontal axis across the motion
        # ((B2) C_L = S / (1 + 2S), S = |b| / |v|, at the hop's start speed; topspin pushes down).
        sp0 = math.sqrt(vh1 * vh1 + vz * vz)
        S = abs(b) / max(sp0, 1e-6)
        cl_hop = k * S / (1.0 + 2.0 * S) if cfg.hop_lift else 0.0  # (B2) times k, in the fit's rounding
        sgn = 1.0 if b >= 0 else -1.0
        w_hop = (sgn * uy, -sgn * ux, 0.0)
        t_hop = t
        p, v, t, hit = _fly(p, (vh1 * ux, vh1 * uy, vz), t, h, k * cd, (cl_hop, 0.0, 1.0), w_hop, contact, t_end, BOUNCE, out)
        # The spin decays in the air (e-folding time ~25 s): over a 1.4 s hop 5 % of the topspin
        # the first impact left, so the next impact finds the ball slipping a little again.
        if cfg.spin_decay_s > 0:
            b *= math.exp(-(t - t_hop) / cfg.spin_decay_s)
    return math.nan, np.full(3, np.nan)


def _impact(v: tuple, b: float, e: float, mu: float, az_r: float) -> tuple[float, tuple[float, float], float, float]:
    """(B4) in the fit's terms: horizontal speed, its direction, backspin surface speed ``b`` and vertical
    speed after an impact of a ball at velocity ``v`` spinning at ``b`` (``az_r``: the direction when it
    comes straight down).

    The normal speed reverses with restitution e; the friction impulse jt (per unit mass, along the
    motion) is mu times the normal impulse, at most the 2/7 of the contact point's slip (horizontal
    speed + backspin surface speed b) that stops it; it takes jt from the horizontal speed and
    5/2 jt from b (b < 0: topspin)."""
    vh0 = math.hypot(v[0], v[1])
    ux, uy = (v[0] / vh0, v[1] / vh0) if vh0 > 1e-9 else (math.cos(az_r), math.sin(az_r))
    slip = vh0 + b
    jt = math.copysign(friction_impulse(mu * (1.0 + e) * abs(v[2]), abs(slip)), slip)
    return vh0 - jt, (ux, uy), b - 2.5 * jt, -e * v[2]


def _roll(p: tuple, vh: float, b: float, direction: tuple[float, float], t: float, a_roll: float, t_end: float,
          h: float, contact: float, out: list[tuple]) -> tuple[float, np.ndarray]:
    """(B5): roll along the last horizontal direction without slipping, decelerating at ``a_roll``, from
    time ``t``; rows every 4 steps appended to ``out``; the rest time and point (NaN: after ``t_end``)."""
    ux, uy = direction
    s0 = no_slip(vh, vh + b)
    if s0 < 0:
        ux, uy, s0 = -ux, -uy, -s0
    t_rest = t + (s0 / a_roll if a_roll > 1e-9 else 1e3)
    t_stop = min(t_rest, t_end + h)
    for tt in np.linspace(t, t_stop, max(2, int(math.ceil((t_stop - t) / (4 * h))) + 1))[1:]:
        dt = tt - t
        dist = roll_distance(s0, a_roll, dt)
        sp = s0 - a_roll * dt
        out.append((tt, p[0] + dist * ux, p[1] + dist * uy, contact, sp * ux, sp * uy, 0.0, ROLL))
    if not t_rest <= t_end + h:
        return math.nan, np.full(3, np.nan)
    dist = roll_distance(s0, a_roll, t_rest - t)
    rest_point = np.array([p[0] + dist * ux, p[1] + dist * uy, contact])
    out.append((t_rest + 1e3, *rest_point, 0.0, 0.0, 0.0, REST))
    return t_rest, rest_point


# --- observations --------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class Observations:
    """Measured frames of the ball: times (s), unit lines of sight, apparent size (px), focal length (px)."""

    frame: np.ndarray
    t: np.ndarray
    los: np.ndarray  # (n, 3)
    size_px: np.ndarray  # (n,) NaN where unknown
    fx: np.ndarray  # (n,)
    camera: np.ndarray  # (3,)
    confidence: np.ndarray | None = None  # (n,) the tracker's confidence, NaN where unknown

    def subset(self, keep: np.ndarray) -> Observations:
        conf = None if self.confidence is None else self.confidence[keep]
        return Observations(self.frame[keep], self.t[keep], self.los[keep], self.size_px[keep], self.fx[keep], self.camera, conf)


def observations(traj: pl.DataFrame, cameras: dict[int, PtzCamera], *, track_id: int | None = None,
                 what: str = "the trajectory") -> Observations:
    """The measured rows with a line of sight and a camera pose; :class:`FlightUnavailable` if none."""
    if not cameras:
        raise FlightUnavailable(f"3-D not available: {what} comes from a log without PTZ encoders and a lens table, "
                                f"so the ball has no lines of sight (the golf tracker tracked in image coordinates only)")
    rows = traj.filter((pl.col("status") == "measured") & pl.col("dx").is_not_null() & pl.col("x").is_not_null())
    if track_id is not None:
        rows = rows.filter(pl.col("track_id") == track_id)
    rows = rows.filter(pl.col("frame").is_in(list(cameras)))
    if rows.height < 10:
        raise FlightUnavailable(f"3-D not available: {what} has only {rows.height} measured frames with a line of sight "
                                f"(at least 10 are needed)")
    frames = rows["frame"].to_numpy()
    los = rows.select("dx", "dy", "dz").to_numpy().astype(float)
    norm = np.linalg.norm(los, axis=1)
    bad = np.flatnonzero(~(np.isfinite(norm) & (norm > 0)))
    if bad.size:
        raise TrackreplayError(f"{what}: the line of sight (dx, dy, dz) at measured frame {int(frames[bad[0]])}"
                               + (f" (and {bad.size - 1} more)" if bad.size > 1 else "") + " is not a finite, non-zero vector")
    los /= norm[:, None]
    w, h = rows["w"].to_numpy().astype(float), rows["h"].to_numpy().astype(float)
    size = np.sqrt(np.where(np.isfinite(w) & (w > 0), w, np.nan) * np.where(np.isfinite(h) & (h > 0), h, np.nan))
    fx = np.array([math.sqrt(cameras[int(f)].intrinsics.fx * cameras[int(f)].intrinsics.fy) for f in frames])
    position = next(iter(cameras.values())).position
    conf = rows["confidence"].cast(pl.Float64).fill_null(np.nan).to_numpy() if "confidence" in rows.columns else np.full(len(frames), np.nan)
    return Observations(frames, rows["t_ns"].to_numpy().astype(float) * 1e-9, los, size, fx, np.asarray(position, float), conf)


# --- the trajectory read for a fit: only the rows and columns it uses ---------------------------------
READ_ROWS = 4096  # rows of a trajectory file read, cast and checked at a time (issue 33)
OBSERVED = ("tracker", "track_id", "frame", "t_ns", "x", "w", "h", "dx", "dy", "dz", "status", "confidence")


@dataclass(frozen=True, eq=False)
class FlightInput:
    """What ``flight`` uses of a trajectory: the ball's trackers' rows (every tracker's when none is a
    ball's) reduced to their measured rows with a position and a line of sight (:data:`OBSERVED`,
    canonical order), the tracks they hold and each track's measured rows."""

    rows: pl.DataFrame
    tracks: frozenset[int]
    measured: dict[int, int]

    def most_measured(self) -> int | None:
        """The track with the most measured rows (the lowest id among equals); None when none has one."""
        return min(self.measured, key=lambda t: (-self.measured[t], t)) if self.measured else None


def _observed(table: pl.DataFrame) -> pl.DataFrame:
    return table.filter((pl.col("status") == "measured") & pl.col("dx").is_not_null()
                        & pl.col("x").is_not_null()).select(OBSERVED)


def _input(parts: list[pl.DataFrame], counts: pl.DataFrame, ball: Callable[[str], bool]) -> FlightInput:
    """``parts``: :func:`_observed` rows in canonical order; ``counts``: ``tracker, track_id, measured`` of
    every track."""
    names = [n for n in counts["tracker"].unique().sort().to_list() if ball(n)]
    if names:
        counts = counts.filter(pl.col("tracker").is_in(names))
    rows = pl.concat(parts) if parts else pl.DataFrame(schema={c: SCHEMA[c] for c in OBSERVED})
    if names:
        rows = rows.filter(pl.col("tracker").is_in(names))
    per_track = counts.group_by("track_id").agg(pl.col("measured").sum())
    measured = {int(t): int(n) for t, n in per_track.iter_rows() if n > 0}
    return FlightInput(rows, frozenset(int(t) for t in counts["track_id"]), measured)


def _counts(table: pl.DataFrame) -> pl.DataFrame:
    return table.group_by("tracker", "track_id").agg((pl.col("status") == "measured").sum().cast(pl.Int64).alias("measured"))


def flight_input(table: pl.DataFrame, ball: Callable[[str], bool]) -> FlightInput:
    """The :class:`FlightInput` of a whole table (``read_trajectory``'s); ``ball(name)``: whether a tracker's
    tracks are a ball in flight."""
    return _input([_observed(table).sort(["tracker", "track_id", "frame"], maintain_order=True)], _counts(table), ball)


def read_flight_input(path, ball: Callable[[str], bool], rows: int | None = None) -> FlightInput | None:
    """:func:`flight_input` of a Parquet or CSV trajectory read ``rows`` (:data:`READ_ROWS`) at a time, each
    batch cast and checked as ``read_trajectory`` checks the whole table (``conform``), keeping only the
    observed rows and the per-track counts (issue 33: the whole table was ~150 bytes a row). None when a
    check fails, the file does not read, holds no rows or is not in canonical order (a track's frame twice
    across batches would go unseen): then read it whole, which names a defect in its own words."""
    from pathlib import Path

    from pyarrow.lib import ArrowException

    from trackreplay.replay.core import export

    path = Path(path)
    suffix = path.suffix.lower()
    if not path.is_file() or suffix not in (".parquet", ".csv"):
        return None
    if suffix == ".parquet":
        batches = (export.conform(b, str(path)) for b in export.parquet_batches(path, rows or READ_ROWS))
    else:
        batches = (part for part, _ in export._csv_parts(path))
    kept, counts, last, n = [], [], None, 0
    try:
        for batch in batches:
            if not batch.height:
                continue
            keys = batch.select(export.KEYS)
            if not export._strictly_ordered(keys if last is None else pl.concat([last, keys])):
                return None
            last = keys.tail(1)
            n += batch.height
            kept.append(_observed(batch))
            counts.append(_counts(batch))
    except (export._ReadWhole, TrackreplayError, pl.exceptions.PolarsError, OSError, ArrowException):
        return None
    if not n:
        return None
    total = pl.concat(counts).group_by("tracker", "track_id").agg(pl.col("measured").sum())
    return _input(kept, total, ball)


def _residuals(theta: np.ndarray, obs: Observations, cfg: FlightConfig, t_end: float, basis: np.ndarray) -> np.ndarray:
    shot = simulate(theta, cfg, t_end)
    pos, _ = shot.at(obs.t)
    rel = pos - obs.camera
    rng = np.linalg.norm(rel, axis=1)
    d = rel / rng[:, None]
    # The modelled direction in the measured ray's own tangent plane, in pixels of that frame.
    cosang = np.sum(d * obs.los, axis=1)
    e1 = np.einsum("ij,ij->i", d, basis[:, 0]) / cosang
    e2 = np.einsum("ij,ij->i", d, basis[:, 1]) / cosang
    res = [obs.fx * e1 / cfg.sigma_px, obs.fx * e2 / cfg.sigma_px]
    if cfg.use_size:
        model_size = obs.fx * cfg.ball.diameter / rng
        r = np.log(obs.size_px / model_size) / cfg.sigma_size
        res.append(np.where(np.isfinite(r), r, 0.0))
    if cfg.confidence_weight and obs.confidence is not None:
        w = np.sqrt(np.clip(np.where(np.isfinite(obs.confidence), obs.confidence, 1.0), 0.1, 1.0))
        res = [r * w for r in res]
    return np.concatenate(res)


def _basis(los: np.ndarray) -> np.ndarray:
    """Two unit vectors perpendicular to each line of sight: (n, 2, 3)."""
    up = np.array([0.0, 0.0, 1.0])
    a = np.cross(los, up)
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    b = np.cross(los, a)
    return np.stack([a, b], axis=1)


def _ground_point(camera: np.ndarray, los: np.ndarray, z: float) -> np.ndarray | None:
    if los[2] >= -1e-6:
        return None
    s = (z - camera[2]) / los[2]
    return camera + s * los


def _initial(obs: Observations, cfg: FlightConfig, fps: float) -> tuple[np.ndarray, list[str], float]:
    """Launch point and time from the frames before the ball moves; a rough rest direction for the azimuth.

    Also the latest launch time: one frame after the last frame that measured the ball still on the
    tee (the tracker loses the ball at the launch and may find it again only far down the flight;
    the frame after its last tee frame, measured or not, is one where the ball had left)."""
    notes: list[str] = []
    contact = cfg.ball.diameter / 2
    first = obs.los[0]
    ang = np.degrees(np.arccos(np.clip(obs.los @ first, -1, 1)))
    # The ball moves when its line of sight leaves the first one by more than ~3 px of the frame.
    moved = np.flatnonzero(ang * np.pi / 180 * obs.fx > 3.0)
    if not moved.size:
        raise FlightUnavailable(f"3-D not available: the ball does not move in the {len(ang)} measured frames "
                                f"(its line of sight stays within 3 px of the first): there is no flight to fit")
    k = int(moved[0])
    still = slice(0, max(1, k))
    mean = obs.los[still].mean(axis=0)
    mean /= np.linalg.norm(mean)
    p0 = _ground_point(obs.camera, mean, contact)
    # The launch bound holds only if the tracker saw the ball at rest on the ground (a track that
    # starts in the air — the "beside" shot, marked over the sky — has no tee frames to bound it).
    on_tee = p0 is not None and k >= 3
    if p0 is None:
        notes.append("the first frames do not look down at the ground: launch point guessed 10 m in front of the camera")
        p0 = obs.camera + 10.0 * mean
        p0[2] = contact
    if k > 0 and on_tee:
        t_last = float(obs.t[k - 1])
        t0, t_hi = min(t_last + 0.5 / fps, 0.5 * (t_last + obs.t[k])), min(t_last + 1.0 / fps, float(obs.t[k]))
    elif k > 0:
        t0, t_hi = 0.5 * (obs.t[k - 1] + obs.t[k]), math.inf
    else:
        t0, t_hi = obs.t[0] - 0.5 / fps, math.inf
    # Azimuth: towards where the ball ends (its last line of sight on the ground), else along the view.
    end = _ground_point(obs.camera, obs.los[-1], contact)
    target = end if end is not None and np.linalg.norm(end[:2] - p0[:2]) > 5.0 else obs.camera + 100 * obs.los[-1]
    az = math.degrees(math.atan2(target[1] - p0[1], target[0] - p0[0]))
    theta = np.array([t0, *p0, 50.0, 20.0, az, 0.25, 0.2, 0.0, 0.0, 0.4, 0.4, 10.0, 2.0])
    return theta, notes, t_hi


# Z0 is held at the ball's resting height (a ball on the tee or the turf): a camera behind the tee
# looks along the line from itself to the ball, so the lines of sight alone cannot place it.
FIXED = np.array([n == "Z0" for n in NAMES])
LOWER = np.array([-np.inf, -np.inf, -np.inf, 0.0, 5.0, 1.0, -np.inf, 0.0, 0.0, -1.0, -60.0, 0.0, 0.0, -20.0, 0.05])
UPPER = np.array([np.inf, np.inf, np.inf, 5.0, 120.0, 75.0, np.inf, 1.5, 1.0, 1.0, 60.0, 0.95, 1.5, 60.0, 20.0])
# Typical size of each parameter's uncertainty (least_squares' x_scale). With x_scale="jac" the
# default tee shot took 222 iterations along the launch speed / time / lift valley (~3000 RK4
# simulations, 74 s on a loaded 2-core machine); with these, 66 iterations to the same optimum (32 s).
# On the launch2 shot they reach a lower cost (4.07 vs 5.32 px RMS) whose landing is 1.6 m off
# instead of 0.1 m: the earlier, closer landing was a worse optimum.
X_SCALE = np.array([0.05, 0.3, 0.3, 0.01, 2.0, 1.0, 0.5, 0.03, 0.03, 0.1, 3.0, 0.05, 0.05, 1.0, 0.3])


def _solve(theta, obs, cfg, t_end, basis, free: np.ndarray, max_nfev: int, upper: np.ndarray = UPPER):
    def fun(x):
        full = theta.copy()
        full[free] = x
        return _residuals(full, obs, cfg, t_end, basis)

    x0 = np.clip(theta[free], LOWER[free] + 1e-9, upper[free] - 1e-9)
    res = least_squares(fun, x0, bounds=(LOWER[free], upper[free]), loss=cfg.loss, f_scale=cfg.f_scale,
                        x_scale=X_SCALE[free], max_nfev=max_nfev, diff_step=1e-6)
    out = theta.copy()
    out[free] = res.x
    return out, res


@dataclass(frozen=True, eq=False)
class FlightFit:
    theta: np.ndarray
    cov: np.ndarray
    shot: Shot
    report: FlightReport
    observations: Observations
    config: FlightConfig
    t_end: float

    def positions(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Fitted positions at log times (s), their 1-σ (per axis) and phase codes; computed
        :data:`POSITION_CHUNK` times at a time (each time's values alone: the same as all at once),
        so a long log's frames cost 49 bytes each (position, 1-σ, phase), not also their derivatives' 360."""
        times = np.asarray(times, dtype=np.float64)
        pos, std, phase = np.empty((len(times), 3)), np.empty((len(times), 3)), np.empty(len(times), np.int8)
        lo = 0
        for p, s, ph in self.position_parts(times):
            part = slice(lo, lo + len(p))
            pos[part], std[part], phase[part] = p, s, ph
            lo += len(p)
        return pos, std, phase

    def position_parts(self, times: np.ndarray, chunk: int | None = None):
        """:meth:`positions` ``chunk`` (:data:`POSITION_CHUNK`) times at a time, in order (the perturbed
        flights simulated once, to the last of all ``times``): each part's values are those of all at once."""
        times = np.asarray(times, dtype=np.float64)
        chunk = chunk or POSITION_CHUNK
        shots = self._perturbed(times)
        for lo in range(0, len(times), chunk):
            pos, J, phase = self._sensitivity(times[lo:lo + chunk], shots)
            yield pos, np.sqrt(np.maximum(np.einsum("nap,pq,naq->na", J, self.cov, J), 0.0)), phase

    def sensitivity(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Fitted positions at log times (s), their derivatives by the parameters ``(n, 3, p)``
        (finite differences: one flight per parameter) and phase codes; with :attr:`cov` they give
        any function of the positions its uncertainty."""
        return self._sensitivity(times, self._perturbed(times))

    def _perturbed(self, times: np.ndarray) -> list[tuple[float, Shot]]:
        """Per parameter, its finite-difference step and the shot with it added (to the last of ``times``)."""
        t_end = max(self.t_end, float(np.max(times))) if len(times) else self.t_end
        out = []
        for i in range(len(self.theta)):
            d = _step(self.theta, i)
            th = self.theta.copy()
            th[i] += d
            out.append((d, simulate(th, self.config, t_end)))
        return out

    def _sensitivity(self, times: np.ndarray, shots: list[tuple[float, Shot]]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        pos, phase = self.shot.at(times)
        J = [(shot.at(times)[0] - pos) / d for d, shot in shots]
        return pos, np.stack(J, axis=-1), phase


POSITION_CHUNK = 4096  # times whose derivatives (3 x 15 values each) FlightFit.positions holds at once


def _step(theta: np.ndarray, i: int) -> float:
    return 1e-4 * max(1.0, abs(float(theta[i])))


UNSEEN_LANDING = slice(2, 12)  # _derived's carry .. rest time: not reported when no frame saw the landing
UNSEEN_REST = slice(8, 12)  # its rest point and time: not reported when no frame saw the ball at rest
BOUNCE_PARAMS = slice(11, 15)  # NAMES' restitution, friction, landing spin, roll deceleration


def _derived(theta: np.ndarray, cfg: FlightConfig, t_end: float) -> np.ndarray:
    s = simulate(theta, cfg, t_end)
    p0 = theta[1:4]
    carry = float(np.hypot(*(s.landing_point[:2] - p0[:2])))
    return np.array([s.apex_point[2], s.apex_time, carry, *s.landing_point, s.landing_time, s.landing_time - theta[0],
                     *s.rest_point, s.rest_time])


@dataclass(frozen=True, eq=False)
class _Problem:
    """What every stage of :func:`fit_flight` solves against: the observations, their ray bases, the
    simulated span and the parameters' upper bounds (the launch time's from the tee frames)."""

    obs: Observations
    cfg: FlightConfig
    t_end: float
    basis: np.ndarray
    upper: np.ndarray

    def solve(self, theta: np.ndarray, free: np.ndarray, max_nfev: int, keep: np.ndarray | None = None):
        """:func:`_solve` on every frame, or on the frames ``keep`` selects."""
        obs, basis = (self.obs, self.basis) if keep is None else (self.obs.subset(keep), self.basis[keep])
        return _solve(theta, obs, self.cfg, self.t_end, basis, free, max_nfev, self.upper)


def fit_flight(obs: Observations, cfg: FlightConfig = FlightConfig(), fps: float = 30.0,
               progress: Callable[[str], None] | None = None) -> FlightFit:
    """Fit the shot to the observations (see the module docstring). Deterministic.
    ``progress(stage)`` is told each stage as it starts (``flight`` prints it); it changes nothing.

    Stages: a start (:func:`_initial`), the launch velocity from a few guesses (:func:`_launch_velocity`),
    every parameter free (:func:`_refine`), the 1-σ of parameters and reported quantities
    (:func:`_uncertainty`, :func:`_jackknife`), what no frame saw left out (:func:`_unseen`), the
    report (:func:`_report`)."""
    t_end = float(obs.t[-1]) + 0.5
    theta, notes, t_hi = _initial(obs, cfg, fps)
    upper = UPPER.copy()
    upper[0] = t_hi
    if math.isfinite(t_hi):
        notes.append(f"launch held before {t_hi:.3f} s, one frame after the last frame with the ball on the tee")
    tell = progress or (lambda stage: None)
    problem = _Problem(obs, cfg, t_end, _basis(obs.los), upper)
    tell("launch velocity")
    theta = _launch_velocity(problem, theta)
    tell("every parameter")
    theta, res = _refine(problem, theta, notes)
    tell("uncertainty")
    cov, base, dstd, pstd = _uncertainty(theta, res, cfg, t_end)
    tell("jackknife")
    cov, dstd, pstd = _jackknife(problem, theta, cov, dstd, pstd, notes)
    shot = simulate(theta, cfg, t_end)
    theta_out = _unseen(shot, obs, theta, base, dstd, pstd, notes)
    report = _report(problem, theta, theta_out, pstd, base, dstd, notes)
    return FlightFit(theta, cov, shot, report, obs, cfg, t_end)


def _launch_velocity(problem: _Problem, theta: np.ndarray) -> np.ndarray:
    """Stage 1: launch velocity from a few guesses (speed x elevation), physics at typical values."""
    vel = np.zeros(len(NAMES), bool)
    vel[[4, 5, 6]] = True
    best = None
    for speed in (35.0, 55.0, 75.0):
        for el in (12.0, 25.0):
            th = theta.copy()
            th[4], th[5] = speed, el
            th, res = problem.solve(th, vel, 40)
            if best is None or res.cost < best[1]:
                best = (th, res.cost)
    return best[0]


def _refine(problem: _Problem, theta: np.ndarray, notes: list[str]):
    """Stage 2: everything free, in rounds of 100 evaluations: a kink (the friction's cap, a hop too low
    to count) can shrink least_squares' trust region until it crawls, and a restart resets it (the
    default tee shot crawled to the 400-evaluation limit in one run; restarted after 100 it converged
    in 9 more)."""
    for _ in range(4):
        theta, res = problem.solve(theta, ~FIXED, 100)
        if res.status != 0:
            break
    if not res.success:
        notes.append(f"least squares stopped early: {res.message}")
    return theta, res


def _uncertainty(theta: np.ndarray, res, cfg: FlightConfig, t_end: float):
    """The fit's covariance ``(JᵀJ)⁻¹ s²`` (zero for the fixed parameters) and the reported quantities
    (:func:`_derived`) with their 1-σ propagated by finite differences; the parameters' 1-σ."""
    all_free = ~FIXED
    m, n = res.fun.size, res.x.size
    J = res.jac
    s2 = 2.0 * res.cost / max(1, m - n)  # the robust (soft-L1) cost: a few wrong blobs do not blow it up
    cov = np.zeros((len(NAMES), len(NAMES)))  # the fixed parameters have no variance
    cov[np.ix_(all_free, all_free)] = np.linalg.pinv(J.T @ J) * s2
    n = len(NAMES)
    base = _derived(theta, cfg, t_end)
    D = np.zeros((base.size, n))
    for i in range(n):
        d = _step(theta, i)
        th = theta.copy()
        th[i] += d
        D[:, i] = (_derived(th, cfg, t_end) - base) / d
    dstd = np.sqrt(np.maximum(np.einsum("ap,pq,aq->a", D, cov, D), 0.0))
    pstd = np.sqrt(np.maximum(np.diag(cov), 0.0))
    return cov, base, dstd, pstd


def _jackknife(problem: _Problem, theta: np.ndarray, cov: np.ndarray, dstd: np.ndarray, pstd: np.ndarray,
               notes: list[str]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Honest uncertainty: the delete-a-block jackknife over time folded into ``cov``, ``dstd`` and ``pstd``.

    (JᵀJ)⁻¹ s² assumes independent residuals; a rendered shot's are not (model error — the bounce,
    launch frames the tracker missed — leaves slow misfits) and it was 20x too small on a tee shot
    (σ 0.36 m, error 6.96 m). Inflating it for the residuals' autocorrelation went the other way
    (σ 115 m for a 0.06 m error: every parameter inflated alike). The jackknife asks the data
    directly: refit without each of K contiguous blocks of frames (warm-started at the fit),
    σ² = (K−1)/K Σ (θ_i − θ̄)², the reported quantities from each refit (no linearisation)."""
    cfg, nobs = problem.cfg, len(problem.obs.t)
    K = cfg.jackknife_blocks
    if not (K >= 2 and nobs >= 5 * K):
        notes.append("1-σ: the fit's covariance only (too few frames for the jackknife): model error not included")
        return cov, dstd, pstd
    thetas, derived = [], []
    for block in np.array_split(np.arange(nobs), K):
        keep = np.ones(nobs, bool)
        keep[block] = False
        th_i, _ = problem.solve(theta, ~FIXED, cfg.jackknife_nfev, keep)
        thetas.append(th_i)
        derived.append(_derived(th_i, cfg, problem.t_end))
    T, Dv = np.array(thetas), np.array(derived)
    f = (K - 1) / K
    dT = T - T.mean(axis=0)
    cov_jk = f * dT.T @ dT
    ok = np.isfinite(Dv).all(axis=0)  # a quantity some refit lacks (no rest in the log) keeps the covariance's
    djk = np.full(Dv.shape[1], np.nan)
    djk[ok] = np.sqrt(f * np.sum((Dv[:, ok] - Dv[:, ok].mean(axis=0)) ** 2, axis=0))
    # Reported quantities (apex, carry, landing, ...): the jackknife's (nonlinear, model error
    # included). The linearised covariance is unreliable there when launch speed and time trade
    # off (σ 48 m/s on a tee shot whose launch the tracker missed, propagated to 18 m on a landing
    # the ground frames pin within a few metres). Fit parameters: the larger of the two, since a
    # warm-started refit does not move along a direction no data constrain.
    dstd = np.where(np.isfinite(djk), djk, dstd)
    pstd = np.fmax(pstd, np.sqrt(np.maximum(np.diag(cov_jk), 0.0)))
    notes.append(f"1-σ: delete-a-block jackknife over {K} blocks of frames (parameters: the larger of it and the fit's covariance)")
    return cov + cov_jk, dstd, pstd  # the covariance for the exported positions: both parts


def _unseen(shot: Shot, obs: Observations, theta: np.ndarray, base: np.ndarray, dstd: np.ndarray, pstd: np.ndarray,
            notes: list[str]) -> np.ndarray:
    """Blank (NaN, in place) what no frame saw: a landing after the last measured frame (and with it the
    bounce and roll parameters), a rest after it; the parameters to report."""
    last_seen = float(obs.t[-1])
    theta_out = np.array(theta, dtype=np.float64)
    if not math.isfinite(shot.landing_time):
        notes.append("the fitted ball does not come down within the log: no landing, carry or rest")
    elif shot.landing_time > last_seen:
        # Nothing seen at or after the landing: the descent's end is an extrapolation of the model
        # (a log cut 10 ms before a 149 m landing fitted a 202 m carry, σ 3.4 m). Not reported.
        notes.append(f"the ball is not seen after the fitted landing (due {shot.landing_time - last_seen:.2f} s after the "
                     "last measured frame): landing, carry, time of flight and rest are extrapolations, not reported")
        base[UNSEEN_LANDING] = np.nan
        dstd[UNSEEN_LANDING] = np.nan
        theta_out[BOUNCE_PARAMS] = np.nan  # no impact seen: the bounce and roll are their starting values
        pstd[BOUNCE_PARAMS] = np.nan
    elif not (math.isfinite(shot.rest_time) and shot.rest_time <= last_seen):
        notes.append("the log ends before the fitted ball rests: no rest point")
        base[UNSEEN_REST] = np.nan
        dstd[UNSEEN_REST] = np.nan
    return theta_out


def _report(problem: _Problem, theta: np.ndarray, theta_out: np.ndarray, pstd: np.ndarray, base: np.ndarray,
            dstd: np.ndarray, notes: list[str]) -> FlightReport:
    """The :class:`FlightReport` of the fitted ``theta``: parameters ``theta_out`` ± ``pstd``, reported
    quantities ``base`` ± ``dstd``, and the residuals' RMS over the frames the robust loss kept."""
    obs, cfg, nobs = problem.obs, problem.cfg, len(problem.obs.t)
    resid = _residuals(theta, obs, cfg, problem.t_end, problem.basis)
    los_px = np.hypot(resid[:nobs], resid[nobs:2 * nobs]) * cfg.sigma_px
    size_r = resid[2 * nobs:] * cfg.sigma_size if cfg.use_size else np.zeros(0)

    def v(i: int) -> Value:
        return Value(float(theta_out[i]), float(pstd[i]))

    def dv(i: int) -> Value:
        return Value(float(base[i]), float(dstd[i]))

    inliers = los_px < 3 * cfg.f_scale * cfg.sigma_px
    return FlightReport(
        launch_time=v(0), launch_point=(v(1), v(2), v(3)), launch_speed=v(4), launch_elevation=v(5), launch_azimuth=v(6),
        drag_cd=v(7), lift_cl=v(8), lift_cl_slope=v(9), spin_tilt=v(10), apex_height=dv(0), apex_time=dv(1), carry=dv(2),
        landing_point=(dv(3), dv(4), dv(5)), landing_time=dv(6), time_of_flight=dv(7), restitution=v(11),
        friction=v(12), landing_spin=v(13), roll_decel=v(14), rest_point=(dv(8), dv(9), dv(10)), rest_time=dv(11),
        frames_used=nobs, rms_px=float(np.sqrt(np.mean(los_px[inliers] ** 2))) if inliers.any() else math.nan,
        size_rms=float(np.sqrt(np.mean(size_r[np.isfinite(obs.size_px)] ** 2))) if size_r.size else math.nan,
        notes=tuple(notes),
    )


ROWS_CHUNK = 8192  # frames of the fitted flight built (and written: a Parquet row group) at a time


def flight_rows(fit: FlightFit, frame_times: dict[int, int], cameras: dict[int, PtzCamera],
                tracker: str = "golf", track_id: int = 1) -> pl.DataFrame:
    """The fitted 3-D trajectory at every frame time: ★ trajectory rows (status ``interpolated``:
    a model value, not a measurement) with ``X, Y, Z``, the line of sight ``dx, dy, dz``, the image
    position in that frame's camera, and extra columns ``X_std, Y_std, Z_std`` (m) and ``phase``."""
    return pl.concat(list(flight_row_parts(fit, frame_times, cameras, tracker, track_id)))


FLIGHT_SCHEMA = {**SCHEMA, "X_std": pl.Float64, "Y_std": pl.Float64, "Z_std": pl.Float64, "phase": pl.String}


def flight_row_parts(fit: FlightFit, frame_times: dict[int, int], cameras: dict[int, PtzCamera],
                     tracker: str = "golf", track_id: int = 1, chunk: int | None = None):
    """:func:`flight_rows` ``chunk`` (:data:`ROWS_CHUNK`) frames at a time, in frame order (a long log's
    table is never whole: issue 33); at least one part, each the whole table's rows on its frames."""
    chunk = chunk or ROWS_CHUNK
    frames = np.array(sorted(frame_times), dtype=np.int64)
    t_ns = np.array([frame_times[int(f)] for f in frames], dtype=np.int64)
    lo = 0
    for pos, std, phase in fit.position_parts(t_ns.astype(np.float64) * 1e-9, chunk):
        part = slice(lo, lo + len(pos))
        lo += len(pos)
        yield _flight_table(fit, frames[part], t_ns[part], cameras, pos, std, phase, tracker, track_id)
    if not len(frames):
        empty = np.empty((0, 3))
        yield _flight_table(fit, frames, t_ns, cameras, empty, empty, np.empty(0, np.int8), tracker, track_id)


def _flight_table(fit: FlightFit, frames: np.ndarray, t_ns: np.ndarray, cameras, pos: np.ndarray, std: np.ndarray,
                  phase: np.ndarray, tracker: str, track_id: int) -> pl.DataFrame:
    rel = pos - fit.observations.camera
    d = rel / np.linalg.norm(rel, axis=1, keepdims=True)
    uv = np.full((len(frames), 2), np.nan)
    for i, f in enumerate(frames):
        cam = cameras.get(int(f))
        if cam is not None:
            p = cam.project_points(pos[i:i + 1])[0]
            if np.isfinite(p).all() and cam.in_image(p.reshape(1, 2))[0]:
                uv[i] = p
    n = len(frames)
    nan = np.full(n, np.nan)
    df = pl.DataFrame({
        "tracker": [tracker] * n, "track_id": np.full(n, track_id, np.int64), "frame": frames,
        "t_ns": t_ns,
        "x": uv[:, 0], "y": uv[:, 1], "w": nan, "h": nan, "X": pos[:, 0], "Y": pos[:, 1], "Z": pos[:, 2],
        "dx": d[:, 0], "dy": d[:, 1], "dz": d[:, 2], "vx": nan, "vy": nan, "status": ["interpolated"] * n,
        "confidence": nan, "X_std": std[:, 0], "Y_std": std[:, 1], "Z_std": std[:, 2],
        "phase": [PHASES[int(p)] for p in phase],
    }, nan_to_null=True)
    return df.cast(SCHEMA).select(*COLUMNS, "X_std", "Y_std", "Z_std", "phase")


def write_flight(fit: FlightFit, frame_times: dict[int, int], cameras: dict[int, PtzCamera], path,
                 tracker: str = "golf", track_id: int = 1, chunk: int | None = None) -> int:
    """:func:`flight_rows` written to ``path`` (.parquet: a row group a part; .csv) a part at a time, under
    this process's own partial name until complete; the rows written."""
    import os
    from pathlib import Path

    from trackreplay.recorder.atomic import claim_partial
    from trackreplay.replay.core.export import PieceWriter, trajectory_format
    from trackreplay.schemas.errors import OutputError

    path = Path(path)
    kind = trajectory_format(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = claim_partial(path)
    written = 0
    try:
        with PieceWriter(tmp, kind, FLIGHT_SCHEMA) as out:
            for part in flight_row_parts(fit, frame_times, cameras, tracker, track_id, chunk):
                out.write(part)
                written += part.height
        os.replace(tmp, path)
    except (OSError, pl.exceptions.PolarsError) as err:
        tmp.unlink(missing_ok=True)
        raise OutputError(f"cannot write {path} ({err})") from None
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return written
