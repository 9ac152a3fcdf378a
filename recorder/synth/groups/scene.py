"""Synthetic stereo crowds for the group tracker (seed 003 §4): ``trackreplay synth groups-…``.

Scenes (people walk in groups on the ground seen by a rectified stereo rig like the paper's):

- ``groups-crossing``: a group of 2 (right → left) and a group of 3 (left → right) cross with
  partial occlusion (5.1 m high, 40° down);
- ``groups-merging``: a group of 2 and a group of 3 walk towards each other, then on together: from
  ``merge_s`` they are one group (ground-truth group 3);
- ``groups-stairs``: a group of 3 walks to a staircase and climbs it (2.1 m high, 15° down);
- ``groups-passing``: a fast group of 2 overtakes a slow group of 3 close beside it (1.9 vs 0.9
  m/s, 0.6 m between them): they must not merge.

The log holds ``/stereo/left|right/image`` (PNG), both ``CameraCalibration``s, and per frame
``/groundtruth/objects`` (every person: image box, torso centre X Y Z in the left camera's frame,
image velocity, visibility, group id) and ``/groundtruth/groups`` (every group: the union of its
members' boxes, the mean of their torso centres, id = group id). The first ``lead_in`` frames
show the empty scene (the background the tracker learns); ground truth starts after them.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from trackreplay.recorder.image_codec import image_message
from trackreplay.recorder.sources.stereo import CameraModel, pose_message
from trackreplay.recorder.synth.groups.people import HEIGHT, TORSO_Z, Look, Painter, person_corners, person_faces
from trackreplay.recorder.synth.groups.world import Rig, Stairs, World
from trackreplay.recorder.writer import LogWriter
from trackreplay.schemas import topics as T

from trackreplay.schemas.messages import FrameTransform
from trackreplay.schemas.records import GroundTruthFrame, GroundTruthObject, timestamp
from trackreplay.trackers.geometry.rig_pose import RigPose

GROUNDTRUTH_GROUPS = "/groundtruth/groups"
SCENES = ("groups-crossing", "groups-merging", "groups-stairs", "groups-passing")
STRIDE_M = 1.4  # one full leg cycle per 1.4 m walked


@dataclass(frozen=True)
class GroupScript:
    gid: int
    offsets: tuple[tuple[float, float], ...]  # members' (dX, dY) from the group's centre, world metres
    waypoints: tuple[tuple[float, float, float], ...]  # (t_s, X, Y) of the centre, linear in between
    relabel: tuple[float, int] | None = None  # (from t_s, new group id): the group joined another

    def centre(self, t: float) -> np.ndarray:
        w = np.asarray(self.waypoints, dtype=np.float64)
        return np.array([np.interp(t, w[:, 0], w[:, 1]), np.interp(t, w[:, 0], w[:, 2])])

    def gid_at(self, t: float) -> int:
        return self.relabel[1] if self.relabel is not None and t >= self.relabel[0] else self.gid


def scripts(scene: str, merge_s: float = 2.0) -> tuple[Rig, Stairs | None, tuple[GroupScript, ...]]:
    if scene == "groups-crossing":
        return Rig(), None, (
            GroupScript(1, ((0.0, -0.35), (0.1, 0.35)), ((0.0, 3.4, 8.8), (4.0, -3.0, 8.8))),
            GroupScript(2, ((0.0, -0.6), (0.15, 0.0), (0.0, 0.6)), ((0.0, -3.4, 7.2), (4.0, 3.0, 7.2))),
        )
    if scene == "groups-merging":
        return Rig(), None, (
            GroupScript(1, ((0.0, -0.35), (0.0, 0.35)), ((0.0, -3.5, 8.0), (merge_s, -0.5, 8.0), (4.0, -0.5, 10.6)),
                        (merge_s, 3)),
            GroupScript(2, ((0.0, -0.6), (0.0, 0.0), (0.0, 0.6)), ((0.0, 3.5, 8.0), (merge_s, 0.45, 8.0), (4.0, 0.45, 10.6)),
                        (merge_s, 3)),
        )
    if scene == "groups-passing":
        return Rig(), None, (
            GroupScript(1, ((0.0, -0.3), (0.0, 0.3)), ((0.0, -4.2, 9.0), (4.0, 3.4, 9.0))),
            GroupScript(2, ((0.0, -0.5), (0.1, 0.0), (0.0, 0.5)), ((0.0, -1.6, 7.6), (4.0, 2.0, 7.6))),
        )
    if scene == "groups-stairs":
        return Rig(height=2.1, tilt_deg=15.0), Stairs(), (
            GroupScript(1, ((-0.5, 0.0), (0.0, 0.3), (0.5, 0.0)), ((0.0, 0.3, 2.9), (1.4, 0.1, 4.5), (4.0, -0.1, 6.6))),
        )
    raise ValueError(f"unknown scene {scene!r}; choose one of {', '.join(SCENES)}")


@dataclass(frozen=True)
class GroupSceneConfig:
    scene: str = "groups-crossing"
    seed: int = 0
    fps: float = 48.0  # Bumblebee2 in the paper
    duration: float = 4.0  # s of walking after the lead-in
    lead_in: int = 10  # empty frames first (the background)
    noise: float = 2.0  # grey levels, Gaussian, per pixel and view
    merge_s: float = 2.0  # groups-merging: when the two groups become one
    start_s: float = 0.0  # script time of the first frame after the lead-in (a short clip from mid-scene)
    encoding: str = "png"
    jpeg_quality: int = 95
    width: int = 640
    height: int = 480

    def validate(self) -> None:
        if self.scene not in SCENES:
            raise ValueError(f"unknown scene {self.scene!r}; choose one of {', '.join(SCENES)}")
        if self.fps <= 0 or self.duration <= 0 or self.lead_in < 1 or self.start_s < 0:
            raise ValueError("fps and duration must be positive and lead_in at least 1 frame")
        if not (self.fps <= 240.0 and self.duration <= 120.0):  # as the golf scene: a review's --duration 1e9 ran until killed
            raise ValueError(f"fps must be at most 240 and duration at most 120 s, not {self.fps:g} and {self.duration:g}")


@dataclass(frozen=True)
class Person:
    pid: int
    group: GroupScript
    offset: np.ndarray
    look: Look


@dataclass
class SceneSummary:
    frames: int
    people: int
    groups: list[int] = field(default_factory=list)

    def describe(self) -> str:
        return f"{self.frames} stereo frames, {self.people} people in groups {self.groups}"


def calibration(rig: Rig) -> tuple[CameraModel, CameraModel]:
    f, cx, cy, b = rig.f, rig.cx, rig.cy, rig.baseline
    K = (f, 0.0, cx, 0.0, f, cy, 0.0, 0.0, 1.0)
    eye = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)
    left = CameraModel(rig.width, rig.height_px, K, (), eye, (f, 0.0, cx, 0.0, 0.0, f, cy, 0.0, 0.0, 0.0, 1.0, 0.0))
    right = CameraModel(rig.width, rig.height_px, K, (), eye, (f, 0.0, cx, -f * b, 0.0, f, cy, 0.0, 0.0, 0.0, 1.0, 0.0))
    return left, right


class GroupScene:
    """Renders one scene frame by frame (both views, the id image and the truth)."""

    def __init__(self, cfg: GroupSceneConfig) -> None:
        cfg.validate()
        self.cfg = cfg
        rig, stairs, groups = scripts(cfg.scene, cfg.merge_s)
        self.rig = replace(rig, width=cfg.width, height_px=cfg.height)
        self.world = World(seed=cfg.seed, stairs=stairs)
        self.groups = groups
        people, pid = [], 1
        for g in groups:
            for off in g.offsets:
                people.append(Person(pid, g, np.asarray(off, np.float64), Look.make(cfg.seed * 100 + pid)))
                pid += 1
        self.people = people
        self.backgrounds = (self.world.background(self.rig, False), self.world.background(self.rig, True))
        self.noise_rng = np.random.default_rng(np.random.SeedSequence(cfg.seed, spawn_key=(0x5E3,)))

    @property
    def frames(self) -> int:
        return self.cfg.lead_in + int(round(self.cfg.duration * self.cfg.fps))

    def pose(self, person: Person, t: float) -> tuple[np.ndarray, float, float]:
        """Ground point (world, on the stairs if any), heading and stride phase at ``t``."""
        xy = person.group.centre(t) + person.offset
        dt = 0.05
        v = person.group.centre(t + dt) - person.group.centre(max(t - dt, 0.0))
        if np.hypot(*v) < 1e-6:
            v = person.group.centre(t) - person.group.centre(max(t - 2 * dt, 0.0))
        heading = float(np.arctan2(v[1], v[0])) if np.hypot(*v) > 1e-6 else 0.0
        walked = self._walked(person.group, t)
        z = float(self.world.ground_height(xy[1]))
        return np.array([xy[0], xy[1], z]), heading, 2.0 * np.pi * walked / STRIDE_M + person.pid

    @staticmethod
    def _walked(group: GroupScript, t: float) -> float:
        w = np.asarray(group.waypoints, dtype=np.float64)
        ts = np.append(w[:, 0][w[:, 0] < t], t)
        pts = np.stack([np.interp(ts, w[:, 0], w[:, 1]), np.interp(ts, w[:, 0], w[:, 2])], axis=1)
        return float(np.linalg.norm(np.diff(pts, axis=0), axis=1).sum()) if len(pts) > 1 else 0.0

    def render(self, index: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, float | None]:
        """Left, right (BGR uint8), the left id image (person id, 0 background), time t (None in the lead-in)."""
        left, right = self.backgrounds[0].copy(), self.backgrounds[1].copy()
        ids = np.zeros(left.shape[:2], np.int32)
        t = None if index < self.cfg.lead_in else self.cfg.start_s + (index - self.cfg.lead_in) / self.cfg.fps
        if t is not None:
            faces, textures, owners = [], [], []
            for p in self.people:
                ground, heading, phase = self.pose(p, t)
                f, tx = person_faces(ground, heading, phase, p.look)
                faces += f
                textures += tx
                owners += [p.pid] * len(f)
            Painter(self.rig, False, left, ids).draw_faces(faces, textures, owners)
            Painter(self.rig, True, right).draw_faces(faces, textures, owners)
        out = []
        for image in (left, right):
            noisy = image.astype(np.float32) + np.float32(self.cfg.noise) * self.noise_rng.standard_normal(image.shape, dtype=np.float32)
            out.append(np.clip(np.round(noisy), 0, 255).astype(np.uint8))
        return out[0], out[1], ids, t

    def truth(self, index: int, t: float, ids: np.ndarray) -> tuple[GroundTruthFrame, GroundTruthFrame, dict]:
        cfg, rig = self.cfg, self.rig
        t_ns = self.t_ns(index)
        counts = np.bincount(ids.ravel(), minlength=len(self.people) + 1)
        persons, by_group = [], {}
        boxes = {}
        for p in self.people:
            box, centre = self._box_and_centre(p, t)
            prev = self._box_and_centre(p, t - 1.0 / cfg.fps)[0] if index > cfg.lead_in else None
            visible = bool(counts[p.pid] >= 40)
            gid = p.group.gid_at(t)
            vx = None if prev is None else float(box[0] - prev[0])
            vy = None if prev is None else float(box[1] - prev[1])
            persons.append(GroundTruthObject(p.pid, *map(float, box), *map(float, centre), vx, vy, visible, gid))
            by_group.setdefault(gid, []).append((box, centre, visible))
            boxes[p.pid] = box
        groups = []
        for gid in sorted(by_group):
            members = by_group[gid]
            b = np.array([m[0] for m in members])
            x0, y0 = (b[:, :2] - b[:, 2:] / 2).min(axis=0)
            x1, y1 = (b[:, :2] + b[:, 2:] / 2).max(axis=0)
            c = np.mean([m[1] for m in members], axis=0)
            groups.append(GroundTruthObject(gid, float((x0 + x1) / 2), float((y0 + y1) / 2), float(x1 - x0), float(y1 - y0),
                                            *map(float, c), None, None, any(m[2] for m in members), gid))
        return GroundTruthFrame(index, t_ns, tuple(persons)), GroundTruthFrame(index, t_ns, tuple(groups)), boxes

    def _box_and_centre(self, p: Person, t: float) -> tuple[np.ndarray, np.ndarray]:
        ground, heading, phase = self.pose(p, max(t, 0.0))
        uv = self.rig.project(self.rig.to_camera(person_corners(ground, heading, phase)))
        lo = np.maximum(uv.min(axis=0), 0.0)
        hi = np.minimum(uv.max(axis=0), [self.rig.width - 1.0, self.rig.height_px - 1.0])
        box = np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, max(hi[0] - lo[0], 0.0), max(hi[1] - lo[1], 0.0)])
        centre = self.rig.to_camera((ground + [0.0, 0.0, TORSO_Z])[None])[0]
        return box, centre

    def t_ns(self, index: int) -> int:
        return int(round(index * 1e9 / self.cfg.fps))


def rig_pose_message(rig: Rig, t_ns: int) -> FrameTransform:
    """The left camera in the world (Z up) as ``foxglove.FrameTransform`` (parent ``world``, child ``left``)."""
    return pose_message(RigPose(tuple(float(v) for v in rig.R.T.ravel()), tuple(float(v) for v in rig.centre)), t_ns)


def write_group_scene(out: str | Path, cfg: GroupSceneConfig,
                      progress: Callable[[int, int], None] | None = None) -> SceneSummary:
    """Render ``cfg.scene`` to ``out``."""
    scene = GroupScene(cfg)
    left_cal, right_cal = calibration(scene.rig)
    total = scene.frames
    with LogWriter(out) as log:
        log.add_metadata("groups_scene", {
            "scene": cfg.scene, "seed": str(cfg.seed), "fps": repr(cfg.fps), "rig_height_m": repr(scene.rig.height),
            "rig_tilt_deg": repr(scene.rig.tilt_deg), "lead_in": str(cfg.lead_in), "merge_s": repr(cfg.merge_s),
            "start_s": repr(cfg.start_s),
            "person_height_m": repr(HEIGHT),
        })
        for index in range(total):
            t_ns = scene.t_ns(index)
            if index == 0:
                log.write(T.STEREO_LEFT_CALIBRATION, left_cal.to_pb(t_ns, "left"), t_ns)
                log.write(T.STEREO_RIGHT_CALIBRATION, right_cal.to_pb(t_ns, "right"), t_ns)
                log.write(T.STEREO_POSE, rig_pose_message(scene.rig, t_ns), t_ns)
            left, right, ids, t = scene.render(index)
            log.write(T.STEREO_LEFT_IMAGE, image_message(left, cfg.encoding, t_ns, frame_id="left", jpeg_quality=cfg.jpeg_quality), t_ns)
            log.write(T.STEREO_RIGHT_IMAGE, image_message(right, cfg.encoding, t_ns, frame_id="right", jpeg_quality=cfg.jpeg_quality), t_ns)
            if t is not None:
                persons, groups, _ = scene.truth(index, t, ids)
                log.write(T.GROUNDTRUTH, persons.to_pb(), t_ns)
                log.write(GROUNDTRUTH_GROUPS, groups.to_pb(), t_ns)
            if progress is not None:
                progress(index + 1, total)
    return SceneSummary(total, len(scene.people), sorted({g.gid for g in scene.groups} | {
        g.relabel[1] for g in scene.groups if g.relabel is not None}))
