"""Things that hide the ball for a while (the long-occlusion variant), as analytic coverage of rays.

- ``Tree``: while the ball is in the air, a tree between the camera and the ball's path; its crown
  is a chain of spheres along the ball's lines of sight during the window, the trunk stands beside
  the path as seen from the camera.
- ``Walker``: while the ball is on or near the ground (rolling, or hopping lower than the camera),
  a spectator with an umbrella walks into the shot, stays on the ball's line of sight for the
  window and walks out again (a ball rolling away from the camera barely moves in the image, so a
  fixed object would hide it for good).

Both give per-ray coverage in [0, 1] with a soft edge one pixel wide, for the renderer (which rays
of the image are covered) and for the ground truth (is the ray to the ball covered). Only the
frames' time and pose matter, so the two always agree.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Protocol

import numpy as np

BARK = (52.0, 62.0, 74.0)
LEAVES = (30.0, 72.0, 40.0)
SHIRT = (120.0, 52.0, 36.0)  # navy, BGR
TROUSERS = (44.0, 44.0, 48.0)
SKIN = (120.0, 150.0, 196.0)
UMBRELLA = (48.0, 40.0, 190.0)  # red
WALKER_AT = 0.7  # the walker stands this fraction of the way from the camera to the ball
UMBRELLA_TOP = 2.4  # m


class Occluder(Protocol):
    window: tuple[float, float]

    def distance(self, camera: np.ndarray, t: float) -> float: ...

    def extent(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Points (N, 3) and radii (N,) that bound the occluder at time ``t``."""
        ...

    def parts(self, camera: np.ndarray, rays: np.ndarray, pixel_angle: float, t: float) -> list[tuple[np.ndarray, tuple[float, float, float], bool]]:
        """(coverage (N,), colour BGR, textured) per part, drawn in this order."""
        ...


def coverage(occ: Occluder, camera: np.ndarray, rays: np.ndarray, pixel_angle: float, t: float) -> np.ndarray:
    out = np.zeros(len(rays), np.float32)
    for cov, _, _ in occ.parts(camera, rays, pixel_angle, t):
        out = np.maximum(out, cov)
    return out


def _cylinder(camera: np.ndarray, rays: np.ndarray, pixel_angle: float, base: np.ndarray, z0: float, z1: float,
              radius: float) -> np.ndarray:
    """Coverage of a vertical cylinder (axis at ``base`` XY, from ``z0`` to ``z1``) seen along unit rays."""
    b = base - camera[:2]
    dh = rays[:, :2]
    h2 = np.maximum((dh * dh).sum(axis=1), 1e-12)
    s = (dh @ b) / h2  # ray parameter of the closest horizontal approach
    perp = np.abs(dh[:, 0] * b[1] - dh[:, 1] * b[0]) / np.sqrt(h2)
    z = camera[2] + s * rays[:, 2]
    rng = np.maximum(s, 1e-6)
    edge = rng * pixel_angle
    side = np.clip((radius - perp) / edge + 0.5, 0.0, 1.0)
    ends = np.clip((z - z0) / edge + 0.5, 0.0, 1.0) * np.clip((z1 - z) / edge + 0.5, 0.0, 1.0)
    return np.where(s > 0, side * ends, 0.0).astype(np.float32)


def _sphere(camera: np.ndarray, rays: np.ndarray, pixel_angle: float, centre: np.ndarray, radius: float,
            rag_phases: np.ndarray | None = None) -> np.ndarray:
    """Coverage of a sphere, optionally with a ragged (leafy) outline."""
    v = centre - camera
    dist = float(np.linalg.norm(v))
    c = v / dist
    alpha = math.asin(min(radius / dist, 0.99))
    out = np.zeros(len(rays), np.float32)
    near = rays @ c > math.cos(min(alpha * 1.4 + 4 * pixel_angle, math.pi / 2))
    if not near.any():
        return out
    r = rays[near]
    theta = np.arccos(np.clip(r @ c, -1.0, 1.0))
    edge = np.full(len(r), alpha)
    if rag_phases is not None:
        e1 = np.cross(c, [0.0, 0.0, 1.0])
        e1 = e1 / (np.linalg.norm(e1) or 1.0)
        e2 = np.cross(e1, c)
        psi = np.arctan2(r @ e2, r @ e1)
        rag = sum(np.sin((j + 3) * psi + ph) / (j + 3) for j, ph in enumerate(rag_phases))
        edge = alpha * (1.0 + 0.25 * rag)
    out[near] = np.clip((edge - theta) / pixel_angle + 0.5, 0.0, 1.0)
    return out


