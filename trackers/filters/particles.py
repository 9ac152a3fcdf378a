"""A particle filter over any state dimension (CONDENSATION: select, predict, measure, estimate).

The transition and the likelihood are passed in per call, so a tracker states its own motion and
observation models and this module only keeps the weighted particle set. Every random draw comes
from the Generator the tracker was given; nothing touches numpy's global RNG. Vectorised over the
particles: no Python loop over them.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

Transition = Callable[[np.ndarray, np.random.Generator], np.ndarray]  # (N, D) particles -> (N, D)
Likelihood = Callable[[np.ndarray], np.ndarray]  # (N, D) particles -> (N,) unnormalised weights


def systematic_resample(weights: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Indices by systematic resampling: one offset ``u ~ U[0, 1/N)``, N evenly spaced pointers."""
    n = len(weights)
    cumulative = np.cumsum(weights)
    cumulative /= cumulative[-1]
    cumulative[-1] = 1.0
    pointers = (rng.random() + np.arange(n)) / n
    return np.minimum(np.searchsorted(cumulative, pointers, side="right"), n - 1)


def squared_deviations(p: np.ndarray, mean: np.ndarray) -> np.ndarray:
    """``(p - mean) ** 2`` for ``(N, D)`` samples ``p``, column by column: the same floats in the same
    (C-ordered) layout as the broadcast, without its slow inner loop of D elements per row."""
    if p.ndim != 2 or p.strides[1] > p.strides[0]:  # not row-major: numpy's result would follow that layout
        return (p - mean) ** 2
    out = np.empty(p.shape)
    for j in range(p.shape[1]):
        np.subtract(p[:, j], mean[j], out=out[:, j])
    return np.square(out, out=out)


def linear_gaussian(F: np.ndarray, sigma: np.ndarray | float) -> Transition:
    """``s = F s' + w``, ``w ~ N(0, diag(sigma)²)`` (e.g. constant velocity)."""
    F = np.asarray(F, dtype=np.float64)
    sigma = np.asarray(sigma, dtype=np.float64)

    def transition(particles: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        noise = rng.standard_normal(particles.shape) * sigma
        return particles @ F.T + noise

    return transition


def constant_velocity(dims: int, dt: float = 1.0) -> np.ndarray:
    """``F`` for a state ``(p_1 … p_dims, v_1 … v_dims)``: ``p += dt v``."""
    F = np.eye(2 * dims)
    F[:dims, dims:] = dt * np.eye(dims)
    return F


class ParticleFilter:
    """N weighted particles of dimension D; the Generator is the caller's."""

    def __init__(self, n: int, dim: int, rng: np.random.Generator) -> None:
        if n < 1 or dim < 1:
            raise ValueError(f"a particle filter needs n >= 1 and dim >= 1, not n={n}, dim={dim}")
        self.n = n
        self.dim = dim
        self.rng = rng
        self.particles = np.zeros((n, dim))
        self.weights = np.full(n, 1.0 / n)

    def initialise(self, mean: np.ndarray, sigma: np.ndarray | float) -> None:
        """Particles ``mean + N(0, diag(sigma)²)`` with uniform weights."""
        self.particles = np.asarray(mean, dtype=np.float64) + self.rng.standard_normal((self.n, self.dim)) * sigma
        self.weights = np.full(self.n, 1.0 / self.n)

    def inject(self, share: float, mean: np.ndarray, sigma: np.ndarray | float) -> np.ndarray:
        """Replace about ``share`` of the particles (a random subset) by draws ``mean + N(0,
        diag(sigma)²)`` with the mean weight (ICONDENSATION's importance samples from a detection,
        without the prior/importance weight correction); returns the replaced rows' mask."""
        chosen = self.rng.random(self.n) < share
        k = int(chosen.sum())
        if k:
            self.particles = self.particles.copy()
            self.particles[chosen] = np.asarray(mean, dtype=np.float64) + self.rng.standard_normal((k, self.dim)) * sigma
            self.weights = self.weights.copy()
            self.weights[chosen] = float(self.weights.sum()) / len(self.weights)  # np.mean's sum / count, without its overhead
            self.weights /= self.weights.sum()
        return chosen

    def resample(self) -> None:
        """Selection: draw N particles by weight (systematic); weights become uniform."""
        # ``take`` gathers the same rows as ``particles[indices]``, several times faster for (N, D) rows
        self.particles = self.particles.take(systematic_resample(self.weights, self.rng), axis=0)
        self.weights = np.full(self.n, 1.0 / self.n)

    def predict(self, transition: Transition) -> None:
        self.particles = transition(self.particles, self.rng)

    def weigh(self, likelihood: Likelihood) -> np.ndarray:
        """Weights ∝ previous weight × likelihood, normalised; returns the raw likelihoods.

        When every likelihood is zero (nothing explains any particle) the weights stay as they
        were rather than dividing by zero.
        """
        lik = np.asarray(likelihood(self.particles), dtype=np.float64)
        weighted = self.weights * lik
        total = weighted.sum()
        if total > 0 and math.isfinite(total):
            weighted /= total  # a new array: the old weights may be kept (intermediates)
            self.weights = weighted
        return lik

    def estimate(self) -> np.ndarray:
        """Weighted mean ``E[s] = Σ π s``."""
        return self.weights @ self.particles

    def spread(self, dims: slice | np.ndarray = slice(None)) -> np.ndarray:
        """Weighted standard deviation of the chosen state components."""
        p = self.particles[:, dims]
        mean = self.weights @ p
        return np.sqrt(np.maximum(self.weights @ squared_deviations(p, mean), 0.0))

    def effective_size(self) -> float:
        """``1 / Σ π²``: N for uniform weights, 1 when one particle holds all the weight."""
        return float(1.0 / np.sum(self.weights**2))
