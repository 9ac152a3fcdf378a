"""Small synthetic images for the golf tracker's tests: a white ball over blue sky or green grass."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from trackreplay.schemas.records import InitRegion, LensEntry, LensTable, PtzReading
from trackreplay.trackers.frame import Frame
from trackreplay.trackers.geometry.ptz import PtzCamera

SKY_BGR = (205, 160, 95)
GRASS_BGR = (45, 135, 60)
BALL_BGR = (240, 242, 244)


def backdrop(height: int = 720, width: int = 1280, horizon: int | None = None, seed: int = 0) -> np.ndarray:
    """Sky above ``horizon`` (default: half height), grass below, mild noise and a vertical gradient."""
    rng = np.random.default_rng(seed)
    horizon = height // 2 if horizon is None else horizon
    img = np.empty((height, width, 3), np.float64)
    img[:horizon] = SKY_BGR
    img[horizon:] = GRASS_BGR
    img[:horizon] += np.linspace(-15, 15, horizon)[:, None, None]
    img += rng.normal(0.0, 3.0, img.shape)
    return np.clip(img, 0, 255).astype(np.uint8)


def draw_ball(img: np.ndarray, centre, radius: float, colour=BALL_BGR) -> np.ndarray:
    """Anti-aliased disc at sub-pixel ``centre`` (pixel centres at integer coordinates)."""
    out = img.copy()
    shift = 4
    c = (int(round(centre[0] * (1 << shift))), int(round(centre[1] * (1 << shift))))
    cv2.circle(out, c, int(round(radius * (1 << shift))), colour, -1, cv2.LINE_AA, shift)
    return out


@pytest.fixture(scope="session", name="backdrop")
def backdrop_fixture():
    """The :func:`backdrop` painter."""
    return backdrop


@pytest.fixture(scope="session", name="draw_ball")
def draw_ball_fixture():
    """The :func:`draw_ball` painter."""
    return draw_ball


# --- sequences of frames ---------------------------------------------------------------------

FPS = 30
NS = 1_000_000_000 // FPS


def image_track(n=40):
    """Up from the grass and over into the sky along an image-space parabola (pixels)."""
    t = np.arange(n, dtype=float)
    return np.stack([300 + 9.0 * t, 620 - 20.0 * t + 0.3 * t * t], axis=1)


def image_sequence(n=40, radius=5.0):
    track = image_track(max(n, 26))
    base = backdrop()
    regions = (InitRegion(0, 0, *track[0], 12, 12, "ball"), InitRegion(25, 25 * NS, *track[25], 12, 12, "ball"))
    frames = []
    for k in range(n):
        hints = tuple(r for r in regions if r.frame == k)
        frames.append(Frame(k, k * NS, draw_ball(base, track[k], radius), hints=hints, all_hints=regions))
    return track[:n], frames


BIG = 0.4  # m: a big "ball" so that a wide, fixed camera sees it several pixels across
LENS = LensTable(1280, 720, (LensEntry(0, 0, 1000, 1000, 640, 360), LensEntry(100, 0, 4000, 4000, 640, 360)), (0.0, 0.0, 1.5))


def ballistic(n: int):
    """Centre positions per frame: launch, land at frame ~73, bounce with restitution 0.5."""
    g, r = 9.81, BIG / 2
    p = np.array([-25.0, 50.0, r])
    v = np.array([15.0, 0.0, 12.0])
    out, landing = [], None
    dt = 1.0 / FPS / 50
    for k in range(n):
        out.append(p.copy())
        for _ in range(50):
            v[2] -= g * dt
            p = p + v * dt
            if p[2] < r and v[2] < 0:
                landing = landing if landing is not None else k + 1
                p[2], v[2] = r, -0.5 * v[2]
    return np.array(out), landing


def ptz_sequence(n=95):
    cam = PtzCamera.from_reading(PtzReading(0, 90.0, 4.0, 0.0, 0.0), LENS)
    world, landing = ballistic(n)
    uv = cam.project_points(world)
    diam = cam.intrinsics.fx * BIG / np.linalg.norm(world - cam.position, axis=1)
    base = backdrop(horizon=int(cam.project_points(np.array([[0.0, 1e4, 0.0]]))[0, 1]))
    regions = (InitRegion(0, 0, *uv[0], math.ceil(diam[0]) + 2, math.ceil(diam[0]) + 2, "ball"),
               InitRegion(25, 25 * NS, *uv[25], math.ceil(diam[25]) + 2, math.ceil(diam[25]) + 2, "ball"))
    frames = [Frame(k, k * NS, draw_ball(base, uv[k], diam[k] / 2), ptz=PtzReading(k * NS, 90.0, 4.0, 0.0, 0.0),
                    lens=LENS, camera=cam, hints=tuple(r for r in regions if r.frame == k), all_hints=regions)
              for k in range(n)]
    return world, uv, landing, frames




@pytest.fixture(scope="session", name="image_sequence")
def image_sequence_fixture():
    """:func:`image_sequence`: a ball rising from the grass into the sky, no camera pose."""
    return image_sequence


@pytest.fixture(scope="session", name="ptz_sequence")
def ptz_sequence_fixture():
    """:func:`ptz_sequence`: a fixed PTZ camera watching a ballistic shot land and bounce."""
    return ptz_sequence
