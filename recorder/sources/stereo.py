"""Stereo pairs (two videos or two image folders) and camera calibration files.

Calibration file: JSON (``.json``) or OpenCV FileStorage (``.yaml``/``.yml``/``.xml``) with

- ``width``, ``height`` (or ``image_width``, ``image_height``): image size in pixels;
- ``K`` (or ``camera_matrix``): 3x3 intrinsics, nested or flat row-major;
- ``D`` (or ``distortion_coefficients``): optional, default none; ``distortion_model`` optional
  (default ``plumb_bob``, or ``rational_polynomial`` for 8 coefficients);
- ``R`` (3x3, default identity; or ``rectification_matrix``) and ``P`` (3x4, default ``[K | 0]``; or
  ``projection_matrix``): optional. A ROS ``camera_info`` YAML (matrices as ``rows``, ``cols``,
  ``data``) is read as it is;
- stereo only: ``baseline_m`` (metres, the right camera ``baseline_m`` to the right of the left),
  or the right camera's own ``right_P``; ``right_K``/``right_D``/``right_R`` optional (default: the
  left's). The right ``P`` defaults to ``[right_K | (-fx * baseline_m, 0, 0)]``;
- stereo, optional: the rig's pose in a world frame (metres, Z up), ``world_t`` (the left camera's
  centre in the world) with ``world_R`` (3x3, left camera frame → world: ``p_world = R p_cam + t``)
  or ``world_quaternion`` (``x y z w`` of that rotation). ``record`` writes it on ``/stereo/pose``
  and the group tracker then reports positions in that world frame.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from trackreplay.recorder.sources.base import FrameClock, ImageFrame, read_json, read_text, require_file
from trackreplay.recorder.sources.images import check_count, list_images, read_image_files
from trackreplay.recorder.sources.video import read_video, video_fps
from foxglove_schemas_protobuf.Quaternion_pb2 import Quaternion
from foxglove_schemas_protobuf.Vector3_pb2 import Vector3

from trackreplay.schemas import messages as m
from trackreplay.schemas.errors import SourceError
from trackreplay.schemas.records import timestamp
from trackreplay.trackers.geometry.rig_pose import RigPose

_ALIASES = {
    "width": ("width", "image_width"),
    "height": ("height", "image_height"),
    "K": ("K", "camera_matrix"),
    "D": ("D", "distortion_coefficients"),
    "R": ("R", "rectification_matrix"),
    "P": ("P", "projection_matrix"),
}


@dataclass(frozen=True)
class CameraModel:
    """One camera's calibration, flattened as ``foxglove.CameraCalibration`` wants it."""

    width: int
    height: int
    K: tuple[float, ...]  # 9, row-major
    D: tuple[float, ...]
    R: tuple[float, ...]  # 9
    P: tuple[float, ...]  # 12
    distortion_model: str = "plumb_bob"

    def to_pb(self, t_ns: int, frame_id: str) -> m.CameraCalibration:
        return m.CameraCalibration(
            timestamp=timestamp(t_ns), frame_id=frame_id, width=self.width, height=self.height,
            distortion_model=self.distortion_model, D=list(self.D), K=list(self.K), R=list(self.R), P=list(self.P),
        )


@dataclass(frozen=True)
class Calibration:
    left: CameraModel  # the mono camera, or the left of a pair
    right: CameraModel | None = None
    pose: RigPose | None = None  # a pair's left camera in a world frame (Z up), when the file gives it
    path: str = ""  # the file it was read from (for messages)

    @property
    def baseline_m(self) -> float | None:
        if self.right is None or self.right.P[0] == 0:
            return None
        return -self.right.P[3] / self.right.P[0]


def _load_json(path: Path) -> dict[str, Any]:
    data = read_json(path)
    if not isinstance(data, dict):
        raise SourceError(f"calibration {path} must hold a JSON object")
    return data


def _load_opencv(path: Path) -> dict[str, Any]:
    read_text(path)  # OpenCV's own parser reports bad bytes without a line
    try:
        return _read_file_storage(path)
    except (cv2.error, SystemError) as err:  # OpenCV's parser errors; SystemError wraps them on open
        reason = str(err.__cause__ or err).strip().splitlines()[-1] if str(err.__cause__ or err).strip() else type(err).__name__
        raise SourceError(f"calibration {path} cannot be read as OpenCV YAML/XML ({reason})") from None


def _read_file_storage(path: Path) -> dict[str, Any]:
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
    if not fs.isOpened():
        raise SourceError(f"calibration {path} cannot be read as OpenCV YAML/XML")
    try:
        out: dict[str, Any] = {}
        root = fs.root()
        for key in root.keys():
            node = root.getNode(key)
            if node.isMap() and not node.empty() and node.getNode("data").isSeq():
                if node.getNode("dt").empty():  # a ROS camera_info matrix: rows, cols and data, no OpenCV type
                    data = node.getNode("data")
                    out[key] = [data.at(i).real() for i in range(data.size())]
                else:
                    out[key] = node.mat().tolist()  # an opencv-matrix
            elif node.isSeq():
                out[key] = [node.at(i).real() for i in range(node.size())]
            elif node.isReal() or node.isInt():
                out[key] = node.real()
            elif node.isString():
                out[key] = node.string()
        return out
    finally:
        fs.release()


