"""3-D extended Kalman filter of the ball and its landing (seed 000, §2.3).

State ``x = (X, Y, Z, VX, VY, VZ)`` in world metres (Z up) and m/s. Motion: gravity and
quadratic drag ``a = g - k |v| v`` (``k = rho C_d A / 2m``), integrated with Heun's method; the
unmodelled rest (Magnus lift, wind) is white acceleration noise. Measurement: the ball's image
position through the frame's posed PTZ camera, and its range ``r = f D / d`` from the apparent
diameter ``d = 2 sqrt(area / pi)`` of a ball of known diameter ``D`` (the paper's "position and
area"), so ``z = (u, v, r)`` and ``h(x) = (project(X, Y, Z), |X - C|)``.

The ball touches the ground when its centre comes down to Z = D/2. When the *predicted* state
crosses that height the tracker re-initialises its particles at the projected contact point
(paper: "the moment the ball meets the plane assumed to be the ground"); the filter itself then
bounces (vertical speed reversed with restitution, horizontal speed reduced) and goes on.
Plain numpy with textbook names (x, P, F, Q, H, R), as filterpy would have them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from trackreplay.trackers.geometry.ptz import PtzCamera
from trackreplay.trackers.golf.config import GolfConfig

NIS_GATE = 30.0  # chi-square, 3 dof: beyond 99.999 %; a selected blob that far is not our ball
MAX_REJECTIONS = 3  # consecutive gated measurements before the filter restarts from the measurement
MAX_SUBSTEP_S = 1.0 / 60.0


@dataclass(frozen=True)
class GroundContact:
    point: np.ndarray  # (3,) world position of the ball centre at contact
    fraction: float  # where in the last step, 0 = previous frame, 1 = this frame


def range_from_area(area_px: float, camera: PtzCamera, diameter_m: float) -> float:
    """Distance to a ball of diameter ``diameter_m`` that covers ``area_px`` pixels."""
    k = camera.intrinsics
    d = 2.0 * math.sqrt(max(area_px, 1e-9) / math.pi)
    return math.sqrt(k.fx * k.fy) * diameter_m / d


def range_rel_sigma(area_px: float, rel: float) -> float:
    """Relative range uncertainty: a floor ``rel`` plus +-0.7 px on the apparent diameter.

    The filter multiplies it by its *predicted* range: scaling by the measured range would
    trust short measurements more than long ones and pull the estimate short.
    """
    d = 2.0 * math.sqrt(max(area_px, 1e-9) / math.pi)
    return math.sqrt(rel * rel + (0.7 / d) ** 2)


def _accel(v: np.ndarray, g: float, k: float) -> np.ndarray:
    speed = math.sqrt(float(v @ v))
    return np.array([0.0, 0.0, -g]) - k * speed * v


def _accel_jacobian(v: np.ndarray, k: float) -> np.ndarray:
    """d(-k |v| v)/dv = -k (|v| I + v v^T / |v|)."""
    speed = math.sqrt(float(v @ v))
    if speed < 1e-9 or k == 0.0:
        return np.zeros((3, 3))
    return -k * (speed * np.eye(3) + np.outer(v, v) / speed)


def propagate(x: np.ndarray, dt: float, g: float, k: float) -> np.ndarray:
    """Heun (RK2) step of the state mean."""
    p, v = x[:3], x[3:]
    a1 = _accel(v, g, k)
    v1 = v + dt * a1
    a2 = _accel(v1, g, k)
    return np.concatenate([p + 0.5 * dt * (v + v1), v + 0.5 * dt * (a1 + a2)])


def predict_landing(x: np.ndarray, contact_z: float, g: float, k: float, horizon: float, step: float) -> tuple[float, np.ndarray] | None:
    """First time (s from now) and point at which the centre comes down to ``contact_z``.

    Pure-Python Heun steps (faster than numpy for a 6-vector), linear interpolation in the last.
    """
    X, Y, Z, vx, vy, vz = (float(c) for c in x)
    if Z <= contact_z:
        return None
    t = 0.0
    while t < horizon:
        s = math.sqrt(vx * vx + vy * vy + vz * vz)
        ax, ay, az = -k * s * vx, -k * s * vy, -g - k * s * vz
        ux, uy, uz = vx + step * ax, vy + step * ay, vz + step * az
        s2 = math.sqrt(ux * ux + uy * uy + uz * uz)
        bx, by, bz = -k * s2 * ux, -k * s2 * uy, -g - k * s2 * uz
        nX, nY, nZ = X + 0.5 * step * (vx + ux), Y + 0.5 * step * (vy + uy), Z + 0.5 * step * (vz + uz)
        if nZ <= contact_z:
            f = (Z - contact_z) / (Z - nZ) if Z != nZ else 1.0
            return t + f * step, np.array([X + f * (nX - X), Y + f * (nY - Y), contact_z])
        X, Y, Z = nX, nY, nZ
        vx, vy, vz = vx + 0.5 * step * (ax + bx), vy + 0.5 * step * (ay + by), vz + 0.5 * step * (az + bz)
        t += step
    return None


def measurement_jacobian(camera: PtzCamera, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``h(x)`` = (u, v, r) and its 3 x 6 Jacobian at world position ``p``."""
    k = camera.intrinsics
    Rt = camera.R.T
    rel = p - camera.position
    a, b, c = Rt @ rel
    c = max(c, 1e-6)
    r = float(np.linalg.norm(rel))
    h = np.array([k.fx * a / c + k.cx, k.fy * b / c + k.cy, r])
    d_uv = np.array([[k.fx / c, 0.0, -k.fx * a / (c * c)], [0.0, k.fy / c, -k.fy * b / (c * c)]]) @ Rt
    H = np.zeros((3, 6))
    H[:2, :3] = d_uv
    H[2, :3] = rel / max(r, 1e-9)
    return h, H


