"""Walking people seen by a fixed camera over flat ground: the colour particle filter's experiments
(seed 002, §5) as logs with ground truth.

A 720x480 pinhole camera ``camera_height`` metres above the floor looks along +Y, tilted down by
``tilt_deg``; the floor is textured tiles, a wall with posters stands ``wall_y`` metres away. Its
image -> ground homography goes to ``/camera/ground_plane``. Two walkers (textured striped shirt,
trousers, skin, hair; legs and arms swing with the gait, so the box's aspect changes): the target
(ground-truth id 1, marked on ``/annotations/init``) and another person (id 2) in other colours
further back. The first ``empty_frames`` frames show the empty scene (the camera started before
anyone came in: the background subtraction at initialisation needs them), then the walkers walk.

- ``colorpf-illumination`` (Table 1): the target walks across; the whole picture's brightness
  changes in 16 uniform steps over the sequence (gain 1.0 down to 0.35).
- ``colorpf-background`` (Table 2): the target walks across in front of posters and floor mats
  whose colours are the target's own (shirt red, trouser blue).
- ``colorpf-approach`` (Table 3): the target walks from 22 m toward the camera to 6.5 m: its image
  grows about 3.5x.

Ground truth: the box around each walker's drawn pixels (centre, size), its ground position
``world_x, world_y`` (m) and ``visible``. Rendered with numpy and OpenCV fills, deterministic for a
seed (sensor noise from ``default_rng(seed)``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from trackreplay.recorder.image_codec import image_message
from trackreplay.recorder.writer import LogWriter
from trackreplay.schemas import topics as T
from trackreplay.schemas.ground_plane import GroundPlaneCalibration
from trackreplay.schemas.records import GroundTruthFrame, GroundTruthObject, InitRegion, init_annotations_pb

SCENES = ("colorpf-illumination", "colorpf-background", "colorpf-approach")
BODY_HEIGHT = 1.75  # m, foot to top of the head

# BGR colours of the walkers' parts (label index -> colour)
TARGET_COLOURS = {1: (40, 40, 200), 2: (30, 30, 140), 3: (150, 80, 30), 4: (120, 150, 210), 5: (30, 35, 45)}  # red shirt / stripe, blue trousers, skin, hair
OTHER_COLOURS = {1: (60, 170, 60), 2: (40, 120, 40), 3: (110, 110, 110), 4: (100, 140, 200), 5: (20, 60, 90)}  # green shirt, grey trousers


@dataclass(frozen=True)
class ColorPfSceneConfig:
    scene: str = "colorpf-illumination"
    seed: int = 0
    width: int = 720
    height: int = 480
    frames: int = 96  # walking frames (after the empty ones)
    empty_frames: int = 8
    fps: float = 30.0
    camera_height: float = 3.0  # m
    tilt_deg: float = 12.0
    focal_px: float = 700.0  # at 720 px wide; scaled with the width
    wall_y: float = 24.0  # m
    steps: int = 16  # illumination steps (colorpf-illumination)
    gain_min: float = 0.35
    noise: float = 2.0  # sensor noise, grey levels
    encoding: str = "jpeg"
    jpeg_quality: int = 92

    def validate(self) -> None:
        if self.scene not in SCENES:
            raise ValueError(f"unknown scene {self.scene!r}; choose one of {', '.join(SCENES)}")
        if self.frames < 2 or self.empty_frames < 0 or self.width < 64 or self.height < 48 or self.steps < 1:
            raise ValueError("frames >= 2, empty_frames >= 0, an image of at least 64x48 and steps >= 1")


@dataclass(frozen=True, eq=False)
class Camera:
    """A pinhole at (0, 0, h) looking along +Y tilted down; image x right, y down."""

    K: np.ndarray
    R: np.ndarray  # rows: camera x, y, z axes in world coordinates
    height: float

    @classmethod
    def of(cls, cfg: ColorPfSceneConfig) -> Camera:
        f = cfg.focal_px * cfg.width / 720.0
        K = np.array([[f, 0.0, (cfg.width - 1) / 2.0], [0.0, f, (cfg.height - 1) / 2.0], [0.0, 0.0, 1.0]])
        t = np.deg2rad(cfg.tilt_deg)
        R = np.array([[1.0, 0.0, 0.0], [0.0, -np.sin(t), -np.cos(t)], [0.0, np.cos(t), -np.sin(t)]])
        return cls(K, R, cfg.camera_height)

    @property
    def centre(self) -> np.ndarray:
        return np.array([0.0, 0.0, self.height])

    def project(self, points: np.ndarray) -> np.ndarray:
        p = (np.asarray(points, dtype=np.float64).reshape(-1, 3) - self.centre) @ self.R.T
        q = p @ self.K.T
        return q[:, :2] / q[:, 2:3]

    def ground_to_image(self) -> np.ndarray:
        """(X, Y, 1) on the floor -> (u, v, 1)."""
        M = self.R @ np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -self.height]])
        return self.K @ M

    def calibration(self, cfg: ColorPfSceneConfig) -> GroundPlaneCalibration:
        H = np.linalg.inv(self.ground_to_image())
        H = H / H[2, 2]
        return GroundPlaneCalibration(cfg.width, cfg.height, tuple(float(v) for v in H.reshape(-1)), (0.0, 0.0),
                                      self.height, (float(self.K[0, 2]), float(self.K[1, 2])), float(self.K[0, 0]))

    def rays(self, width: int, height: int) -> np.ndarray:
        v, u = np.mgrid[0:height, 0:width].astype(np.float64)
        pix = np.stack([u, v, np.ones_like(u)], axis=-1) @ np.linalg.inv(self.K).T
        return pix @ self.R  # world directions (not normalised)


def _noise_grid(rng: np.random.Generator, n: int = 64) -> np.ndarray:
    g = rng.standard_normal((n, n))
    return cv2.GaussianBlur(g, (0, 0), 1.0)


def render_background(cfg: ColorPfSceneConfig, cam: Camera, rng: np.random.Generator) -> np.ndarray:
    """Floor tiles and a wall with posters (float32 BGR, 0..255)."""
    d = cam.rays(cfg.width, cfg.height)
    dz, dy = d[..., 2], d[..., 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        t_floor = np.where(dz < 0, -cam.height / dz, np.inf)
        t_wall = np.where(dy > 0, cfg.wall_y / dy, np.inf)
    floor = t_floor < t_wall
    t = np.where(floor, t_floor, t_wall)
    X = t * d[..., 0]
    Y = t * d[..., 1]
    Z = cam.height + t * dz
    grid = _noise_grid(rng)
    img = np.zeros((cfg.height, cfg.width, 3), np.float32)
    # floor: 1 m tiles in two beige-grey tones, grout lines, a fine stone texture
    gi = (np.floor(X * 8).astype(np.int64) % 64, np.floor(Y * 8).astype(np.int64) % 64)
    tone = np.where((np.floor(X) + np.floor(Y)) % 2 == 0, 1.0, 0.86)
    grout = (np.abs(X - np.round(X)) < 0.015) | (np.abs(Y - np.round(Y)) < 0.015)
    base = np.array([150.0, 165.0, 175.0], np.float32)
    stone = (tone * (1.0 + 0.06 * grid[gi]))[..., None] * base
    stone = np.where(grout[..., None], base * 0.55, stone)
    # wall: pale blue-grey plaster with a dado stripe
    wi = (np.floor(X * 6).astype(np.int64) % 64, np.floor(Z * 6).astype(np.int64) % 64)
    wall = (1.0 + 0.05 * grid[wi])[..., None] * np.array([185.0, 180.0, 170.0], np.float32)
    wall = np.where(((Z > 0.9) & (Z < 1.05))[..., None], np.array([110.0, 110.0, 105.0], np.float32), wall)
    img[:] = np.where(floor[..., None], stone, wall)
    # posters on the wall (x0, x1, z0, z1, colour) and mats on the floor (x0, x1, y0, y1, colour)
    if cfg.scene == "colorpf-background":  # the target's own colours: red, dark red, denim blue
        posters = [(-6.0, -3.2, 0.3, 2.6, (45, 45, 205)), (-2.6, -0.8, 0.2, 2.8, (150, 80, 30)),
                   (-0.4, 2.4, 0.4, 2.5, (35, 35, 150)), (2.8, 5.5, 0.2, 2.7, (140, 85, 40)),
                   (6.0, 8.0, 0.5, 2.4, (40, 40, 200))]
        mats = [(-4.5, -2.0, 13.0, 18.0, (45, 45, 190)), (-1.2, 1.0, 12.8, 17.0, (150, 85, 35)),
                (1.6, 4.0, 13.0, 19.0, (40, 40, 170)), (-0.5, 2.0, 8.0, 10.0, (45, 45, 200))]
    else:  # other colours: yellow, purple, teal
        posters = [(-6.0, -3.5, 0.4, 2.5, (40, 200, 220)), (-1.5, 0.8, 0.3, 2.7, (160, 60, 140)),
                   (3.0, 5.5, 0.4, 2.5, (160, 160, 40))]
        mats = [(-3.0, -1.0, 12.0, 15.0, (70, 150, 200))]
    for x0, x1, z0, z1, colour in posters:
        inside = ~floor & (X >= x0) & (X <= x1) & (Z >= z0) & (Z <= z1)
        shade = (1.0 + 0.08 * grid[wi])[..., None] * np.array(colour, np.float32)
        img = np.where(inside[..., None], shade, img)
    for x0, x1, y0, y1, colour in mats:
        inside = floor & (X >= x0) & (X <= x1) & (Y >= y0) & (Y <= y1)
        shade = (1.0 + 0.08 * grid[gi])[..., None] * np.array(colour, np.float32)
        img = np.where(inside[..., None], shade, img)
    return img


@dataclass(frozen=True)
class Walk:
    """A straight walk on the floor: from ``start`` to ``end`` (X, Y metres) over the walking frames."""

    start: tuple[float, float]
    end: tuple[float, float]
    colours: dict
    stride_frames: float = 30.0  # frames per gait cycle (two steps)
    phase: float = 0.0

    def at(self, k: int, n: int) -> np.ndarray:
        a = k / max(n - 1, 1)
        return (1.0 - a) * np.asarray(self.start) + a * np.asarray(self.end)


def walks(cfg: ColorPfSceneConfig) -> tuple[Walk, Walk]:
    if cfg.scene == "colorpf-approach":
        target = Walk((1.6, 22.0), (-0.4, 6.5), TARGET_COLOURS, 32.0)
        other = Walk((4.5, 17.0), (-4.5, 17.5), OTHER_COLOURS, 30.0, 0.3)
    elif cfg.scene == "colorpf-background":
        target = Walk((-3.2, 12.5), (3.4, 11.5), TARGET_COLOURS)
        other = Walk((4.0, 19.0), (-3.0, 20.0), OTHER_COLOURS, 28.0, 0.5)
    else:
        target = Walk((-3.0, 10.0), (3.0, 12.0), TARGET_COLOURS)
        other = Walk((4.5, 18.0), (-4.0, 17.0), OTHER_COLOURS, 28.0, 0.5)
    return target, other


def _quad(p0: np.ndarray, p1: np.ndarray, w0: float, w1: float) -> np.ndarray:
    """A limb from p0 to p1 (body metres), widths w0 at p0 and w1 at p1."""
    d = p1 - p0
    n = np.array([-d[1], d[0]]) / max(np.hypot(*d), 1e-9)
    return np.array([p0 + n * w0 / 2, p1 + n * w1 / 2, p1 - n * w1 / 2, p0 - n * w0 / 2])


def draw_walker(img: np.ndarray, cam: Camera, ground: np.ndarray, heading: np.ndarray, gait: float,
                colours: dict) -> np.ndarray | None:
    """Draw one walker standing at ``ground`` (X, Y) into ``img`` (float32 BGR, in place); returns
    its box ``(x0, y0, x1, y1)`` (half-open pixels) or None when it is out of the picture."""
    h_img, w_img = img.shape[:2]
    foot, head = cam.project(np.array([[ground[0], ground[1], 0.0], [ground[0], ground[1], BODY_HEIGHT]]))
    scale = (foot[1] - head[1]) / BODY_HEIGHT  # px per metre at the walker (weak perspective)
    # swing seen sideways in proportion to the walk's image-lateral component
    lateral = abs(heading[0]) / max(np.hypot(*heading), 1e-9)
    swing = np.sin(2 * np.pi * gait)
    leg_a = np.deg2rad(24.0) * swing * lateral
    arm_a = -np.deg2rad(20.0) * swing * lateral
    spread = 0.05 + 0.07 * (1.0 - lateral) * abs(swing)  # walking toward the camera: legs part sideways
    hip, shoulder = 0.92, 1.45
    parts: list[tuple[int, np.ndarray]] = []
    for side, a in ((-1, leg_a), (1, -leg_a)):
        top = np.array([side * 0.08, hip])
        parts.append((3, _quad(top, top + 0.92 * np.array([np.sin(a) + side * spread, -np.cos(a)]), 0.16, 0.12)))
    for side, a in ((-1, arm_a), (1, -arm_a)):
        top = np.array([side * 0.22, shoulder - 0.03])
        parts.append((4, _quad(top, top + 0.62 * np.array([np.sin(a) + side * 0.06, -np.cos(a)]), 0.10, 0.08)))
    parts.append((1, np.array([[-0.17, hip], [0.17, hip], [0.21, shoulder], [-0.21, shoulder]])))
    labels = np.zeros((h_img, w_img), np.uint8)

    def to_px(p: np.ndarray) -> np.ndarray:
        return np.round((np.array([foot[0], foot[1]]) + p * np.array([scale, -scale])) * 16).astype(np.int32)

    for label, poly in parts:
        cv2.fillConvexPoly(labels, to_px(poly), label, cv2.LINE_8, 4)
    head_c = to_px(np.array([0.0, 1.62]))
    r = int(round(0.12 * scale * 16))
    cv2.circle(labels, tuple(int(v) for v in head_c), r, 4, -1, cv2.LINE_8, 4)
    cv2.ellipse(labels, tuple(int(v) for v in head_c), (r, r), 0, 180, 360, 5, -1, cv2.LINE_8, 4)
    ys, xs = np.nonzero(labels)
    if xs.size == 0:
        return None
    y0, y1, x0, x1 = ys.min(), ys.max() + 1, xs.min(), xs.max() + 1
    lab = labels[y0:y1, x0:x1]
    # stripes across the shirt every 8 cm (label 2), shading across the body
    z = (foot[1] - np.arange(y0, y1, dtype=np.float64)) / scale
    stripes = (np.floor(z / 0.08) % 2 == 0)[:, None] & (lab == 1)
    lab = np.where(stripes, 2, lab)
    xoff = (np.arange(x0, x1, dtype=np.float64) - foot[0]) / scale
    shade = (1.0 - 0.25 * np.clip(np.abs(xoff) / 0.3, 0, 1) ** 2)[None, :]
    table = np.zeros((6, 3), np.float32)
    for k, c in colours.items():
        table[k] = c
    patch = table[lab] * shade[..., None]
    region = img[y0:y1, x0:x1]
    region[:] = np.where((lab > 0)[..., None], patch, region)
    return np.array([x0, y0, x1, y1], dtype=np.float64)


def illumination_gain(cfg: ColorPfSceneConfig, frame: int) -> float:
    """colorpf-illumination: 16 uniform steps (1.0 ... gain_min) over the walking frames; else 1."""
    if cfg.scene != "colorpf-illumination":
        return 1.0
    k = max(frame - cfg.empty_frames, 0)
    step = min(k * cfg.steps // cfg.frames, cfg.steps - 1)
    return float(1.0 - (1.0 - cfg.gain_min) * step / max(cfg.steps - 1, 1))


@dataclass(frozen=True)
class SceneSummary:
    frames: int
    mark_frame: int
    target_height_px: tuple[float, float]  # smallest and largest box height of the target

    def describe(self) -> str:
        lo, hi = self.target_height_px
        return f"{self.frames} frames, target marked on frame {self.mark_frame}, its height {lo:.0f}-{hi:.0f} px"


def frames_of(cfg: ColorPfSceneConfig):
    """Yield ``(index, image uint8, objects)`` per frame (objects: GroundTruthObject per walker)."""
    cfg.validate()
    rng = np.random.default_rng(cfg.seed)
    cam = Camera.of(cfg)
    background = render_background(cfg, cam, rng)
    target, other = walks(cfg)
    total = cfg.empty_frames + cfg.frames
    for i in range(total):
        img = background.copy()
        objects = []
        k = i - cfg.empty_frames
        if k >= 0:
            drawn = []
            for wid, walk in ((2, other), (1, target)):
                g = walk.at(k, cfg.frames)
                heading = np.asarray(walk.end) - np.asarray(walk.start)
                drawn.append((g[1], wid, walk, g, heading))
            boxes = {}
            for _, wid, walk, g, heading in sorted(drawn, key=lambda t: -t[0]):  # far first
                boxes[wid] = (draw_walker(img, cam, g, heading, k / walk.stride_frames + walk.phase, walk.colours), g)
            for wid in (1, 2):
                box, g = boxes[wid]
                if box is None:
                    objects.append(GroundTruthObject(id=wid, visible=False))
                    continue
                x0, y0, x1, y1 = box
                objects.append(GroundTruthObject(id=wid, x=(x0 + x1 - 1) / 2.0, y=(y0 + y1 - 1) / 2.0, w=x1 - x0,
                                                 h=y1 - y0, X=float(g[0]), Y=float(g[1]), Z=0.0, visible=True))
        else:
            objects = [GroundTruthObject(id=1, visible=False), GroundTruthObject(id=2, visible=False)]
        img = img * illumination_gain(cfg, i) + rng.standard_normal(img.shape).astype(np.float32) * cfg.noise
        yield i, np.clip(np.round(img), 0, 255).astype(np.uint8), objects


def write_colorpf_scene(out: str | Path, cfg: ColorPfSceneConfig,
                        progress: Callable[[int, int], None] | None = None) -> SceneSummary:
    """Write the scene: images, ``/camera/ground_plane``, the target's mark, ground truth."""
    cfg.validate()
    cam = Camera.of(cfg)
    period_ns = 1e9 / cfg.fps
    total = cfg.empty_frames + cfg.frames
    heights = []
    with LogWriter(out) as log:
        for i, image, objects in frames_of(cfg):
            t_ns = int(round(i * period_ns))
            if i == 0:
                log.write(T.CAMERA_GROUND_PLANE, cam.calibration(cfg).to_pb(t_ns), t_ns)
            target = objects[0]
            if i == cfg.empty_frames and target.visible:
                log.write(T.ANNOTATIONS_INIT, init_annotations_pb(
                    [InitRegion(i, t_ns, target.x, target.y, target.w, target.h, "target")], t_ns), t_ns)
            if target.visible:
                heights.append(target.h)
            log.write(T.CAMERA_IMAGE, image_message(image, cfg.encoding, t_ns, jpeg_quality=cfg.jpeg_quality), t_ns)
            log.write(T.GROUNDTRUTH, GroundTruthFrame(i, t_ns, tuple(objects)).to_pb(), t_ns)
            if progress is not None:
                progress(i + 1, total)
    return SceneSummary(total, cfg.empty_frames, (min(heights, default=0.0), max(heights, default=0.0)))
