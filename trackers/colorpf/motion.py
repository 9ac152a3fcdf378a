"""The state transition, eq. (2): ``x += ω_x``, ``y += ω_y``; ``w, h`` from the size estimate.

Position noise is Gaussian with standard deviations ``noise * (w, h)`` of the current box (at least
``min_noise_px``): relative, so a walker that comes closer (larger, faster in the image) is still
followed, and per axis, so the particles spread like the box — with an isotropic spread the
extent of the high-likelihood particles (eq. 11) measures the noise as much as the target, and
``R`` drifts to 1 (measured on the synthetic scenes).

The size per particle, by ``size.mode``:

- ``"geometry"`` (§4): ``S'`` from eq. (9) at the particle's own foot point, ``w, h`` from eq. (12)
  with the current ``R``;
- ``"noise"`` (the paper's baseline of Table 3, and of Tables 1-2): ``w, h`` random walks, each
  scaled by ``1 + N(0, size.noise)`` per frame;
- ``"fixed"``: the marked box's size throughout.
"""

from __future__ import annotations

import numpy as np

from trackreplay.trackers.colorpf.aspect import box_from_area
from trackreplay.trackers.colorpf.config import SizeConfig
from trackreplay.trackers.colorpf.size import WeakPerspectiveSize, foot_points, ground_distance  # noqa: F401
from trackreplay.trackers.filters.particles import Transition
from trackreplay.trackers.geometry.ground_plane import GroundPlane


def position_sigma(box_wh: np.ndarray, noise: float, min_px: float) -> np.ndarray:
    """``(σ_x, σ_y)`` for a box of size ``(w, h)``."""
    return np.maximum(noise * np.asarray(box_wh, dtype=np.float64), min_px)


def vouched_prediction(vouched_frame: int, vouched_xy: np.ndarray, velocity: np.ndarray, index: int) -> np.ndarray:
    """``hold.anchor = "vouched"``: the centre on frame ``index`` from the last vouched estimate (frame
    ``vouched_frame``, centre ``vouched_xy``) moving at ``velocity`` per frame: the constant-velocity
    prediction over the frames since, not from the last estimate (which no cue vouched for)."""
    frames = index - vouched_frame
    return np.asarray(vouched_xy, dtype=np.float64)[:2] + np.asarray(velocity, dtype=np.float64) * frames


def standing_box(xy: np.ndarray, h0: float | np.ndarray, model: WeakPerspectiveSize, plane: GroundPlane | None,
                 side: float, ratio: float, omega: np.ndarray | float = 0.0,
                 iterations: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """``S'`` (eq. 9) and ``Z`` for boxes centred at ``xy`` whose bottom stands on the ground.

    The foot is the box's bottom centre, the box's height follows from ``S'`` at the foot's
    distance: a fixed point ``h = R w = sqrt(R S') (Z(y + h/2))``, found by a few substitutions
    from ``h0`` (they converge fast: ``h`` changes the distance little). Taking the foot from the
    previous estimate's height instead feeds back: a box that shrank onto the shirt puts the foot
    higher, farther, so the next box is smaller still (seen on the synthetic scenes).
    """
    xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    h = np.broadcast_to(np.asarray(h0, dtype=np.float64), (len(xy),)).copy()
    if plane is None:  # every distance is NaN whatever h: each substitution repeats the first
        iterations = min(iterations, 1)
    for _ in range(iterations):
        distance = ground_distance(plane, foot_points(xy, h), side)
        area = model.areas_for(distance, omega)
        h = box_from_area(area, ratio)[1]
    return area, distance


def transition(*, sigma: np.ndarray, size: SizeConfig, ratio: float, box_wh: np.ndarray,
               model: WeakPerspectiveSize, plane: GroundPlane | None, side: float,
               initial_wh: np.ndarray, drift: np.ndarray | None = None) -> Transition:
    """Eq. (2) for :meth:`ParticleFilter.predict`; ``drift`` (ours, ``motion.model =
    "constant_velocity"``): a displacement ``(dx, dy)`` added to every particle, besides the noise."""

    def step(particles: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        out = particles.copy()
        out[:, :2] += rng.standard_normal((len(out), 2)) * sigma
        if drift is not None:
            out[:, :2] += drift
        if size.mode == "geometry" and not model.has_distance and size.no_plane == "random_walk":
            scale = np.maximum(1.0 + rng.standard_normal(len(out)) * size.noise, 0.5)  # aspect kept
            w = out[:, 2] * scale
            h = ratio * w
        elif size.mode == "geometry":
            omega = rng.standard_normal(len(out)) * model.r_s
            area, distance = standing_box(out[:, :2], box_wh[1], model, plane, side, ratio, omega)  # eq. (9)
            w, h = box_from_area(area, ratio)  # eq. (12)
        elif size.mode == "noise":
            scale = np.maximum(1.0 + rng.standard_normal((len(out), 2)) * size.noise, 0.5)
            w, h = out[:, 2] * scale[:, 0], out[:, 3] * scale[:, 1]
        else:
            w, h = np.full(len(out), initial_wh[0]), np.full(len(out), initial_wh[1])
        out[:, 2] = np.maximum(w, size.min_px)
        out[:, 3] = np.maximum(h, size.min_px)
        return out

    return step
