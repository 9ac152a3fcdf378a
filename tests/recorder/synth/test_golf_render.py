"""Rendering of the synthetic tee shot agrees with its ground truth."""

import math

import cv2
import numpy as np
import pytest

from trackreplay.recorder.synth.golf.flight import AIR, REST, ROLL, TEE
from trackreplay.recorder.synth.golf.render import GolfRenderer
from trackreplay.recorder.synth.golf.scene import GolfSceneConfig, plan_shot


@pytest.fixture(scope="module")
def scene():
    shot = plan_shot(GolfSceneConfig())
    renderer = GolfRenderer(shot.world, shot.cfg.width, shot.cfg.height, shot.cfg.seed, ball_radius=shot.cfg.ball.radius)
    return shot, renderer


def _pick(shot, phase, background, still=True):
    """A frame of this phase over this background with the ball well inside the image."""
    for tr in shot.truth:
        if tr.phase == phase and tr.background == background and tr.visible and tr.uv is not None:
            u, v = tr.uv
            moving = math.hypot(*tr.velocity_px) if tr.velocity_px else 0.0
            if 40 < u < shot.cfg.width - 40 and 40 < v < shot.cfg.height - 40 and (moving < 0.5) == still and tr.diameter > 2.5:
                return tr
    raise AssertionError(f"no frame with phase {phase} over {background}")


def _ball_only(shot, renderer, tr):
    view = shot.view(tr.frame)
    with_ball = renderer.render(view, noise=False).astype(np.float64)
    without = renderer.render(view, draw_ball=False, noise=False).astype(np.float64)
    return with_ball, (with_ball - without).max(axis=2)


@pytest.mark.parametrize("phase,background", [(TEE, "ground"), (AIR, "sky"), (ROLL, "ground"), (REST, "ground")])
def test_ball_is_drawn_where_the_ground_truth_says(scene, phase, background) -> None:
    shot, renderer = scene
    tr = _pick(shot, phase, background)
    image, diff = _ball_only(shot, renderer, tr)
    u, v = tr.uv
    ys, xs = np.nonzero(diff > 1.0)
    w = diff[ys, xs]
    cx, cy = (xs * w).sum() / w.sum(), (ys * w).sum() / w.sum()
    assert math.hypot(cx - u, cy - v) < 0.5  # shading (sun side brighter) pulls it a little
    # Its size: the covered area (difference / contrast) is the disc's pi r^2.
    contrast = diff.max()
    area = (diff / contrast).sum()
    assert area == pytest.approx(math.pi * tr.diameter**2 / 4, rel=0.35)
    # And in the real frame (noise and all) the brightest blob around there is centred on it.
    grey = image.mean(axis=2)
    y0, x0 = int(v) - 15, int(u) - 15
    win = grey[y0 : y0 + 31, x0 : x0 + 31]
    assert win.max() > np.median(win) + 20
    mask = (win > 0.5 * (win.max() + np.median(win))).astype(np.uint8)
    _, labels, _, centroids = cv2.connectedComponentsWithStats(mask)
    by, bx = np.unravel_index(np.argmax(win), win.shape)
    bx, by = centroids[labels[by, bx]]
    assert math.hypot(x0 + bx - u, y0 + by - v) <= 1.0


def test_motion_blur_streaks_along_the_image_velocity_and_keeps_the_centroid(scene) -> None:
    shot, renderer = scene
    tr = max((t for t in shot.truth if t.visible and t.uv is not None and t.velocity_px is not None
              and 60 < t.uv[0] < shot.cfg.width - 60 and 60 < t.uv[1] < shot.cfg.height - 60),
             key=lambda t: math.hypot(*t.velocity_px))
    speed = math.hypot(*tr.velocity_px)
    assert speed > 5.0
    _, diff = _ball_only(shot, renderer, tr)
    ys, xs = np.nonzero(diff > 0.5)
    w = diff[ys, xs]
    cx, cy = (xs * w).sum() / w.sum(), (ys * w).sum() / w.sum()
    assert math.hypot(cx - tr.uv[0], cy - tr.uv[1]) < 2.0
    # Elongated along the velocity: the streak spans about speed * shutter pixels.
    d = np.stack([xs - cx, ys - cy], axis=1)
    along = d @ (np.array(tr.velocity_px) / speed)
    assert np.ptp(along) > 0.6 * speed * shot.cfg.shutter


def test_sky_above_the_horizon_and_grass_below(scene) -> None:
    shot, renderer = scene
    sky = _pick(shot, AIR, "sky")
    image = renderer.render(shot.view(sky.frame), draw_ball=False, noise=False).astype(float)
    b, g, r = image[..., 0].mean(), image[..., 1].mean(), image[..., 2].mean()
    assert b > g > r  # blue sky
    ground = _pick(shot, REST, "ground")
    image = renderer.render(shot.view(ground.frame), draw_ball=False, noise=False).astype(float)
    lower = image[image.shape[0] // 2 :]
    assert lower[..., 1].mean() > lower[..., 0].mean() and lower[..., 1].mean() > lower[..., 2].mean()  # green


def test_rendering_is_deterministic_and_clouds_stay_in_the_world(scene) -> None:
    shot, renderer = scene
    tr = _pick(shot, AIR, "sky")
    a = renderer.render(shot.view(tr.frame))
    b = GolfRenderer(shot.world, shot.cfg.width, shot.cfg.height, shot.cfg.seed, ball_radius=shot.cfg.ball.radius).render(shot.view(tr.frame))
    assert np.array_equal(a, b)
    # A second pose sees the same cloud texture where the same world direction projects.
    cam = shot.view(tr.frame).camera
    other = shot.view(tr.frame + 6)
    pts = np.array([[400.0, 200.0], [800.0, 500.0], [640.0, 360.0]])
    uv2 = other.camera.project_directions(cam.line_of_sight(pts))
    img1 = renderer.render(shot.view(tr.frame), draw_ball=False, noise=False).astype(float)
    img2 = renderer.render(other, draw_ball=False, noise=False).astype(float)
    for (u1, v1), (u2, v2) in zip(pts, uv2):
        assert np.abs(img1[int(round(v1)), int(round(u1))] - img2[int(round(v2)), int(round(u2))]).max() < 12


def test_occluded_ball_leaves_no_trace(scene) -> None:
    shot = plan_shot(GolfSceneConfig(occlusion=(2.0, 3.0)))
    renderer = GolfRenderer(shot.world, shot.cfg.width, shot.cfg.height, shot.cfg.seed, ball_radius=shot.cfg.ball.radius)
    tr = shot.truth[75]
    assert tr.occluded and tr.in_frame and not tr.visible
    _, diff = _ball_only(shot, renderer, tr)
    assert np.abs(diff).max() < 1.0