class BallisticEkf:
    """The landing predictor; ``x``/``P`` are None until the first measurement with a camera."""

    def __init__(self, config: GolfConfig) -> None:
        self.config = config
        self.contact_z = config.ball_diameter_m / 2.0
        self.x: np.ndarray | None = None
        self.P: np.ndarray | None = None
        self.armed = False  # set once the ball has been high enough for a landing to mean something
        self.rejections = 0
        self.last_nis = math.nan

    @property
    def initialised(self) -> bool:
        return self.x is not None

    def initialise(self, camera: PtzCamera, uv: np.ndarray, range_m: float, rel_sigma: float) -> None:
        sigma_r = rel_sigma * range_m
        los = camera.line_of_sight(np.asarray(uv, dtype=np.float64).reshape(1, 2))[0]
        f = math.sqrt(camera.intrinsics.fx * camera.intrinsics.fy)
        across = range_m * self.config.ekf_pixel_sigma / f
        self.x = np.concatenate([camera.position + range_m * los, np.zeros(3)])
        self.P = np.zeros((6, 6))
        along = np.outer(los, los)
        self.P[:3, :3] = sigma_r**2 * along + across**2 * (np.eye(3) - along)
        self.P[3:, 3:] = self.config.ekf_init_velocity_sigma**2 * np.eye(3)
        self.rejections = 0

    def predict(self, dt: float) -> None:
        """Propagate ``x`` and ``P`` by ``dt`` seconds (substeps of at most 1/60 s)."""
        if self.x is None or dt <= 0:
            return
        cfg = self.config
        steps = max(1, int(math.ceil(dt / MAX_SUBSTEP_S)))
        h = dt / steps
        q = cfg.ekf_accel_noise**2
        G = np.concatenate([0.5 * h * h * np.eye(3), h * np.eye(3)])
        Q = q * G @ G.T
        for _ in range(steps):
            F = np.eye(6)
            F[:3, 3:] = h * np.eye(3)
            F[3:, 3:] += h * _accel_jacobian(self.x[3:], cfg.drag_k)
            self.x = propagate(self.x, h, cfg.gravity, cfg.drag_k)
            self.P = F @ self.P @ F.T + Q
        self.P = 0.5 * (self.P + self.P.T)

    def ground_contact(self, previous: np.ndarray) -> GroundContact | None:
        """The contact point if the state went from above the contact height to at/below it."""
        if self.x is None:
            return None
        z0, z1 = previous[2] - self.contact_z, self.x[2] - self.contact_z
        if z0 > 0.0 >= z1 and self.x[5] < 0:
            f = z0 / (z0 - z1)
            point = previous[:3] + f * (self.x[:3] - previous[:3])
            return GroundContact(point, float(f))
        if z0 <= 0.0 and z1 < 0.0:  # resting or rolling: stay on the ground
            return GroundContact(self.x[:3].copy(), 1.0)
        return None

    def bounce(self, contact: GroundContact) -> None:
        """Put the ball back on the ground: reversed vertical speed, slower horizontal speed."""
        cfg = self.config
        self.x[2] = self.contact_z
        if self.x[5] < 0:
            self.x[5] = -cfg.restitution * self.x[5]
        self.x[3:5] *= cfg.bounce_friction if self.armed else 1.0
        if self.armed:
            self.P[3:, 3:] += np.diag([4.0, 4.0, 4.0]) ** 2  # the bounce is poorly known

    def update(self, camera: PtzCamera, uv: np.ndarray, range_m: float, rel_sigma: float) -> bool:
        """EKF update with ``z = (u, v, r)``; returns False when the measurement was gated out.

        ``rel_sigma`` is the range's relative uncertainty (see :func:`range_rel_sigma`).
        """
        if self.x is None:
            self.initialise(camera, uv, range_m, rel_sigma)
            return True
        h, H = measurement_jacobian(camera, self.x[:3])
        sigma_r = rel_sigma * h[2]
        z = np.array([uv[0], uv[1], range_m])
        R = np.diag([self.config.ekf_pixel_sigma**2, self.config.ekf_pixel_sigma**2, sigma_r**2])
        y = z - h
        S = H @ self.P @ H.T + R
        Sinv = np.linalg.inv(S)
        self.last_nis = float(y @ Sinv @ y)
        if self.last_nis > NIS_GATE:
            self.rejections += 1
            if self.rejections >= MAX_REJECTIONS:
                self.initialise(camera, uv, range_m, rel_sigma)
            return False
        self.rejections = 0
        K = self.P @ H.T @ Sinv
        self.x = self.x + K @ y
        IKH = np.eye(6) - K @ H
        self.P = IKH @ self.P @ IKH.T + K @ R @ K.T  # Joseph form
        if self.x[2] >= self.config.landing_arm_height_m + self.contact_z:
            self.armed = True
        return True

    def landing(self) -> tuple[float, np.ndarray] | None:
        """Predicted time (s from now) and point of the next ground contact."""
        if self.x is None or self.x[2] <= self.contact_z + 1e-3:
            return None
        cfg = self.config
        return predict_landing(self.x, self.contact_z, cfg.gravity, cfg.drag_k, cfg.landing_horizon_s, cfg.landing_step_s)


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
