"""`trackreplay synth golf-teeshot`: a broadcast tee shot with PTZ encoders and ground truth.

One ball flies, bounces and rolls (``flight``); an operator follows it with a PTZ head and a 20x
lens (``operator``, ``lens``); every frame is rendered from the world model under the true pose
(``render``); ground truth and the user's marked ball regions come from the same model
(``truth``). The log holds:

- ``/camera/image``: JPEG frames at ``k / fps`` (t0 = 0);
- ``/ptz/encoders``: readings at the encoders' own rate, with noise and quantisation unless
  ``encoder_noise=False`` (the pose the renderer used is the exact, noise-free path);
- ``/ptz/lens_table``: once at t0 (zoom/focus counts -> intrinsics, camera position);
- ``/groundtruth/objects``: per frame, object id 1 = the ball;
- ``/annotations/init``: once at t0, ``"ball"`` boxes over sky and over ground on real frames.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from trackreplay.recorder.image_codec import image_message
from trackreplay.recorder.synth.golf.flight import BallModel, Launch, Trajectory, simulate_shot
from trackreplay.recorder.synth.golf.lens import BroadcastLens
from trackreplay.recorder.synth.golf.operator import (
    CameraPath, EncoderModel, OperatorConfig, ShotTimes, encoder_readings, follow_ball,
)
from trackreplay.recorder.synth.golf.render import FrameView, GolfRenderer
from trackreplay.recorder.synth.golf.truth import Annotation, FrameTruth, choose_annotations, frame_truth
from trackreplay.recorder.synth.golf.occluders import build_occluder
from trackreplay.recorder.synth.golf.world import World, build_blobs, build_course, sun_direction
from trackreplay.recorder.writer import LogWriter
from trackreplay.schemas import topics as T
from trackreplay.schemas.errors import TrackreplayError
from trackreplay.schemas.records import LensTable, PtzReading, init_annotations_pb
from trackreplay.trackers.geometry.ptz import PtzCamera

SCENE = "golf-teeshot"
SIZES = {"720p": (1280, 720), "1080p": (1920, 1080)}
CAMERA_PLACES = {"behind": (-10.0, -2.0, 2.5), "beside": (20.0, -35.0, 3.0)}
GRID_DT = 1e-3  # s, the operator's (and the camera truth's) time step


class SceneConfigError(TrackreplayError):
    """A golf-teeshot option is out of range (one sentence naming the option)."""


@dataclass(frozen=True)
class GolfSceneConfig:
    """A synthetic broadcast tee shot. Times are seconds on the log clock (first frame at 0)."""

    seed: int = 0
    width: int = 1280  # 720p; 1920x1080 for 1080p; smaller sizes are allowed (tests)
    height: int = 720
    fps: float = 30.0
    duration: float | None = None  # None: until the ball has rested for 1 s (at most max_duration)
    max_duration: float = 20.0
    launch_at: float = 0.5  # the ball sits on the tee before this
    launch: Launch = Launch(speed=46.0, elevation=22.0, azimuth=0.0, backspin_rpm=8000.0)
    ball: BallModel = BallModel(friction=0.6, rolling_resistance=0.3)
    camera: str = "behind"  # "behind" the tee or "beside" it (see CAMERA_PLACES)
    camera_position: tuple[float, float, float] | None = None  # overrides ``camera``
    operator: OperatorConfig = OperatorConfig()
    encoders: EncoderModel = EncoderModel()
    encoder_noise: bool = True  # False: the logged readings are the exact path (geometry tests)
    shutter: float = 0.5  # exposure as a fraction of the frame interval (motion blur)
    distractors: bool = True  # tee markers, spare balls, a bird
    jpeg_quality: int = 90
    # Variants.
    bounce: bool = True  # False: the ball checks into the turf and rolls out, no hop
    cut_at: float | None = None  # a camera cut / fast zoom at this time (snapped to a frame)
    occlusion: tuple[float, float] | None = None  # ball hidden behind a tree in [start, end)
    encoder_dropout: tuple[float, float] | None = None  # no encoder readings in [start, end)

    def validate(self) -> None:
        def bad(msg: str) -> SceneConfigError:
            return SceneConfigError(f"golf-teeshot: {msg}")

        if self.width < 64 or self.height < 48:
            raise bad(f"image size {self.width}x{self.height} is too small (at least 64x48)")
        if not 1.0 <= self.fps <= 240.0:
            raise bad(f"--fps must be between 1 and 240, not {self.fps}")
        if self.duration is not None and not 0.0 < self.duration <= 120.0:
            raise bad(f"--duration must be in (0, 120] seconds, not {self.duration}")
        if self.camera_position is None and self.camera not in CAMERA_PLACES:
            raise bad(f"camera must be one of {', '.join(CAMERA_PLACES)}, not {self.camera!r}")
        if not 0.0 <= self.shutter <= 1.0:
            raise bad(f"shutter must be a fraction of the frame interval in [0, 1], not {self.shutter}")
        if self.launch.speed <= 0.0:
            raise bad(f"launch speed must be positive, not {self.launch.speed}")
        for name in ("occlusion", "encoder_dropout"):
            window = getattr(self, name)
            if window is not None and not (0.0 <= window[0] < window[1]):
                flag = "--" + name.replace("_", "-")
                raise bad(f"{flag} needs START < END with START >= 0, got {window[0]} {window[1]}")
        if self.cut_at is not None and self.cut_at < 0.0:
            raise bad(f"--cut must be a time >= 0, not {self.cut_at}")

    @property
    def camera_xyz(self) -> np.ndarray:
        return np.array(self.camera_position if self.camera_position is not None else CAMERA_PLACES[self.camera], dtype=np.float64)


@dataclass(frozen=True)
class GolfSceneSummary:
    """What was written, and the facts a tracker test wants to compare against."""

    path: str
    frames: int
    fps: float
    duration: float
    width: int
    height: int
    encoder_readings: int
    launch_time: float
    apex_time: float
    apex_height: float
    landing_time: float
    landing_frame: int | None  # first frame at or after the landing; None when the log ends before it
    landing_point: tuple[float, float, float]
    carry: float
    bounce_times: tuple[float, ...]
    rest_time: float
    rest_point: tuple[float, float, float]
    cut_time: float | None
    in_frame_frames: int
    visible_frames: int
    ball_diameter_px_at_landing: float | None  # None when the log ends before the landing
    annotation_frames_sky: tuple[int, ...]
    annotation_frames_ground: tuple[int, ...]

    def describe(self) -> str:
        return (
            f"{self.frames} frames {self.width}x{self.height} @ {self.fps:g} fps ({self.duration:.2f} s), "
            f"{self.encoder_readings} encoder readings; launch {self.launch_time:.2f} s, apex {self.apex_height:.1f} m, "
            f"landing {self.landing_time:.2f} s"
            + ("" if self.landing_frame is None else f" (frame {self.landing_frame})")
            + f" after {self.carry:.1f} m carry, rest {self.rest_time:.2f} s; ball visible in {self.visible_frames} frames"
            + ("" if self.ball_diameter_px_at_landing is None else f", {self.ball_diameter_px_at_landing:.1f} px across at landing")
        )


@dataclass
class GolfShot:
    """Everything but the pixels: the physics, the camera path, the world and the per-frame truth."""

    cfg: GolfSceneConfig
    trajectory: Trajectory
    path: CameraPath
    lens: BroadcastLens
    lens_table: LensTable
    world: World
    frame_times: np.ndarray
    duration: float
    cut_time: float | None
    encoder_seed: np.random.SeedSequence
    truth: list[FrameTruth] = field(default_factory=list)

    def ball_at(self, t: float | np.ndarray) -> np.ndarray:
        """Ball centre(s) at log-clock time(s) ``t``."""
        return self.trajectory.sample(np.atleast_1d(t) - self.cfg.launch_at).position

    def camera_at(self, t: float) -> PtzCamera:
        """The true (noise-free) camera at log-clock time ``t``."""
        pan, tilt, zoom, focus = (float(a[0]) for a in self.path.at(t))
        return PtzCamera.from_reading(PtzReading(int(round(t * 1e9)), pan, tilt, zoom, focus), self.lens_table)

    def view(self, k: int) -> FrameView:
        """The frame's pose and the shutter sub-samples for motion blur."""
        t = float(self.frame_times[k])
        cam = self.camera_at(t)
        half = 0.5 * self.cfg.shutter / self.cfg.fps
        lo, hi = t - half, t + half
        if self.cut_time is not None and lo < self.cut_time <= hi:  # do not expose across a cut
            lo, hi = (self.cut_time, self.cut_time + 2 * half) if t >= self.cut_time else (self.cut_time - 2 * half - GRID_DT, self.cut_time - GRID_DT)
        if hi - lo <= 0.0:
            return FrameView(k, t, cam, np.array([t]), (cam,), self.ball_at(t))
        ends = self.ball_at(np.array([lo, hi]))
        ca, cb = self.camera_at(lo), self.camera_at(hi)
        ua, ub = ca.project_points(ends[0])[0], cb.project_points(ends[1])[0]
        streak = float(np.hypot(*(ub - ua))) if np.isfinite(ua).all() and np.isfinite(ub).all() else 0.0
        n = int(np.clip(math.ceil(streak / 0.5) + 1, 3, 48))
        # Odd count so the middle sub-sample is the capture time when the window is centred.
        n += 1 - n % 2
        times = np.linspace(lo, hi, n)
        cams = tuple(self.camera_at(float(s)) for s in times)
        return FrameView(k, t, cam, times, cams, self.ball_at(times))


