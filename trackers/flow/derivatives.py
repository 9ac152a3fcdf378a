"""Beaudet-type derivative operators (Beaudet 1978, ref. 22 of the paper; §3.1 error source (1)).

A polynomial surface of total degree ``order`` is fitted by least squares to each ``size``×``size``
window; the fitted surface's value and slopes at the window centre are linear in the pixels, so
they are correlation kernels. The kernels are solved with exact rational arithmetic: they do not
depend on the machine's floating point, and they differentiate polynomials up to ``order`` exactly.

Spatial derivatives are taken on the mean of the two frames: the gradient then belongs to the
half-way instant that ``E_t`` (a two-frame difference) also describes, which cancels the first-order
error term of the constraint ``E_x u + E_y v + E_t = 0`` (eq. 3) when the gradient changes
between frames. ``E_t`` is the difference image passed through the same fit (its centre value),
so all three derivatives share one 5×5 support.
"""

from __future__ import annotations

from fractions import Fraction
from functools import lru_cache

import cv2
import numpy as np


def _monomials(order: int) -> list[tuple[int, int]]:
    return [(i, d - i) for d in range(order + 1) for i in range(d, -1, -1)]


def _solve_exact(a: list[list[Fraction]], b: list[list[Fraction]]) -> list[list[Fraction]]:
    """Gauss–Jordan elimination of ``a x = b`` over the rationals (``a`` square, invertible)."""
    n = len(a)
    m = [row[:] + rhs[:] for row, rhs in zip(a, b)]
    for col in range(n):
        pivot = next(r for r in range(col, n) if m[r][col] != 0)
        m[col], m[pivot] = m[pivot], m[col]
        p = m[col][col]
        m[col] = [v / p for v in m[col]]
        for r in range(n):
            if r != col and m[r][col] != 0:
                f = m[r][col]
                m[r] = [vr - f * vc for vr, vc in zip(m[r], m[col])]
    return [row[n:] for row in m]


@lru_cache(maxsize=None)
def beaudet_kernels(size: int = 5, order: int = 3) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(smooth, d/dx, d/dy)`` correlation kernels (float64, ``size``×``size``) of the LS surface fit.

    Rows index y (down), columns x (right); ``d/dx`` applied with ``cv2.filter2D`` gives the
    slope in grey levels per pixel towards +x.
    """
    if size < 3 or size % 2 == 0:
        raise ValueError(f"derivative window must be odd and >= 3, not {size}")
    if order not in (1, 2, 3) or len(_monomials(order)) > size * size:
        raise ValueError(f"surface order must be 1, 2 or 3 and fit in the window, not {order}")
    r = size // 2
    coords = [(x, y) for y in range(-r, r + 1) for x in range(-r, r + 1)]
    mons = _monomials(order)
    design = [[Fraction(x**i * y**j) for i, j in mons] for x, y in coords]
    normal = [[sum((row[p] * row[q] for row in design), Fraction(0)) for q in range(len(mons))] for p in range(len(mons))]
    # (AᵀA)⁻¹Aᵀ: row k maps the window's pixels to the k-th coefficient of the fitted surface
    pinv = _solve_exact(normal, [[row[p] for row in design] for p in range(len(mons))])
    out = []
    for mon in ((0, 0), (1, 0), (0, 1)):
        k = mons.index(mon)
        out.append(np.array([float(v) for v in pinv[k]], dtype=np.float64).reshape(size, size))
    for kernel in out:
        kernel.setflags(write=False)
    return out[0], out[1], out[2]


@lru_cache(maxsize=None)
def _kernels32(size: int, order: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The kernels as float32 (what ``cv2.filter2D`` is given), converted once."""
    out = tuple(k.astype(np.float32) for k in beaudet_kernels(size, order))
    for kernel in out:
        kernel.setflags(write=False)
    return out


def _apply(image: np.ndarray, kernel: np.ndarray) -> np.ndarray:
    return cv2.filter2D(image, cv2.CV_32F, kernel.astype(np.float32, copy=False), borderType=cv2.BORDER_REPLICATE)


def spatial_gradient(image: np.ndarray, size: int = 5, order: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """``(E_x, E_y)`` of one float32 image with the Beaudet operator (eq. 4)."""
    _, kx, ky = _kernels32(size, order)
    image = np.asarray(image, dtype=np.float32)
    return _apply(image, kx), _apply(image, ky)


def derivatives(e0: np.ndarray, e1: np.ndarray, size: int = 5, order: int = 3) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(E_x, E_y, E_t)`` between two float32 frames one time unit apart (eq. 3–4).

    ``E_x, E_y`` on the frames' mean; ``E_t = S * (e1 - e0)`` with ``S`` the fit's smoothing kernel.
    """
    smooth, kx, ky = _kernels32(size, order)
    e0 = np.asarray(e0, dtype=np.float32)
    e1 = np.asarray(e1, dtype=np.float32)
    mean = e0 + e1
    mean *= np.float32(0.5)
    return _apply(mean, kx), _apply(mean, ky), _apply(e1 - e0, smooth)
