"""CONDENSATION over the ball's image position and velocity (seed 000, §2.2, eq. (1)-(3)).

State ``s = (x, y, vx, vy)`` in frame pixels and pixels per frame; N weighted samples.
Each frame: *select* (systematic resampling by weight, one uniform draw from the engine's
Generator and ``searchsorted``), *predict* ``s = F s' + G w`` with constant-velocity ``F`` and
Gaussian ``w`` (eq. (1)), *measure* ``pi ∝ alpha + 1/(sqrt(2 pi) sigma) sum_m exp(-d_m^2 / 2 sigma^2)``
over the M candidate centroids (eq. (2)), normalise, and estimate ``E[x] = sum pi s`` (eq. (3)).
Everything is vectorised over the N samples; nothing draws from numpy's global RNG.
"""

from __future__ import annotations

import numpy as np

F = np.array([[1.0, 0.0, 1.0, 0.0], [0.0, 1.0, 0.0, 1.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]])
SQRT_2PI = float(np.sqrt(2.0 * np.pi))


def systematic_resample(weights: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Indices drawn by systematic resampling: one offset ``u ~ U[0, 1/N)``, N evenly spaced pointers."""
    n = len(weights)
    cumulative = np.cumsum(weights)
    cumulative /= cumulative[-1]
    cumulative[-1] = 1.0
    pointers = (rng.random() + np.arange(n)) / n
    return np.minimum(np.searchsorted(cumulative, pointers, side="right"), n - 1)


def likelihood(positions: np.ndarray, candidates: np.ndarray, sigma: float, alpha: float) -> np.ndarray:
    """Eq. (2), unnormalised, for every sample position ``(N, 2)`` against candidates ``(M, 2)``."""
    out = np.full(len(positions), alpha, dtype=np.float64)
    if len(candidates):
        d2 = ((positions[:, None, :] - candidates[None, :, :]) ** 2).sum(axis=2)
        out += np.exp(-d2 / (2.0 * sigma * sigma)).sum(axis=1) / (SQRT_2PI * sigma)
    return out


def warp_states(states: np.ndarray, H: np.ndarray) -> np.ndarray:
    """Move samples through the image homography ``H`` (a pure camera rotation/zoom).

    Positions map through ``H``; a velocity maps as the difference of the images of ``p`` and
    ``p + v``, so it is expressed in the new pose's pixels.
    """
    def apply(p: np.ndarray) -> np.ndarray:
        q = p @ H[:, :2].T + H[:, 2]
        return q[:, :2] / q[:, 2:3]

    p = states[:, :2]
    p2 = apply(p)
    v2 = apply(p + states[:, 2:4]) - p2
    return np.concatenate([p2, v2], axis=1)


class CondensationFilter:
    """N weighted samples of ``(x, y, vx, vy)``; the Generator is the engine's, passed in."""

    def __init__(self, n: int, rng: np.random.Generator) -> None:
        self.n = n
        self.rng = rng
        self.s = np.zeros((n, 4))
        self.w = np.full(n, 1.0 / n)

    def initialise(self, mean: np.ndarray, pos_sigma: float | np.ndarray, vel_sigma: float) -> None:
        """Samples around ``mean`` = (x, y[, vx, vy]) with uniform weights (§2.3)."""
        m = np.zeros(4)
        m[: len(mean)] = mean
        sig = np.empty(4)
        sig[:2] = pos_sigma
        sig[2:] = vel_sigma
        self.s = m + self.rng.standard_normal((self.n, 4)) * sig
        self.w = np.full(self.n, 1.0 / self.n)

    def select(self) -> None:
        """Selection step: resample N times by weight; weights become uniform."""
        self.s = self.s[systematic_resample(self.w, self.rng)]
        self.w = np.full(self.n, 1.0 / self.n)

    def warp(self, H: np.ndarray) -> None:
        self.s = warp_states(self.s, H)

    def predict(self, pos_sigma: float, vel_sigma: float) -> None:
        """Eq. (1): ``s = F s' + G w``, G = I, w ~ N(0, diag(pos, pos, vel, vel)^2)."""
        noise = self.rng.standard_normal((self.n, 4)) * np.array([pos_sigma, pos_sigma, vel_sigma, vel_sigma])
        self.s = self.s @ F.T + noise

    def measure(self, candidates: np.ndarray, sigma: float, alpha: float) -> None:
        """Eq. (2) then normalisation. With no candidate (and alpha > 0) the weights stay uniform."""
        lik = likelihood(self.s[:, :2], np.asarray(candidates, dtype=np.float64).reshape(-1, 2), sigma, alpha)
        total = lik.sum()
        self.w = lik / total if total > 0 else np.full(self.n, 1.0 / self.n)

    def estimate(self) -> np.ndarray:
        """Eq. (3): the weighted mean ``(x, y, vx, vy)``."""
        return self.w @ self.s

    def spread(self) -> np.ndarray:
        """Weighted standard deviation of x and y (sets the search region's size and aspect)."""
        mean = self.w @ self.s[:, :2]
        return np.sqrt(np.maximum(self.w @ (self.s[:, :2] - mean) ** 2, 0.0))
