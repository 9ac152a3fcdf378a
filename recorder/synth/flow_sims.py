"""The three simulations of the gradient-flow paper (seed 004, §5) as logs with ground truth.

sim1: a 13x13 square of brightness 200 on circular motion over a 256x256 background.
sim2: the same square rotating 1 deg/frame about its centre.
sim3: a disc of radius 7 growing 1 px every 5 frames from t = 5, on the same circle.
t = 0..50; the target moves between integer pixel positions (integer velocities).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from trackreplay.recorder.image_codec import image_message
from trackreplay.recorder.synth.texture import natural_texture, photo_background
from trackreplay.recorder.writer import LogWriter
from trackreplay.schemas import topics as T
from trackreplay.schemas.records import GroundTruthFrame, GroundTruthObject, InitRegion, init_annotations_pb

SCENES = ("flow-sim1", "flow-sim2", "flow-sim3")
_SUPERSAMPLE = 8


@dataclass(frozen=True)
class FlowSimConfig:
    scene: str = "flow-sim1"
    size: int = 256
    frames: int = 51
    fps: float = 30.0
    radius: float = 20.0  # of the circular path, px
    period: float = 50.0  # frames per revolution
    square: int = 13
    disc_radius: int = 7
    brightness: int = 200
    rotation_deg_per_frame: float = 1.0
    background: str = "texture"  # or a scikit-image photo name
    seed: int = 0
    encoding: str = "png"


def target_centres(cfg: FlowSimConfig) -> np.ndarray:
    """Integer centre (x, y) per frame on a circle around the image centre."""
    t = np.arange(cfg.frames)
    angle = 2.0 * np.pi * t / cfg.period
    c = (cfg.size - 1) / 2.0
    xy = np.stack([c + cfg.radius * np.cos(angle), c + cfg.radius * np.sin(angle)], axis=1)
    return np.round(xy).astype(np.int64)


def disc_radius(cfg: FlowSimConfig, t: int) -> int:
    """Radius 7, +1 px every 5 frames from t = 5 (paper §5.3)."""
    return cfg.disc_radius + (t // 5 if t >= 5 else 0)


def _coverage(cfg: FlowSimConfig, t: int, centre: np.ndarray) -> tuple[np.ndarray, float]:
    """Anti-aliased target coverage in [0, 1] over the image, and its box side in px."""
    s = _SUPERSAMPLE
    big = np.zeros((cfg.size * s, cfg.size * s), np.uint8)
    # pixel (i, j) covers [j-0.5, j+0.5): supersampled coordinates of a point p are (p + 0.5) * s - 0.5
    cx, cy = (centre + 0.5) * s - 0.5
    if cfg.scene == "flow-sim3":
        r = disc_radius(cfg, t)
        cv2.circle(big, (int(round(cx * 16)), int(round(cy * 16))), int(round((r + 0.5) * s * 16)), 255, -1, cv2.LINE_8, 4)
        side = 2.0 * r + 1.0
    else:
        half = cfg.square / 2.0 * s
        angle = np.deg2rad(cfg.rotation_deg_per_frame * t) if cfg.scene == "flow-sim2" else 0.0
        corners = np.array([[-half, -half], [half, -half], [half, half], [-half, half]])
        rot = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
        pts = corners @ rot.T + [cx, cy]
        cv2.fillConvexPoly(big, np.round(pts * 16).astype(np.int32), 255, cv2.LINE_8, 4)
        side = float(cfg.square)
    cover = cv2.resize(big, (cfg.size, cfg.size), interpolation=cv2.INTER_AREA).astype(np.float32) / 255.0
    return cover, side


def render(cfg: FlowSimConfig, background: np.ndarray, t: int, centre: np.ndarray) -> tuple[np.ndarray, float]:
    cover, side = _coverage(cfg, t, centre)
    image = background.astype(np.float32) * (1.0 - cover) + cfg.brightness * cover
    return np.round(image).astype(np.uint8), side


def write_flow_sim(out: str | Path, cfg: FlowSimConfig) -> int:
    """Write the scene to ``out``; returns the number of frames."""
    if cfg.scene not in SCENES:
        raise ValueError(f"unknown scene {cfg.scene!r}; choose one of {', '.join(SCENES)}")
    if cfg.background == "texture":
        background = natural_texture(cfg.size, cfg.size, cfg.seed)
    else:
        background = photo_background(cfg.background, cfg.size, cfg.size)
    centres = target_centres(cfg)
    period_ns = 1e9 / cfg.fps
    with LogWriter(out) as log:
        for t in range(cfg.frames):
            t_ns = int(round(t * period_ns))
            image, side = render(cfg, background, t, centres[t])
            if t == 0:
                x, y = centres[0]
                init = InitRegion(0, t_ns, float(x), float(y), side, side, "target")
                log.write(T.ANNOTATIONS_INIT, init_annotations_pb([init], t_ns), t_ns)
            vx, vy = (centres[t] - centres[t - 1]).tolist() if t > 0 else (None, None)
            obj = GroundTruthObject(
                id=1, x=float(centres[t][0]), y=float(centres[t][1]), w=side, h=side,
                vx=None if vx is None else float(vx), vy=None if vy is None else float(vy), visible=True,
            )
            log.write(T.CAMERA_IMAGE, image_message(image, cfg.encoding, t_ns), t_ns)
            log.write(T.GROUNDTRUTH, GroundTruthFrame(t, t_ns, (obj,)).to_pb(), t_ns)
    return cfg.frames