def _snap_cut(cfg: GolfSceneConfig, duration: float) -> float | None:
    """The cut happens at a frame time that is also an encoder tick (so readings bracket it cleanly)."""
    if cfg.cut_at is None:
        return None
    k0 = int(math.ceil(cfg.cut_at * cfg.fps - 1e-9))
    for k in range(k0, k0 + int(cfg.fps) + 1):
        x = k / cfg.fps * cfg.encoders.rate_hz
        if abs(x - round(x)) < 1e-6 and abs(k / cfg.fps * 1000 - round(k / cfg.fps * 1000)) < 1e-6:
            return k / cfg.fps if k / cfg.fps < duration else None
    return k0 / cfg.fps if k0 / cfg.fps < duration else None


def plan_shot(cfg: GolfSceneConfig) -> GolfShot:
    """Simulate the shot, the operator and the world; no pixels yet (cheap)."""
    cfg.validate()
    root = np.random.SeedSequence(cfg.seed, spawn_key=(0x601F, 0x5C))
    world_ss, enc_ss = root.spawn(2)
    traj = simulate_shot(cfg.launch, cfg.ball, bounce=cfg.bounce, t_max=cfg.max_duration + 5.0)
    if cfg.duration is not None:
        duration = cfg.duration
    else:
        duration = min(cfg.launch_at + traj.rest_time + 1.0, cfg.max_duration)
    n_frames = max(1, int(math.floor(duration * cfg.fps + 1e-9)))
    frame_times = np.arange(n_frames) / cfg.fps
    cut_time = _snap_cut(cfg, duration)
    camera = cfg.camera_xyz
    lens = BroadcastLens(cfg.width, cfg.height)
    grid = np.arange(int(math.ceil((duration + 0.2) / GRID_DT)) + 1) * GRID_DT
    ball_grid = traj.sample(grid - cfg.launch_at).position
    shot = ShotTimes(cfg.launch_at, cfg.launch_at + traj.apex_time, cfg.launch_at + traj.landing_time)
    path = follow_ball(cfg.operator, lens, camera, grid, ball_grid, shot, cfg.ball.diameter, cut_time)
    rng = np.random.default_rng(world_ss)

    def ball_at(t: float) -> np.ndarray:
        return traj.sample([t - cfg.launch_at]).position[0]

    course = build_course(rng, traj)
    blobs = build_blobs(rng, traj, course, camera, ball_at, cfg.launch_at) if cfg.distractors else ()
    occluder = build_occluder(rng, camera, ball_at, cfg.occlusion, cfg.ball.radius) if cfg.occlusion is not None else None
    world = World(course, blobs, occluder, sun_direction())
    shot_plan = GolfShot(cfg, traj, path, lens, lens.table(tuple(camera)), world, frame_times, duration, cut_time, enc_ss)
    shot_plan.truth = [frame_truth(shot_plan, k) for k in range(n_frames)]
    return shot_plan


