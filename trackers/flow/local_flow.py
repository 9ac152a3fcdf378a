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
        zero = np.float32(0.0)
        return (np.where(self.valid, self.u, zero).astype(np.float32, copy=False),
                np.where(self.valid, self.v, zero).astype(np.float32, copy=False))

    @staticmethod
    def zeros(shape: tuple[int, int]) -> FlowField:
        nan = np.full(shape, np.nan, np.float32)
        return FlowField(nan, nan.copy(), np.zeros(shape, bool), nan.copy())


def _box(a: np.ndarray, n: int) -> np.ndarray:
    # the neighbourhood mean: the same weight for each of the m equations, as in plain least squares
    return cv2.boxFilter(a, cv2.CV_32F, (n, n), normalize=True, borderType=cv2.BORDER_REPLICATE).astype(np.float64)


def normal_equations(ex: np.ndarray, ey: np.ndarray, et: np.ndarray, n: int) -> tuple[np.ndarray, ...]:
    """Per-pixel ``(a, b, c, p, q)`` with ``GᵀG/m = [[a, b], [b, c]]`` and ``Gᵀb/m = [p, q]``.

    The five products are box-filtered as the channels of one image: OpenCV filters each channel
    with the same sums as a one-channel image, in one call instead of five.
    """
    if not all(isinstance(x, np.ndarray) and x.dtype == np.float32 and x.ndim == 2 for x in (ex, ey, et)):
        return (_box(ex * ex, n), _box(ex * ey, n), _box(ey * ey, n), _box(ex * et, n), _box(ey * et, n))
    products = np.empty(ex.shape + (5,), np.float32)  # pixel-interleaved: OpenCV's 5-channel layout
    np.multiply(ex, ex, out=products[..., 0])
    np.multiply(ex, ey, out=products[..., 1])
    np.multiply(ey, ey, out=products[..., 2])
    np.multiply(ex, et, out=products[..., 3])
    np.multiply(ey, et, out=products[..., 4])
    sums = cv2.boxFilter(products, cv2.CV_32F, (n, n), normalize=True, borderType=cv2.BORDER_REPLICATE)
    sums = sums.transpose(2, 0, 1).astype(np.float64)  # channel-major: each of a … q contiguous
    return sums[0], sums[1], sums[2], sums[3], sums[4]


def condition_number(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """cond₂(G) = sqrt(λmax/λmin) of ``GᵀG`` (eq. 8 with the 2-norm); ``inf`` when singular."""
    return _condition(a, b, c, 0.5 * (a + c))


def _condition(a: np.ndarray, b: np.ndarray, c: np.ndarray, half_trace: np.ndarray) -> np.ndarray:
    """:func:`condition_number` given ``0.5 (a + c)``: λ = half_trace ± sqrt(((a − c)/2)² + b²);
    the ratio is taken only where λmin > 0 (elsewhere, and where it is not finite, ``inf``)."""
    d = np.asarray(a - c)
    root = np.square(d, out=d)
    root *= 0.25
    root += b * b
    root = np.sqrt(root, out=root)
    lmax = half_trace + root
    lmin = np.subtract(half_trace, root, out=root)
    positive = lmin > 0
    cond = np.full(np.shape(lmin), np.inf)
    np.divide(lmax, lmin, out=cond, where=positive)
    np.sqrt(cond, out=cond)
    cond[np.isnan(cond)] = np.inf  # a NaN ratio is not finite: inf, as for λmin <= 0
    return cond


def local_flow(ex: np.ndarray, ey: np.ndarray, et: np.ndarray, n: int, cond_max: float, min_energy: float) -> FlowField:
    """Least-squares flow per pixel (eq. 7), rejected where cond(G) > ``cond_max`` (eq. 8).

    ``min_energy`` rejects neighbourhoods whose mean squared gradient ``(E_x² + E_y²)`` is below it:
    there cond(G) may be small yet the gradient is noise and the flow meaningless.
    """
    if n not in (3, 5, 7):
        raise ValueError(f"neighbourhood must be 3, 5 or 7, not {n}")
    a, b, c, p, q = normal_equations(ex, ey, et, n)
    trace = a + c
    cond = _condition(a, b, c, 0.5 * trace)
    valid = cond <= cond_max
    valid &= trace >= min_energy
    invalid = ~valid
    # ŵ = −(GᵀG)⁻¹Gᵀb (eq. 7) in closed form; dividing by −det is negating the quotient, exactly
    neg_det = b * b
    neg_det -= a * c
    np.copyto(neg_det, -1.0, where=invalid)
    nan = np.float32(np.nan)
    u = c * p
    u -= b * q
    u /= neg_det
    u = u.astype(np.float32)
    np.copyto(u, nan, where=invalid)
    v = a * q
    v -= b * p
    v /= neg_det
    v = v.astype(np.float32)
    np.copyto(v, nan, where=invalid)
    return FlowField(u, v, valid, cond.astype(np.float32))