def _get(data: dict[str, Any], key: str, path: Path, default: Any = None, required: bool = False) -> Any:
    for name in _ALIASES.get(key, (key,)):
        if name in data:
            return data[name]
    if required:
        raise SourceError(f"calibration {path} has no {key!r}")
    return default


MAX_CALIBRATION_VALUE = 1e300
MAX_SIDE = 1 << 18  # pixels; a picture's side (images are limited to 2**28 pixels)


def _floats(value: Any, n: int, key: str, path: Path) -> tuple[float, ...]:
    try:
        arr = np.asarray(value, dtype=np.float64).ravel()
    except (TypeError, ValueError):
        raise SourceError(f"calibration {path}: {key} is not a list of numbers") from None
    if n and arr.size != n:
        raise SourceError(f"calibration {path}: {key} has {arr.size} numbers, expected {n}")
    # OpenCV's YAML reader reads `nan` (ROS camera_info writes it so) as the largest double: no
    # calibration value comes near that
    if not np.all(np.isfinite(arr)) or np.any(np.abs(arr) >= MAX_CALIBRATION_VALUE):
        raise SourceError(f"calibration {path}: {key} holds a non-finite number (nan or inf)")
    return tuple(float(v) for v in arr)


def _camera(data: dict[str, Any], path: Path, prefix: str, fallback: CameraModel | None, baseline: float | None) -> CameraModel:
    def get(key: str, default: Any = None, required: bool = False) -> Any:
        return _get(data, prefix + key, path, default, required)

    if fallback is None:
        width, height = get("width", required=True), get("height", required=True)
        # whole numbers (OpenCV YAML reads 640 as 640.0), not "640", 640.5 or true
        if not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and float(v).is_integer()
                   for v in (width, height)):
            raise SourceError(f"calibration {path}: width and height must be integers, not {width!r} and {height!r}")
        if not (0 < width <= MAX_SIDE and 0 < height <= MAX_SIDE):  # (a `nan` read by OpenCV is 1.8e308)
            raise SourceError(f"calibration {path}: width and height must be positive, at most {MAX_SIDE} pixels, "
                              f"not {width:g} and {height:g}")
        width, height = int(width), int(height)
    else:
        width, height = fallback.width, fallback.height
    k_raw = get("K")
    K = _floats(k_raw, 9, prefix + "K", path) if k_raw is not None else (fallback.K if fallback else None)
    if K is None:
        raise SourceError(f"calibration {path} has no 'K'")
    if K[0] <= 0 or K[4] <= 0:
        raise SourceError(f"calibration {path}: {prefix}K must have positive fx and fy")
    d_raw = get("D")
    D = _floats(d_raw, 0, prefix + "D", path) if d_raw is not None else (fallback.D if fallback else ())
    r_raw = get("R")
    R = _floats(r_raw, 9, prefix + "R", path) if r_raw is not None else (fallback.R if fallback else (1.0, 0, 0, 0, 1.0, 0, 0, 0, 1.0))
    p_raw = get("P")
    if p_raw is not None:
        P = _floats(p_raw, 12, prefix + "P", path)
    else:
        tx = -K[0] * baseline if baseline is not None else 0.0
        P = (K[0], K[1], K[2], tx, K[3], K[4], K[5], 0.0, K[6], K[7], K[8], 0.0)
    model = get("distortion_model") or ("rational_polynomial" if len(D) == 8 else "plumb_bob")
    return CameraModel(width, height, K, D, tuple(float(v) for v in R), P, str(model))


def load_calibration(path: str | Path, stereo: bool = False) -> Calibration:
    """Read a calibration file (format in this module's docstring)."""
    path = require_file(path, "calibration")
    data = _load_opencv(path) if path.suffix.lower() in (".yaml", ".yml", ".xml") else _load_json(path)
    left = _camera(data, path, "", None, None)
    if not stereo:
        return Calibration(left, path=str(path))
    baseline = data.get("baseline_m")
    if baseline is None and "right_P" not in data:
        raise SourceError(f"calibration {path} needs 'baseline_m' or 'right_P' for a stereo pair")
    if baseline is not None:
        if isinstance(baseline, bool) or not isinstance(baseline, (int, float)):  # (not "0.12", not true)
            raise SourceError(f"calibration {path}: baseline_m is not a number")
        baseline = float(baseline)
        if not (math.isfinite(baseline) and 0 < baseline < MAX_CALIBRATION_VALUE):
            raise SourceError(f"calibration {path}: baseline_m must be a finite positive number of metres, not {baseline!r}")
    right = _camera(data, path, "right_", left, baseline)
    # the baseline the right P implies (P_right[3] = -fx_right * baseline), as the replay reads it
    implied = -right.P[3] / right.P[0] + 0.0  # (+ 0.0: no "-0" in the message)
    if not (math.isfinite(implied) and implied > 0):
        raise SourceError(f"calibration {path}: right_P puts the right camera {implied:g} m to the right of the left "
                          "(need a finite positive baseline: P[3] = -fx * baseline_m < 0)")
    if baseline is not None and "right_P" in data and not math.isclose(implied, baseline, rel_tol=1e-6):
        raise SourceError(f"calibration {path}: baseline_m {baseline:g} and right_P ({implied:g} m) disagree; give one")
    return Calibration(left, right, _pose(data, path), str(path))


