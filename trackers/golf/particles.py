"""The golf tracker's CONDENSATION models (seed 000, §2.2), for the shared particle filter.

State ``s = (x, y, vx, vy)`` in frame pixels and pixels per frame, N weighted samples in a
:class:`~trackreplay.trackers.filters.particles.ParticleFilter`. Per frame the filter *selects*
(systematic resampling), *predicts* with :func:`motion` and *measures* with :func:`likelihood`:

- eq. (1) ``s = F s' + G w``: constant velocity ``F``, ``G = I``, Gaussian ``w`` with standard
  deviations ``(pos, pos, vel, vel)``. Ours on top: after a miss the velocities are damped (an
  unseen ball's velocity is ever less known; without this the cloud drifts away), and ``k``
  dropped frames coast ``k`` more constant-velocity steps with the noise grown by ``√(k+1)``;
  and a mixed state (Isard & Blake's mixed-state CONDENSATION): each frame a share of the samples
  stop. A broadcast ball's image velocity is mostly the operator's error, which can stop or reverse
  within a frame or two (catching up after a hop); constant-velocity samples alone run on past it.
- eq. (2) ``π ∝ α + 1/(√(2π) σ) Σ_m exp(−d(z_m, x)² / 2σ²)`` over the M candidate centroids
  (the printed formula shows ``1 +``; ``α`` is the constant the text names).
- eq. (3) ``E[x] = Σ π s``: ``ParticleFilter.estimate``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from trackreplay.trackers.filters.particles import (Likelihood, ParticleFilter, Transition, constant_velocity, linear_gaussian,
                                                   squared_deviations)
from trackreplay.trackers.geometry.homography import apply_homography, transfer_velocities
from trackreplay.trackers.golf.config import ParticleConfig

DIM = 4  # x, y, vx, vy
F = constant_velocity(2)
SQRT_2PI = float(np.sqrt(2.0 * np.pi))


def state(position: np.ndarray, velocity: np.ndarray | None = None) -> np.ndarray:
    """``(x, y, vx, vy)`` from a position (velocity 0 unless given)."""
    s = np.zeros(DIM)
    s[:2] = position
    if velocity is not None:
        s[2:] = velocity
    return s


def spread_sigma(position: float | np.ndarray, velocity: float) -> np.ndarray:
    """Per-component standard deviations ``(px, py, v, v)`` for ``ParticleFilter.initialise``."""
    sig = np.empty(DIM)
    sig[:2] = position
    sig[2:] = velocity
    return sig


def motion(cfg: ParticleConfig, scale: float, *, damp: bool, steps: int, followed: bool = False) -> Transition:
    """Eq. (1) over ``steps`` frames (1 = the next frame), with velocity damping after a miss
    (``damp``), else, when an operator's camera follows the ball (``followed``), the mixed state's
    stopping share: the image velocity is then the operator's error, which stops or turns as the
    operator catches up. Not in a fixed view (the image velocity is the ball's own, and a stop
    hypothesis there would favour the scenery), nor after a miss (the damping slows the samples
    already, and a ball struck from rest must not be held back)."""
    root = math.sqrt(steps)
    noise = linear_gaussian(F, np.array([cfg.noise_pos_px * scale * root] * 2 + [cfg.noise_vel_px * scale * root] * 2))

    def transition(particles: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        particles = particles.copy()
        if cfg.stop_share > 0 and followed and not damp:  # mixed state: these samples bet that the ball stopped in the image this frame
            particles[rng.random(len(particles)) < cfg.stop_share, 2:] = 0.0
        if damp:
            particles[:, 2:] *= cfg.miss_velocity_damping
        if steps > 1:  # dropped frames: constant velocity over the gap
            particles[:, :2] += (steps - 1) * particles[:, 2:]
        return noise(particles, rng)

    return transition


def launch(sigma: float) -> Transition:
    """The ball was struck during the last (missed) frame: velocities spread by ``sigma`` px/frame,
    positions by the step such a velocity made in that frame."""

    def transition(particles: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        kick = rng.standard_normal((len(particles), 2)) * sigma
        out = particles.copy()
        out[:, 2:] += kick
        out[:, :2] += kick
        return out

    return transition


def warp(particles: np.ndarray, H: np.ndarray) -> np.ndarray:
    """Samples moved through the pose-change homography ``H`` (positions, and velocities as the
    difference of the images of ``p`` and ``p + v``): a camera that rotates or zooms."""
    p, v = transfer_velocities(H, particles[:, :2], particles[:, 2:])
    return np.concatenate([p, v], axis=1)


def with_camera_motion(velocity: tuple[float, float], position: tuple[float, float], H: np.ndarray) -> tuple[float, float]:
    """An image velocity of samples that live in camera-independent directions (camera motion
    compensated by the pose-change homography ``H``, previous -> this pose), plus the camera's own motion."""
    before = apply_homography(np.linalg.inv(H), np.array([position]))[0]
    return velocity[0] + position[0] - float(before[0]), velocity[1] + position[1] - float(before[1])


