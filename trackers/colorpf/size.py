"""Box area from the distance to the target, §4.1 eq. (9): weak perspective ``S' = f² (S + ω_S) / Z²``.

``S`` is fixed at initialisation from the marked box's area ``S'_0`` at the known distance ``Z_0``:
``S = S'_0 Z_0² / f²``, so ``S' = S'_0 (Z_0 / Z)² (1 + ω)`` with ``ω ~ N(0, r_S)`` (relative, as docs/papers.md §3
states r_S; the paper's "standard deviation r_S" of ``ω_S`` relative to ``S``): ``f`` cancels and
the log's ground plane needs no focal length.

``Z`` is the distance from the camera to the target's foot point on the ground (the box's bottom
centre through the image -> ground homography). The paper's ``Z`` is the depth along the optical
axis; the two differ by the cosine of the angle off the axis, which changes little along a walk
(within a few per cent for targets within 20 degrees of the axis). Without a ground plane the
distance is taken as constant: ``S'`` stays at ``S'_0`` (1 + ω).
"""

from __future__ import annotations

import numpy as np

from trackreplay.trackers.geometry.ground_plane import GroundPlane


def object_area(area_image: float, distance: float) -> float:
    """``S`` of eq. (9) in units of ``f²``: ``S' Z²``."""
    return float(area_image) * float(distance) ** 2


def image_area(S: float, distance: np.ndarray, omega: np.ndarray | float = 0.0) -> np.ndarray:
    """Eq. (9), ``f = 1``: ``S' = S (1 + ω) / Z²`` (ω relative to S)."""
    return S * (1.0 + np.asarray(omega, dtype=np.float64)) / np.asarray(distance, dtype=np.float64) ** 2


def foot_points(xy: np.ndarray, h: float | np.ndarray) -> np.ndarray:
    """(N, 2) bottom centres of boxes centred at ``xy`` with height ``h``: where the target stands."""
    xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    return np.stack([xy[:, 0], xy[:, 1] + 0.5 * np.asarray(h, dtype=np.float64)], axis=1)


def ground_distance(plane: GroundPlane | None, feet: np.ndarray, side: float = 0.0) -> np.ndarray:
    """Camera-to-foot distance per point (m); NaN without a plane.

    With ``side`` (the sign of the homogeneous scale ``(H [u v 1])_3`` at a point known to be on
    the ground, e.g. the marked foot), points on the other side of the horizon (which map behind the
    camera) are NaN too.
    """
    feet = np.asarray(feet, dtype=np.float64).reshape(-1, 2)
    if plane is None:
        return np.full(len(feet), np.nan)
    d = plane.distance(feet)
    ok = np.isfinite(d)
    if side:
        ok &= np.sign(horizon_side(plane, feet)) == np.sign(side)
    return np.where(ok, d, np.nan)


def horizon_side(plane: GroundPlane, points: np.ndarray) -> np.ndarray:
    """``(H [u v 1])_3`` per point: its sign flips at the horizon."""
    H = plane.image_to_ground
    return np.asarray(points, dtype=np.float64).reshape(-1, 2) @ H[2, :2] + H[2, 2]


def region_area(area: float, region_wh: np.ndarray, rate: float) -> float:
    """``refine.size_follows = "area"``: without a ground plane, ``S'`` (the size state, eq. (9) with
    ``Z = Z_0``) moved ``rate`` of the way to the area of the foreground region's box ``(w_r, h_r)``.
    From ``S'`` itself, not from the PF's weighted-mean box (which carries that frame's colour-weighted
    ``omega``: fed back, the state would random-walk); the region's aspect is not used (see
    ``RefineConfig.size_follows``)."""
    w, h = (float(v) for v in np.asarray(region_wh, dtype=np.float64)[:2])
    return (1.0 - rate) * float(area) + rate * w * h


class WeakPerspectiveSize:
    """``S`` fixed at the mark; per particle ``S'`` from its own foot point's distance (eq. 9)."""

    def __init__(self, r_s: float, area0: float, distance0: float) -> None:
        self.r_s = r_s
        self.area0 = float(area0)
        self.distance0 = float(distance0) if np.isfinite(distance0) and distance0 > 0 else np.nan
        self.S = object_area(area0, self.distance0) if np.isfinite(self.distance0) else np.nan

    @property
    def has_distance(self) -> bool:
        return bool(np.isfinite(self.S))

    def areas_for(self, distance: np.ndarray, omega: np.ndarray | float = 0.0) -> np.ndarray:
        """``S'`` per distance for given ``ω`` (relative to S); NaN distance: ``S'_0``."""
        distance = np.asarray(distance, dtype=np.float64)
        scale = np.maximum(1.0 + np.asarray(omega, dtype=np.float64), 0.1)
        if not self.has_distance:
            return self.area0 * scale * np.ones_like(distance)
        ok = np.isfinite(distance)
        return np.where(ok, self.S / np.where(ok, distance, 1.0) ** 2, self.area0) * scale

    def areas(self, distance: np.ndarray, rng: np.random.Generator | None) -> np.ndarray:
        """``S'`` per distance, with ``ω ~ N(0, r_S)`` drawn from ``rng`` (None: ω = 0).

        A NaN distance (no plane, or a foot above the horizon) keeps the initial area ``S'_0``;
        ``1 + ω`` is kept above 0.1 (a 4.5-sigma draw at r_S = 0.2 would make it negative).
        """
        distance = np.asarray(distance, dtype=np.float64)
        omega = 0.0 if rng is None else rng.standard_normal(distance.shape) * self.r_s
        scale = np.maximum(1.0 + omega, 0.1)
        if not self.has_distance:
            return self.area0 * scale * np.ones_like(distance)
        base = np.where(np.isfinite(distance), self.S / np.where(np.isfinite(distance), distance, 1.0) ** 2, self.area0)
        return base * scale