def pose_message(pose: RigPose, t_ns: int) -> m.FrameTransform:
    """The left camera in the world (Z up) as ``foxglove.FrameTransform`` (parent ``world``, child ``left``)."""
    q, c = pose.quaternion, pose.t
    return m.FrameTransform(timestamp=timestamp(t_ns), parent_frame_id="world", child_frame_id="left",
                            translation=Vector3(x=c[0], y=c[1], z=c[2]), rotation=Quaternion(x=q[0], y=q[1], z=q[2], w=q[3]))


def _pose(data: dict[str, Any], path: Path) -> RigPose | None:
    """The rig's world pose from ``world_t`` with ``world_R`` or ``world_quaternion`` (None without ``world_t``)."""
    given = [k for k in ("world_t", "world_R", "world_quaternion") if k in data]
    if not given:
        return None
    if "world_t" not in data or ("world_R" in data) == ("world_quaternion" in data):
        raise SourceError(f"calibration {path}: a rig pose needs world_t and one of world_R or world_quaternion, "
                          f"got {', '.join(given)}")
    t = _floats(data["world_t"], 3, "world_t", path)
    try:
        if "world_R" in data:
            return RigPose(_floats(data["world_R"], 9, "world_R", path), (t[0], t[1], t[2]))
        return RigPose.from_quaternion(np.array(_floats(data["world_quaternion"], 4, "world_quaternion", path)), np.array(t))
    except ValueError as err:
        raise SourceError(f"calibration {path}: {err}") from None


@dataclass(frozen=True)
class StereoSource:
    """Two videos or two image folders, checked for equal counts where that is known up front."""

    left: Path
    right: Path

    @property
    def is_folders(self) -> bool:
        return self.left.is_dir()

    def check(self, clock: FrameClock) -> int | None:
        """Validate before recording; the pair count when known."""
        for side in (self.left, self.right):
            if not side.exists():
                raise SourceError(f"stereo input {side} does not exist")
        if self.left.is_dir() != self.right.is_dir():
            raise SourceError(f"stereo inputs {self.left} and {self.right} must both be folders or both be videos")
        if not self.is_folders:
            require_file(self.left, "video")
            require_file(self.right, "video")
            rates = video_fps(self.left), video_fps(self.right)
            if all(r > 0 for r in rates) and abs(rates[0] - rates[1]) > 1e-3 * max(rates):  # frame k of each: not one moment
                raise SourceError(f"stereo videos run at different rates: {self.left} {rates[0]:g} fps, {self.right} {rates[1]:g} fps")
            return None
        lf, rf = list_images(self.left), list_images(self.right)
        if len(lf) != len(rf):
            raise SourceError(f"stereo folders differ in length: {self.left} has {len(lf)} images, {self.right} has {len(rf)}")
        check_count(lf, clock, self.left)
        return len(lf)

    def pairs(self, clock: FrameClock) -> Iterator[tuple[ImageFrame, ImageFrame]]:
        if self.is_folders:
            left, right = read_image_files(list_images(self.left), clock), read_image_files(list_images(self.right), clock)
        else:
            left, right = read_video(self.left, clock), read_video(self.right, clock)
        count = 0
        for lf in left:
            rf = next(right, None)
            if rf is None:
                raise SourceError(f"stereo videos differ in length: {self.right} ends after {count} frames, {self.left} goes on")
            if lf.index != rf.index:  # (a frame of one video did not decode)
                raise SourceError(f"stereo videos lost different frames: {lf.where} is paired with {rf.where}")
            if lf.size != rf.size:
                raise SourceError(f"{rf.where} is {rf.size[0]}x{rf.size[1]} but {lf.where} is {lf.size[0]}x{lf.size[1]}")
            if (lf.pixels.ndim == 3) != (rf.pixels.ndim == 3):  # a replay would refuse the pair: one kind for both
                grey, colour = (lf, rf) if lf.pixels.ndim == 2 else (rf, lf)
                raise SourceError(f"{grey.where} is grey but {colour.where} is colour; record both views alike")
            count += 1
            yield lf, rf
        if next(right, None) is not None:
            raise SourceError(f"stereo videos differ in length: {self.left} ends after {count} frames, {self.right} goes on")


def read_stereo(left: str | Path, right: str | Path, clock: FrameClock) -> Iterator[tuple[ImageFrame, ImageFrame]]:
    """(left, right) frame pairs with equal ``t_ns``."""
    source = StereoSource(Path(left), Path(right))
    source.check(clock)
    yield from source.pairs(clock)