def _dome(camera: np.ndarray, rays: np.ndarray, pixel_angle: float, centre: np.ndarray, radius: float) -> np.ndarray:
    """The upper half of a sphere (an open umbrella seen from the side)."""
    cov = _sphere(camera, rays, pixel_angle, centre, radius)
    s = rays @ (centre - camera)  # ray parameter nearest the centre
    z = camera[2] + s * rays[:, 2]
    return cov * np.clip((z - centre[2]) / (np.maximum(s, 1e-6) * pixel_angle) + 0.5, 0.0, 1.0).astype(np.float32)


@dataclass(frozen=True, eq=False)
class Tree:
    centres: np.ndarray  # (K, 3) crown spheres
    radii: np.ndarray  # (K,)
    trunk_base: np.ndarray | None  # (2,) XY; None for a low bush
    trunk_top: float
    trunk_radius: float
    edge_phases: np.ndarray  # (K, J)
    window: tuple[float, float]
    rho: float  # distance of the crown from the camera, m

    def distance(self, camera: np.ndarray, t: float) -> float:
        return self.rho

    def extent(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        pts, rad = [self.centres], [self.radii * 1.3]
        if self.trunk_base is not None:
            pts.append(np.array([[*self.trunk_base, 0.0], [*self.trunk_base, self.trunk_top]]))
            rad.append(np.full(2, 2.0 * self.trunk_radius))
        return np.vstack(pts), np.concatenate(rad)

    def parts(self, camera, rays, pixel_angle, t):
        crown = np.zeros(len(rays), np.float32)
        for k in range(len(self.radii)):
            crown = np.maximum(crown, _sphere(camera, rays, pixel_angle, self.centres[k], float(self.radii[k]), self.edge_phases[k]))
        out = []
        if self.trunk_base is not None:
            out.append((_cylinder(camera, rays, pixel_angle, self.trunk_base, 0.0, self.trunk_top, self.trunk_radius), BARK, False))
        out.append((crown, LEAVES, True))
        return out


@dataclass(frozen=True, eq=False)
class Walker:
    """A spectator (1.8 m, open umbrella) who walks onto the ball's line of sight, stays for the window, walks off."""

    window: tuple[float, float]
    stations: np.ndarray  # (M, 2) XY on the line of sight at the times below
    times: np.ndarray  # (M,)
    side: np.ndarray  # (2,) unit, the direction the person comes from and leaves to
    speed: float = 1.4  # m/s

    def position(self, t: float) -> np.ndarray:
        start, end = self.window
        tc = min(max(t, start), end)
        p = np.array([np.interp(tc, self.times, self.stations[:, 0]), np.interp(tc, self.times, self.stations[:, 1])])
        if t < start:
            p = p + self.side * self.speed * (start - t)
        elif t > end:
            p = p - self.side * self.speed * (t - end)
        return p

    def distance(self, camera: np.ndarray, t: float) -> float:
        p = self.position(t)
        return float(math.hypot(p[0] - camera[0], p[1] - camera[1]))

    def extent(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        p = self.position(t)
        return np.array([[p[0], p[1], 0.0], [p[0], p[1], 0.9], [p[0], p[1], 1.7]]), np.array([0.5, 0.5, 0.8])

    def parts(self, camera, rays, pixel_angle, t):
        p = self.position(t)
        legs = _cylinder(camera, rays, pixel_angle, p, 0.0, 0.9, 0.2)
        body = _cylinder(camera, rays, pixel_angle, p, 0.88, 1.52, 0.27)
        head = _sphere(camera, rays, pixel_angle, np.array([p[0], p[1], 1.66]), 0.12)
        top = UMBRELLA_TOP - 0.7
        umbrella = _dome(camera, rays, pixel_angle, np.array([p[0], p[1], top]), 0.7)
        pole = _cylinder(camera, rays, pixel_angle, p + 0.2 * self.side, 1.0, top, 0.015)
        return [(legs, TROUSERS, False), (body, SHIRT, False), (head, SKIN, False), (pole, TROUSERS, False),
                (umbrella, UMBRELLA, False)]


def build_tree(rng: np.random.Generator, camera: np.ndarray, ball_at: Callable[[float], np.ndarray],
               window: tuple[float, float], ball_radius: float, max_angular_radius_deg: float = 0.6) -> Tree:
    """A tree whose crown covers the ball's lines of sight during ``window``.

    The crown is trimmed at both ends by half a crown radius, so the ball disappears a little
    before ``start`` and reappears a little after ``end`` (the ground truth says exactly when).
    """
    start, end = window
    times = np.linspace(start, end, max(2, int(math.ceil((end - start) * 120)) + 1))
    rel = np.array([ball_at(t) for t in times]) - camera
    ranges = np.linalg.norm(rel, axis=1)
    dirs = rel / ranges[:, None]
    steps = np.arccos(np.clip((dirs[1:] * dirs[:-1]).sum(axis=1), -1.0, 1.0))
    run = np.concatenate([[0.0], np.cumsum(steps)])  # angle travelled along the path, rad
    length = float(run[-1])
    alpha = float(np.clip(0.35 * length, 4.0 * ball_radius / ranges.min(), math.radians(max_angular_radius_deg)))
    rho = float(np.clip(0.3 * ranges.min(), 3.0, 40.0))
    lo, hi = 0.5 * alpha, length - 0.5 * alpha
    marks = [0.5 * length] if hi <= lo else list(np.linspace(lo, hi, max(2, int(math.ceil((hi - lo) / (0.5 * alpha))) + 1)))
    keep = sorted({int(np.clip(np.searchsorted(run, m), 0, len(run) - 1)) for m in marks})
    centres = [camera + rho * dirs[i] for i in keep]
    radius = rho * math.tan(alpha)
    radii = [radius] * len(centres)
    # Trunk: beside the crown, perpendicular to the path as seen from the camera (down or sideways).
    low = int(np.argmin([c[2] for c in centres]))
    mid = centres[low]
    path = dirs[-1] - dirs[0]
    view = dirs[keep[low]]
    perp = np.cross(view, path) if np.linalg.norm(path) > 1e-9 else np.cross(view, [0.0, 0.0, 1.0])
    perp /= np.linalg.norm(perp) or 1.0
    if perp[2] > 0:
        perp = -perp
    trunk_base, trunk_top = None, 0.0
    if mid[2] - radius > 1.0:  # a crown in the air needs a trunk; a low one is a bush
        top = mid + perp * (1.8 * radius)
        top[2] = max(top[2], 0.5)
        for f in (0.5, 1.0):  # boughs joining the crown to the trunk top
            centres.append(mid + f * (top - mid))
            radii.append(0.8 * radius)
        trunk_base, trunk_top = top[:2].copy(), float(top[2])
    phases = rng.uniform(0.0, 2.0 * math.pi, (len(centres), 5))
    return Tree(np.array(centres), np.array(radii), trunk_base, trunk_top, max(0.15, 0.25 * radius), phases, window, rho)


def build_walker(rng: np.random.Generator, camera: np.ndarray, ball_at: Callable[[float], np.ndarray],
                 window: tuple[float, float]) -> Walker:
    """A walker on the ball's line of sight during ``window``, ``WALKER_AT`` of the way to the ball."""
    start, end = window
    times = np.linspace(start, end, max(2, int(math.ceil((end - start) * 30)) + 1))
    stations = []
    for t in times:
        d = ball_at(t)[:2] - camera[:2]
        stations.append(camera[:2] + WALKER_AT * d)
    stations = np.array(stations)
    d0 = ball_at(start)[:2] - camera[:2]
    left = np.array([-d0[1], d0[0]]) / (np.linalg.norm(d0) or 1.0)
    side = left if rng.random() < 0.5 else -left
    return Walker(window, stations, times, side)


@dataclass(frozen=True, eq=False)
class Both:
    """A tree for the part of the window the ball is in the air, a walker for the part on the ground."""

    tree: Tree
    walker: Walker
    window: tuple[float, float]

    def distance(self, camera: np.ndarray, t: float) -> float:
        return min(self.tree.distance(camera, t), self.walker.distance(camera, t))

    def extent(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        (pa, ra), (pb, rb) = self.tree.extent(t), self.walker.extent(t)
        return np.vstack([pa, pb]), np.concatenate([ra, rb])

    def parts(self, camera, rays, pixel_angle, t):
        return self.tree.parts(camera, rays, pixel_angle, t) + self.walker.parts(camera, rays, pixel_angle, t)


def build_occluder(rng: np.random.Generator, camera: np.ndarray, ball_at: Callable[[float], np.ndarray],
                   window: tuple[float, float], ball_radius: float) -> Occluder:
    """A tree while the ball flies high, a walker once it stays low enough for the umbrella to hide it."""
    start, end = window
    times = np.linspace(start, end, max(50, int((end - start) * 200)))
    # The line of sight passes the walker at (1 - f) camera height + f ball height: below the umbrella top?
    low_enough = max(0.5, (UMBRELLA_TOP - 0.1 - (1.0 - WALKER_AT) * float(camera[2])) / WALKER_AT)
    high = np.nonzero(np.array([float(ball_at(t)[2]) for t in times]) >= low_enough)[0]
    if len(high) == 0:
        return build_walker(rng, camera, ball_at, window)
    split = float(times[high[-1]])
    if split >= end - 1e-6:
        return build_tree(rng, camera, ball_at, window, ball_radius)
    tree = build_tree(rng, camera, ball_at, (start, split), ball_radius)
    walker = build_walker(rng, camera, ball_at, (split, end))
    return Both(tree, walker, window)
