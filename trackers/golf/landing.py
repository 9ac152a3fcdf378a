"""3-D extended Kalman filter of the ball and its landing (seed 000, §2.3).

State ``x = (X, Y, Z, VX, VY, VZ)`` in world metres (Z up) and m/s. Motion ``f``: the shared ball
model's (B1) (:mod:`trackreplay.trackers.golf.ball_flight`) without lift, gravity and quadratic drag
``a = g - k |v| v`` (``k = rho C_d A / 2m``), integrated with Heun's method; the unmodelled rest
(Magnus lift, wind) is white acceleration noise ``Q``. The integration stays hand-written: an EKF
needs the Jacobian ``F`` of each step (:func:`~trackreplay.trackers.golf.ball_flight.drag_jacobian`),
and one Heun step per 1/60 s substep is what every golden digest was computed with. Measurement
``z = (u, v, r)``: the ball's image position through the frame's PTZ camera and its range from the
apparent area (:mod:`trackreplay.trackers.golf.range`; the paper's "position and area"), so
``h(x) = (project(X, Y, Z), |X - C|)`` with Jacobian ``H``.

The ball touches the ground when its centre comes down to ``Z = D/2``. When the *predicted*
state crosses that height (:meth:`BallisticEkf.advance`) the tracker re-initialises its particles
at the projected contact point (paper: "the moment the ball meets the plane assumed to be the
ground"; see :mod:`trackreplay.trackers.golf.reinit`); the filter itself bounces (vertical speed
reversed with restitution, horizontal speed reduced) and goes on.

The filter is filterpy's EKF (:class:`~trackreplay.trackers.filters.kalman.MotionModelEkf`, the
project's one Kalman vocabulary: ``x, P, F, Q, H, R``), with a NIS gate in front of each update.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np

from trackreplay.trackers.base import NOT_HASHED
from trackreplay.trackers.filters.gating import Innovation
from trackreplay.trackers.filters.kalman import MotionModelEkf
from trackreplay.trackers.geometry.ptz import PtzCamera
from trackreplay.trackers.golf.ball_flight import acceleration
from trackreplay.trackers.golf.config import EkfConfig

NIS_GATE = 30.0  # chi-square, 3 dof: beyond 99.999 %; a selected blob that far is not our ball
MAX_REJECTIONS = 3  # consecutive gated measurements before the filter restarts from the measurement
MAX_SUBSTEP_S = 1.0 / 60.0
SUBSTEP_CACHE = 16  # substep lengths whose Q and F are kept (a steady log has two or three)


@dataclass(frozen=True)
class GroundContact:
    point: np.ndarray  # (3,) world position of the ball centre at contact
    fraction: float  # where in the last step, 0 = previous frame, 1 = this frame


def _substep_jacobian(v: np.ndarray, k: float, h: float, F0: np.ndarray) -> np.ndarray:
    """``F0`` with ``h * drag_jacobian(v, k)`` (:mod:`~trackreplay.trackers.golf.ball_flight`, (B1)) added to
    its velocity block, in Python floats: the same IEEE operations in the same order as
    ``F[3:, 3:] += h * (-k * (|v| I + v vᵀ / |v|))`` (``|v| * 1`` is ``|v|``, ``|v| * 0`` is ``0.0``; ``F0`` itself when the Jacobian is zero, as
    adding zeros to it gives)."""
    speed = math.sqrt(float(v @ v))
    if speed < 1e-9 or k == 0.0:
        return F0
    vx, vy, vz = v.tolist()
    nk = -k
    txy, txz, tyz = vx * vy / speed, vx * vz / speed, vy * vz / speed
    oxy, oxz, oyz = 0.0 + h * (nk * (0.0 + txy)), 0.0 + h * (nk * (0.0 + txz)), 0.0 + h * (nk * (0.0 + tyz))
    return np.array((1.0, 0.0, 0.0, h, 0.0, 0.0,  # one flat sequence: numpy reads it faster than nested rows
                     0.0, 1.0, 0.0, 0.0, h, 0.0,
                     0.0, 0.0, 1.0, 0.0, 0.0, h,
                     0.0, 0.0, 0.0, 1.0 + h * (nk * (speed + vx * vx / speed)), oxy, oxz,
                     0.0, 0.0, 0.0, oxy, 1.0 + h * (nk * (speed + vy * vy / speed)), oyz,
                     0.0, 0.0, 0.0, oxz, oyz, 1.0 + h * (nk * (speed + vz * vz / speed)))).reshape(6, 6)


def propagate(x: np.ndarray, dt: float, g: float, k: float) -> np.ndarray:
    """``f(x)``: one Heun (RK2) step of the state mean under (B1) without lift (:func:`acceleration`).

    Component by component in Python floats: the same IEEE operations, in the same order, as the
    vector form ``a = [0, 0, -g] - (k |v|) v``, ``v1 = v + dt a1``, ``p + (0.5 dt)(v + v1)``,
    ``v + (0.5 dt)(a1 + a2)``."""
    X, Y, Z, vx, vy, vz = x.tolist()
    ax, ay, az = acceleration((vx, vy, vz), k, g)
    ux, uy, uz = vx + dt * ax, vy + dt * ay, vz + dt * az
    bx, by, bz = acceleration((ux, uy, uz), k, g)
    half = 0.5 * dt
    return np.array([X + half * (vx + ux), Y + half * (vy + uy), Z + half * (vz + uz),
                     vx + half * (ax + bx), vy + half * (ay + by), vz + half * (az + bz)])


def predict_landing(x: np.ndarray, contact_z: float, g: float, k: float, horizon: float, step: float) -> tuple[float, np.ndarray] | None:
    """First time (s from now) and point at which the centre comes down to ``contact_z``.

    :func:`propagate`'s Heun steps in Python floats (faster than numpy for a 6-vector), linear
    interpolation in the last.
    """
    X, Y, Z, vx, vy, vz = x.tolist()
    if Z <= contact_z:
        return None
    t = 0.0
    half = 0.5 * step
    while t < horizon:
        ax, ay, az = acceleration((vx, vy, vz), k, g)
        ux, uy, uz = vx + step * ax, vy + step * ay, vz + step * az
        nZ = Z + half * (vz + uz)
        if nZ <= contact_z:
            nX, nY = X + half * (vx + ux), Y + half * (vy + uy)
            f = (Z - contact_z) / (Z - nZ) if Z != nZ else 1.0
            return t + f * step, np.array([X + f * (nX - X), Y + f * (nY - Y), contact_z])
        bx, by, bz = acceleration((ux, uy, uz), k, g)
        X, Y, Z = X + half * (vx + ux), Y + half * (vy + uy), nZ
        vx, vy, vz = vx + half * (ax + bx), vy + half * (ay + by), vz + half * (az + bz)
        t += step
    return None


def measurement_jacobian(camera: PtzCamera, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``h(x)`` = (u, v, r) and its 3 x 6 Jacobian ``H`` at world position ``p``."""
    k = camera.intrinsics
    fx, fy = float(k.fx), float(k.fy)
    Rt = camera.R.T
    rel = p - camera.position
    a, b, c = (Rt @ rel).tolist()  # Python floats: the same IEEE arithmetic as numpy's scalars
    c = max(c, 1e-6)
    r = math.sqrt(float(rel.dot(rel)))  # np.linalg.norm of a vector
    h = np.array([fx * a / c + k.cx, fy * b / c + k.cy, r])
    (u0, u1, u2), (v0, v1, v2) = (np.array([[fx / c, 0.0, -fx * a / (c * c)], [0.0, fy / c, -fy * b / (c * c)]]) @ Rt).tolist()
    x, y, z = rel.tolist()
    n = max(r, 1e-9)  # rel / n, element by element: numpy's divisions
    H = np.array([[u0, u1, u2, 0.0, 0.0, 0.0], [v0, v1, v2, 0.0, 0.0, 0.0], [x / n, y / n, z / n, 0.0, 0.0, 0.0]])
    return h, H