def write_golf_teeshot(out: str | Path, cfg: GolfSceneConfig = GolfSceneConfig(),
                       progress: Callable[[int, int], None] | None = None) -> GolfSceneSummary:
    """Render and write the scene to ``out``; ``progress(done, total)`` is called per frame."""
    shot = plan_shot(cfg)
    readings = logged_readings(shot)
    annotations = choose_annotations(shot)
    regions = [a.region for a in annotations]
    renderer = GolfRenderer(shot.world, cfg.width, cfg.height, cfg.seed, ball_radius=cfg.ball.radius)
    n = len(shot.frame_times)
    frame_ns = [int(round(k * 1e9 / cfg.fps)) for k in range(n)]
    with LogWriter(out) as log:
        log.write(T.PTZ_LENS_TABLE, shot.lens_table.to_pb(0), 0)
        log.write(T.ANNOTATIONS_INIT, init_annotations_pb(regions, 0), 0)
        j = 0
        for k in range(n):
            while j < len(readings) and readings[j].t_ns <= frame_ns[k]:
                log.write(T.PTZ_ENCODERS, readings[j].to_pb(), readings[j].t_ns)
                j += 1
            image = renderer.render(shot.view(k))
            log.write(T.CAMERA_IMAGE, image_message(image, "jpeg", frame_ns[k], jpeg_quality=cfg.jpeg_quality), frame_ns[k])
            log.write(T.GROUNDTRUTH, shot.truth[k].record(frame_ns[k]).to_pb(), frame_ns[k])
            if progress is not None:
                progress(k + 1, n)
        for r in readings[j:]:
            log.write(T.PTZ_ENCODERS, r.to_pb(), r.t_ns)
    return summarise(shot, str(out), len(readings), annotations)