def likelihood(candidates: np.ndarray, sigma: float, alpha: float) -> Likelihood:
    """Eq. (2), unnormalised, of each particle's position against the candidates ``(M, 2)``."""
    candidates = np.asarray(candidates, dtype=np.float64).reshape(-1, 2)

    def weigh(particles: np.ndarray) -> np.ndarray:
        if len(candidates) == 1:  # the usual single candidate: a sum over one column is that column
            return _single(particles, candidates[0], sigma, alpha)
        out = np.full(len(particles), alpha, dtype=np.float64)
        if len(candidates):
            # d² = dx² + dy² (what summing the last axis of the squared differences adds, without the reduction)
            d2 = (particles[:, 0:1] - candidates[None, :, 0]) ** 2 + (particles[:, 1:2] - candidates[None, :, 1]) ** 2
            out += np.exp(-d2 / (2.0 * sigma * sigma)).sum(axis=1) / (SQRT_2PI * sigma)
        return out

    return weigh


def _single(particles: np.ndarray, candidate: np.ndarray, sigma: float, alpha: float) -> np.ndarray:
    """Eq. (2) against one candidate, ``alpha + exp(-d² / 2σ²) / (√(2π) σ)``, in one buffer: the
    operations of the plain form (``(x - cx) ** 2`` is ``np.square``, ``alpha + t`` is ``t + alpha``),
    without its eight temporary arrays."""
    cx, cy = candidate
    d2 = particles[:, 0] - cx
    np.square(d2, out=d2)
    dy = particles[:, 1] - cy
    np.square(dy, out=dy)
    d2 += dy
    np.negative(d2, out=d2)
    d2 /= 2.0 * sigma * sigma
    np.exp(d2, out=d2)
    d2 /= SQRT_2PI * sigma
    d2 += alpha
    return d2


@dataclass(frozen=True, eq=False)
class ParticleSet:
    """The CONDENSATION stage's intermediates: the weighted samples after the measurement."""

    particles: np.ndarray  # (N, 4) x, y, vx, vy
    weights: np.ndarray  # (N,) eq. (2), normalised
    estimate: np.ndarray  # (4,) eq. (3)

    @classmethod
    def empty(cls) -> ParticleSet:
        return cls(np.zeros((0, DIM)), np.zeros(0), np.full(DIM, np.nan))


class SampleMoments:
    """The samples' weighted moments and estimate (eq. (3)), each computed once per set of samples:
    the search region, the apparent motion, the injection and the re-initialisation all ask, and
    a set of samples is new whenever the filter replaces its particles or weights."""

    def __init__(self, pf: ParticleFilter) -> None:
        self.pf = pf
        self._moments: tuple = (None, None, {})  # particles, weights, {first component: (mean, spread)}
        self._estimate: tuple = (None, None, None)  # particles, weights, estimate

    def moments(self, first: int) -> tuple[np.ndarray, np.ndarray]:
        """Weighted mean and spread of components ``first``, ``first + 1`` (positions: 0, velocities:
        2), as ``weights @ particles[:, first:first + 2]`` and ``ParticleFilter.spread`` compute them."""
        particles, weights = self.pf.particles, self.pf.weights
        if self._moments[0] is not particles or self._moments[1] is not weights:
            self._moments = (particles, weights, {})
        known = self._moments[2]
        out = known.get(first)
        if out is None:
            p = particles[:, first:first + 2]
            mean = weights @ p
            out = known[first] = (mean, np.sqrt(np.maximum(weights @ squared_deviations(p, mean), 0.0)))
        return out

    def estimate(self) -> np.ndarray:
        """``ParticleFilter.estimate`` (eq. (3)), a copy (the caller may keep it)."""
        pf = self.pf
        if self._estimate[0] is not pf.particles or self._estimate[1] is not pf.weights:
            self._estimate = (pf.particles, pf.weights, pf.estimate())
        return self._estimate[2].copy()