class BallisticEkf:
    """The landing predictor; ``x``/``P`` are None until the first measurement with a camera.

    ``contact_z`` is the height of the ball's centre on the ground (half its diameter).
    """

    def __init__(self, config: EkfConfig, contact_z: float) -> None:
        self.config = config
        self.contact_z = contact_z
        self.kf = MotionModelEkf(6, 3, lambda x, dt: propagate(x, dt, config.gravity, config.drag_k))
        self.initialised = False
        self.armed = False  # set once the ball has been high enough for a landing to mean something
        self.landed = False  # set when the flight's landing fired: from then on the ball may be rolling
        self.rejections = 0
        self.last_nis = math.nan
        self._substeps: dict[float, tuple[np.ndarray, np.ndarray]] = {}  # substep h: its Q and its F without the drag term

    @property
    def x(self) -> np.ndarray | None:
        return self.kf.x if self.initialised else None

    @property
    def P(self) -> np.ndarray | None:  # noqa: N802 (the textbook symbol)
        return self.kf.P if self.initialised else None

    def initialise(self, camera: PtzCamera, uv: np.ndarray, range_m: float, rel_sigma: float) -> None:
        """Start at the measured line of sight and range; velocity unknown (``init_velocity_sigma``)."""
        sigma_r = rel_sigma * range_m
        los = camera.line_of_sight(np.asarray(uv, dtype=np.float64).reshape(1, 2))[0]
        f = math.sqrt(camera.intrinsics.fx * camera.intrinsics.fy)
        across = range_m * self.config.pixel_sigma / f
        self.kf.x = np.concatenate([camera.position + range_m * los, np.zeros(3)])
        P = np.zeros((6, 6))
        along = np.outer(los, los)
        P[:3, :3] = sigma_r**2 * along + across**2 * (np.eye(3) - along)
        P[3:, 3:] = self.config.init_velocity_sigma**2 * np.eye(3)
        self.kf.P = P
        self.initialised = True
        self.rejections = 0

    def forget(self) -> None:
        """Back to "not started": the next measurement initialises the filter again."""
        self.initialised = False
        self.armed = False
        self.landed = False
        self.rejections = 0

    def predict(self, dt: float) -> None:
        """Propagate ``x`` and ``P`` by ``dt`` seconds (substeps of at most 1/60 s). A gap longer
        than ``max_gap_s`` is not integrated: the filter forgets the ball (:meth:`forget`), so the
        work per frame is bounded whatever the timestamps (at most ``max_gap_s * 60`` substeps)."""
        if not self.initialised or not dt > 0:
            return
        cfg = self.config
        if not dt <= cfg.max_gap_s:
            self.forget()
            return
        steps = max(1, int(math.ceil(dt / MAX_SUBSTEP_S)))
        h = dt / steps
        Q, F0 = self._substep_matrices(h)
        kf = self.kf
        kf.Q = Q
        for _ in range(steps):
            kf.F = _substep_jacobian(kf.x[3:], cfg.drag_k, h, F0)
            kf.predict(u=h)
        kf.P = 0.5 * (kf.P + kf.P.T)

    def _substep_matrices(self, h: float) -> tuple[np.ndarray, np.ndarray]:
        """``Q`` and ``F`` (without the drag term) of a substep of ``h`` seconds, built once per ``h``: a
        log's frame intervals take a few values (nanosecond stamps of 1/30 s round two ways), so the
        last one alone missed on two frames in three."""
        cached = self._substeps.get(h)
        if cached is None:
            G = np.concatenate([0.5 * h * h * np.eye(3), h * np.eye(3)])
            F = np.eye(6)
            F[:3, 3:] = h * np.eye(3)
            Q = self.config.accel_noise**2 * G @ G.T
            Q.flags.writeable = F.flags.writeable = False  # shared by every substep (the EKF only reads them)
            if len(self._substeps) >= SUBSTEP_CACHE:
                self._substeps.clear()
            cached = self._substeps[h] = (Q, F)
        return cached

    def ground_contact(self, previous: np.ndarray) -> GroundContact | None:
        """The contact point if the state went from above the contact height to at/below it."""
        if not self.initialised:
            return None
        x = self.kf.x
        z0, z1 = previous[2] - self.contact_z, x[2] - self.contact_z
        if z0 > 0.0 >= z1 and x[5] < 0:
            f = z0 / (z0 - z1)
            point = previous[:3] + f * (x[:3] - previous[:3])
            return GroundContact(point, float(f))
        if z0 <= 0.0 and z1 < 0.0:  # resting or rolling: stay on the ground
            return GroundContact(x[:3].copy(), 1.0)
        return None

    def bounce(self, contact: GroundContact) -> None:
        """Put the ball back on the ground: reversed vertical speed, slower horizontal speed."""
        cfg = self.config
        x = self.kf.x
        x[2] = self.contact_z
        if x[5] < 0:
            x[5] = -cfg.restitution * x[5]
        x[3:5] *= cfg.bounce_friction if self.armed else 1.0
        if self.armed:
            self.kf.P[3:, 3:] += np.diag([4.0, 4.0, 4.0]) ** 2  # the bounce is poorly known

    def on_ground(self, max_vz: float) -> bool:
        """The filter has the ball rolling or resting after its landing: at the contact height, hardly
        moving up or down. (Before the landing a state at the contact height is a range error, not a
        ball on the ground.)"""
        return (self.initialised and self.landed and self.kf.x[2] <= self.contact_z + 1e-6
                and abs(float(self.kf.x[5])) < max_vz)

    def advance(self, dt: float) -> np.ndarray | None:
        """Predict by ``dt``; the ground contact point when this is the flight's landing (§2.3).

        A contact counts as the landing once, after the ball was seen high enough (``armed``) and
        when it happened within the step; the filter bounces at every contact.
        """
        if not self.initialised:
            return None
        previous = self.kf.x.copy()
        self.predict(dt)
        if not self.initialised:  # a time gap: forgotten
            return None
        contact = self.ground_contact(previous)
        if contact is None:
            return None
        landing = contact.point if self.armed and contact.fraction < 1.0 else None
        self.bounce(contact)
        if landing is not None:
            self.armed = False
            self.landed = True
        return landing

    def update(self, camera: PtzCamera, uv: np.ndarray, range_m: float, rel_sigma: float, may_restart: bool = True) -> bool:
        """EKF update with ``z = (u, v, r)``; returns False when the measurement was gated out.

        With ``may_restart`` False a gated-out measurement is only a question asked (it neither counts
        towards the restart after ``MAX_REJECTIONS`` nor restarts the filter).

        ``rel_sigma`` is the range's relative uncertainty (see :func:`range.range_rel_sigma`); it
        scales the *predicted* range.
        """
        if not self.initialised:
            self.initialise(camera, uv, range_m, rel_sigma)
            return True
        h, H = measurement_jacobian(camera, self.kf.x[:3])
        sigma_r = rel_sigma * h[2]
        z = np.array([uv[0], uv[1], range_m])
        pixel_var = self.config.pixel_sigma**2
        R = np.array([[pixel_var, 0.0, 0.0], [0.0, pixel_var, 0.0], [0.0, 0.0, float(sigma_r**2)]])  # np.diag's matrix
        PHT = np.dot(self.kf.P, H.T)  # innovation()'s S, formed once for the gate and the update
        S = np.dot(H, PHT) + R
        self.last_nis = Innovation(z - h, S).nis
        if self.last_nis > NIS_GATE:
            if not may_restart:
                return False
            self.rejections += 1
            if self.rejections >= MAX_REJECTIONS:
                self.initialise(camera, uv, range_m, rel_sigma)
            return False
        self.rejections = 0
        self.kf.update(z, lambda _x: H, lambda _x: h, R=R, PHT=PHT, S=S)  # filterpy's update (Joseph form)
        if self.kf.x[2] >= self.config.landing_arm_height_m + self.contact_z:
            self.armed = True
        return True

    def image_covariance(self, camera: PtzCamera) -> np.ndarray:
        """2 x 2 pixel covariance of the position estimate seen through ``camera`` (``H P Hᵀ``)."""
        _, H = measurement_jacobian(camera, self.kf.x[:3])
        return H[:2, :3] @ self.kf.P[:3, :3] @ H[:2, :3].T

    def landing(self) -> tuple[float, np.ndarray] | None:
        """Predicted time (s from now) and point of the next ground contact."""
        return next_landing(self.kf.x, self.contact_z, self.config) if self.initialised else None