def logged_readings(shot: GolfShot) -> list[PtzReading]:
    """The encoder readings the log holds (noisy and quantised unless ``encoder_noise=False``)."""
    cfg = shot.cfg
    enc = cfg.encoders if cfg.encoder_noise else EncoderModel(rate_hz=cfg.encoders.rate_hz, noisy=False)
    return encoder_readings(shot.path, enc, np.random.default_rng(shot.encoder_seed), shot.duration, cfg.encoder_dropout)


def summarise(shot: GolfShot, path: str, n_readings: int, annotations: list[Annotation]) -> GolfSceneSummary:
    cfg, traj = shot.cfg, shot.trajectory
    land_t = cfg.launch_at + traj.landing_time
    land_k: int | None = int(math.ceil(land_t * cfg.fps - 1e-9))
    if land_k >= len(shot.frame_times):
        land_k = None
    sky = tuple(a.region.frame for a in annotations if a.background == "sky")
    ground = tuple(a.region.frame for a in annotations if a.background == "ground")
    diameter = None
    if land_t < shot.duration:
        cam = shot.camera_at(land_t)
        diameter = float(2.0 * cam.intrinsics.fx * cfg.ball.radius / np.linalg.norm(traj.landing_point - cam.position))
    return GolfSceneSummary(
        path=path, frames=len(shot.frame_times), fps=cfg.fps, duration=shot.duration, width=cfg.width, height=cfg.height,
        encoder_readings=n_readings, launch_time=cfg.launch_at, apex_time=cfg.launch_at + traj.apex_time,
        apex_height=float(traj.apex_point[2]), landing_time=land_t, landing_frame=land_k,
        landing_point=tuple(float(x) for x in traj.landing_point), carry=traj.carry,
        bounce_times=tuple(cfg.launch_at + b for b in traj.bounce_times), rest_time=cfg.launch_at + traj.rest_time,
        rest_point=tuple(float(x) for x in traj.rest_point), cut_time=shot.cut_time,
        in_frame_frames=sum(t.in_frame for t in shot.truth), visible_frames=sum(t.visible for t in shot.truth),
        ball_diameter_px_at_landing=diameter,
        annotation_frames_sky=sky, annotation_frames_ground=ground,
    )
