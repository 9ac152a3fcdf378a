"""The stereo rig and the static world of the group scenes (seed 003 §4).

World frame: right-handed, metres, **Z up**, ground Z = 0; the rig stands on the world's origin at
``height`` m and looks along +Y, tilted ``tilt_deg`` down. Camera frame (what the logs' ground truth
and the tracker use): the left camera's, x right, y down, z forward. The right camera is
``baseline`` m to the right of the left (rectified pair: same R, same intrinsics).

Rig like the paper's Bumblebee2: f = 3.8 mm on 7.4 µm pixels = 513.5 px, b = 120 mm, VGA.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import cv2
import numpy as np

from trackreplay.recorder.synth.texture import natural_texture


@dataclass(frozen=True)
class Rig:
    height: float = 5.1  # m above the ground
    tilt_deg: float = 40.0  # down from horizontal
    f: float = 3.8e-3 / 7.4e-6  # px
    baseline: float = 0.12  # m
    width: int = 640
    height_px: int = 480

    @property
    def cx(self) -> float:
        return (self.width - 1) / 2.0

    @property
    def cy(self) -> float:
        return (self.height_px - 1) / 2.0

    @cached_property
    def R(self) -> np.ndarray:
        """World → left camera rotation (rows: camera x, y, z axes in world coordinates)."""
        t = np.deg2rad(self.tilt_deg)
        z = np.array([0.0, np.cos(t), -np.sin(t)])
        x = np.array([1.0, 0.0, 0.0])
        return np.stack([x, np.cross(z, x), z])

    @property
    def centre(self) -> np.ndarray:
        return np.array([0.0, 0.0, self.height])

    def to_camera(self, world: np.ndarray) -> np.ndarray:
        """(N, 3) world points → left camera frame."""
        return (np.asarray(world, dtype=np.float64) - self.centre) @ self.R.T

    def to_world(self, cam: np.ndarray) -> np.ndarray:
        return np.asarray(cam, dtype=np.float64) @ self.R + self.centre

    def project(self, cam: np.ndarray, right: bool = False) -> np.ndarray:
        """(N, 3) left-camera points → (N, 2) pixels in the left (or right) image."""
        p = np.asarray(cam, dtype=np.float64).reshape(-1, 3)
        x = p[:, 0] - (self.baseline if right else 0.0)
        return np.stack([self.f * x / p[:, 2] + self.cx, self.f * p[:, 1] / p[:, 2] + self.cy], axis=1)

    def rays(self, right: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Camera centre (3,) and per-pixel ray directions (H, W, 3), both in world coordinates."""
        u, v = np.meshgrid(np.arange(self.width, dtype=np.float64), np.arange(self.height_px, dtype=np.float64))
        d_cam = np.stack([(u - self.cx) / self.f, (v - self.cy) / self.f, np.ones_like(u)], axis=2)
        origin = self.centre + (self.R.T @ np.array([self.baseline, 0.0, 0.0]) if right else 0.0)
        return origin, d_cam @ self.R


@dataclass(frozen=True)
class Stairs:
    """``steps`` solid slabs from ``y0``: slab k spans Y ∈ [y0 + k·tread, y0 + steps·tread + landing],
    Z ∈ [k·rise, (k + 1)·rise], X ∈ [x0, x1]."""

    y0: float = 4.6
    steps: int = 10
    tread: float = 0.3
    rise: float = 0.16
    x0: float = -2.5
    x1: float = 2.5
    landing: float = 6.0

    def height_at(self, y: np.ndarray | float) -> np.ndarray:
        k = np.floor((np.asarray(y, dtype=np.float64) - self.y0) / self.tread) + 1.0
        return np.clip(k, 0.0, self.steps) * self.rise

    def slabs(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """(min corner, max corner) per slab, bottom first (the painter's order from a camera above)."""
        end = self.y0 + self.steps * self.tread + self.landing
        return [(np.array([self.x0, self.y0 + k * self.tread, k * self.rise]),
                 np.array([self.x1, end, (k + 1) * self.rise])) for k in range(self.steps)]


@dataclass(frozen=True)
class World:
    """Textured ground (40 m square) and a back wall at ``wall_y``; optional stairs."""

    seed: int = 0
    wall_y: float = 24.0
    stairs: Stairs | None = None
    texture_px: int = 1024
    ground_extent: tuple[float, float, float, float] = (-20.0, 20.0, -2.0, 38.0)  # X0 X1 Y0 Y1
    tint_ground: tuple[float, float, float] = (0.85, 0.95, 1.05)  # BGR gains
    tint_wall: tuple[float, float, float] = (1.1, 0.95, 0.8)
    _cache: dict = field(default_factory=dict, compare=False, repr=False)

    def ground_height(self, y: np.ndarray | float) -> np.ndarray:
        return self.stairs.height_at(y) if self.stairs is not None else np.zeros_like(np.asarray(y, dtype=np.float64))

    def _texture(self, key: int) -> np.ndarray:
        if key not in self._cache:
            grey = natural_texture(self.texture_px, self.texture_px, self.seed * 7 + key, beta=1.6, lo=40, hi=210)
            self._cache[key] = grey.astype(np.float32)
        return self._cache[key]

    def background(self, rig: Rig, right: bool = False) -> np.ndarray:
        """The empty scene as seen by one camera (BGR uint8): ground and wall by ray casting, stairs drawn on top."""
        origin, d = rig.rays(right)
        x0, x1, y0, y1 = self.ground_extent
        with np.errstate(divide="ignore", invalid="ignore"):
            t_ground = np.where(d[..., 2] < 0, -origin[2] / d[..., 2], np.inf)
            t_wall = np.where(d[..., 1] > 0, (self.wall_y - origin[1]) / d[..., 1], np.inf)
        use_ground = t_ground < t_wall
        t = np.minimum(t_ground, t_wall)
        t = np.where(np.isfinite(t), t, 1e3)
        p = origin + d * t[..., None]
        n = self.texture_px
        gx = ((p[..., 0] - x0) / (x1 - x0) * n).astype(np.float32)
        gy = ((p[..., 1] - y0) / (y1 - y0) * n).astype(np.float32)
        wz = ((p[..., 2]) / 10.0 * n).astype(np.float32)
        ground = cv2.remap(self._texture(1), gx, gy, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
        wall = cv2.remap(self._texture(2), gx, wz, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
        out = np.where(use_ground[..., None], ground[..., None] * np.array(self.tint_ground, np.float32),
                       wall[..., None] * np.array(self.tint_wall, np.float32))
        image = np.clip(np.round(out), 0, 255).astype(np.uint8)
        if self.stairs is not None:
            from trackreplay.recorder.synth.groups.people import Painter, box_faces

            painter = Painter(rig, right, image)
            tex = np.clip(self._texture(3)[:256, :256] * 0.9 + 20, 0, 255).astype(np.uint8)
            for lo, hi in self.stairs.slabs():
                faces = box_faces(lo, hi)
                painter.draw_faces(faces, [cv2.cvtColor(tex, cv2.COLOR_GRAY2BGR)] * len(faces), ids=None, sort=True)
        return image