def next_landing(x: np.ndarray, contact_z: float, cfg: EkfConfig) -> tuple[float, np.ndarray] | None:
    """:func:`predict_landing` of state ``x`` with the filter's physics (None: on the ground already)."""
    if x[2] <= contact_z + 1e-3:
        return None
    return predict_landing(x, contact_z, cfg.gravity, cfg.drag_k, cfg.landing_horizon_s, cfg.landing_step_s)


@dataclass(frozen=True, eq=False)
class EkfState:
    """The EKF stage's intermediates (NaN before the filter starts).

    The predicted landing is drawn, never used by the tracker: it is integrated on first read
    (``landing_world``, ``landing_image``, ``landing_in_s``) from ``x``, which the digest hashes, so
    a replay that draws nothing (no ``--rrd``) never spends the ~100 Heun steps on it; what else it
    needs is the field ``landing_from``, which the digest skips (``NOT_HASHED``) and
    ``dataclasses.replace`` keeps."""

    x: np.ndarray  # (6,) world X, Y, Z, VX, VY, VZ
    P: np.ndarray  # (6, 6)
    nis: float  # of the last update (NaN: none yet)
    # what the landing is integrated from: contact height, EKF config, the frame's camera (None: no landing)
    landing_from: tuple | None = field(default=None, repr=False, metadata=NOT_HASHED)

    @classmethod
    def empty(cls) -> EkfState:
        return cls(np.full(6, np.nan), np.full((6, 6), np.nan), math.nan)

    @classmethod
    def of(cls, ekf: BallisticEkf, camera: PtzCamera | None) -> EkfState:
        """The filter now; its predicted landing (:func:`next_landing`) seen through ``camera`` when read."""
        if not ekf.initialised:
            return cls(np.full(6, np.nan), np.full((6, 6), np.nan), float(ekf.last_nis))
        return cls(ekf.x.copy(), ekf.P.copy(), float(ekf.last_nis), (ekf.contact_z, ekf.config, camera))

    @functools.cached_property
    def _landing(self) -> tuple[np.ndarray, np.ndarray, float]:
        world, image, seconds = np.full(3, np.nan), np.full(2, np.nan), math.nan
        source = self.landing_from
        prediction = next_landing(self.x, source[0], source[1]) if source is not None else None
        if prediction is not None:
            seconds, world = prediction
            if source[2] is not None:
                image = source[2].project_point(world)
        return np.asarray(world, float), np.asarray(image, float), float(seconds)

    @property
    def landing_world(self) -> np.ndarray:
        """(3,) predicted next ground contact (NaN if none)."""
        return self._landing[0]

    @property
    def landing_image(self) -> np.ndarray:
        """(2,) ... projected into this frame."""
        return self._landing[1]

    @property
    def landing_in_s(self) -> float:
        """Seconds until that contact."""
        return self._landing[2]
