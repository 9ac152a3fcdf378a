"""Local-optimisation gradient flow: least squares over an n×n neighbourhood (eq. 5–8).

For each pixel the m = n² constraints ``G w + b = 0`` of its neighbourhood (eq. 5) are solved as
``ŵ = −(GᵀG)⁻¹Gᵀb`` (eq. 7). ``GᵀG`` and ``Gᵀb`` are neighbourhood sums of ``E_x², E_xE_y, E_y²,
E_xE_t, E_yE_t``, so box filters give them for every pixel at once and the 2×2 inverse is closed
form. The sign: eq. 7 as printed drops the minus that eq. 5 implies.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np


@dataclass(frozen=True, eq=False)
class FlowField:
    """Dense flow in px/frame; ``u, v`` are NaN where ``valid`` is False; ``cond`` is cond₂(G) (eq. 8).

    ``residual`` (RMS grey levels of the two frames aligned by the flow, eq. 10) and
    ``iterations`` (accepted refinements) are filled in by the refinement.
    """

    u: np.ndarray
    v: np.ndarray
    valid: np.ndarray
    cond: np.ndarray
    residual: float = float("nan")
    iterations: int = 0

    @property
    def shape(self) -> tuple[int, int]:
        return self.u.shape

    def filled(self) -> tuple[np.ndarray, np.ndarray]:
        """``(u, v)`` with rejected pixels set to 0 (a warm start or a warp needs finite values)."""
        return np.where(self.valid, self.u, 0.0).astype(np.float32), np.where(self.valid, self.v, 0.0).astype(np.float32)

    @staticmethod
    def zeros(shape: tuple[int, int]) -> FlowField:
        nan = np.full(shape, np.nan, np.float32)
        return FlowField(nan, nan.copy(), np.zeros(shape, bool), nan.copy())


def _box(a: np.ndarray, n: int) -> np.ndarray:
    # the neighbourhood mean: the same weight for each of the m equations, as in plain least squares
    return cv2.boxFilter(a, cv2.CV_32F, (n, n), normalize=True, borderType=cv2.BORDER_REPLICATE).astype(np.float64)


def normal_equations(ex: np.ndarray, ey: np.ndarray, et: np.ndarray, n: int) -> tuple[np.ndarray, ...]:
    """Per-pixel ``(a, b, c, p, q)`` with ``GᵀG/m = [[a, b], [b, c]]`` and ``Gᵀb/m = [p, q]``."""
    return (_box(ex * ex, n), _box(ex * ey, n), _box(ey * ey, n), _box(ex * et, n), _box(ey * et, n))


def condition_number(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """cond₂(G) = sqrt(λmax/λmin) of ``GᵀG`` (eq. 8 with the 2-norm); ``inf`` when singular."""
    half_trace = 0.5 * (a + c)
    root = np.sqrt(0.25 * (a - c) ** 2 + b * b)
    lmax = half_trace + root
    lmin = half_trace - root
    with np.errstate(divide="ignore", invalid="ignore"):
        cond = np.sqrt(lmax / lmin)
    return np.where((lmin > 0) & np.isfinite(cond), cond, np.inf)


def local_flow(ex: np.ndarray, ey: np.ndarray, et: np.ndarray, n: int, cond_max: float, min_energy: float) -> FlowField:
    """Least-squares flow per pixel (eq. 7), rejected where cond(G) > ``cond_max`` (eq. 8).

    ``min_energy`` rejects neighbourhoods whose mean squared gradient ``(E_x² + E_y²)`` is below it:
    there cond(G) may be small yet the gradient is noise and the flow meaningless.
    """
    if n not in (3, 5, 7):
        raise ValueError(f"neighbourhood must be 3, 5 or 7, not {n}")
    a, b, c, p, q = normal_equations(ex, ey, et, n)
    cond = condition_number(a, b, c)
    valid = (cond <= cond_max) & ((a + c) >= min_energy)
    det = np.where(valid, a * c - b * b, 1.0)
    u = np.where(valid, -(c * p - b * q) / det, np.nan).astype(np.float32)
    v = np.where(valid, -(a * q - b * p) / det, np.nan).astype(np.float32)
    return FlowField(u, v, valid, cond.astype(np.float32))
