"""A fixed camera's ground-plane calibration from a small JSON file (``record --ground-plane FILE``).

The file is one JSON object::

    {
      "width": 720, "height": 480,              // image size the calibration is for (pixels)
      "image_to_ground": [[h11, h12, h13],      // 3x3 homography: (u, v, 1) pixels -> (X, Y, 1) metres
                          [h21, h22, h23],      //   (nested or 9 values row-major), or instead
                          [h31, h32, h33]],
      "points": [[u, v, X, Y], ...],            // >= 4 pixel <-> ground correspondences (metres),
                                                //   e.g. floor marks measured with a tape; the
                                                //   homography is fitted to them (least squares)
      "camera_ground": [X, Y],                  // the ground point straight below the camera (m)
      "camera_height": 3.0,                     // camera centre above the ground (m)
      "principal_point": [cx, cy],              // optional (default: the image centre)
      "focal_px": 700.0                         // optional
    }

Give exactly one of ``image_to_ground`` and ``points``. Pixel coordinates are OpenCV's ((0, 0) is
the centre of the top-left pixel); the ground frame is any right-handed metric frame on the floor.
With ``points``, the fit's largest reprojection error (ground metres) is reported as a warning when
it exceeds 5 cm.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import cv2
import numpy as np

from trackreplay.recorder.sources.base import read_json, require_file
from trackreplay.schemas.errors import SourceError
from trackreplay.schemas.ground_plane import GroundPlaneCalibration
from trackreplay.trackers.geometry.homography import apply_homography

MAX_CONDITION = 1e12  # an image-to-ground homography's 2-norm condition number: beyond it, singular

KEYS = ("width", "height", "image_to_ground", "points", "camera_ground", "camera_height", "principal_point", "focal_px")
FIT_WARNING_M = 0.05


def _numbers(path: Path, key: str, value: Any, shape: tuple[int, ...] | None = None) -> np.ndarray:
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise SourceError(f"{path}: {key} must be numbers, not {value!r}") from None
    if not np.isfinite(array).all():
        raise SourceError(f"{path}: {key} holds a value that is not a finite number")
    if shape is not None and array.size != int(np.prod(shape)):
        raise SourceError(f"{path}: {key} needs {int(np.prod(shape))} numbers, not {array.size}")
    return array if shape is None else array.reshape(shape)


def fit_homography(path: Path, points: np.ndarray) -> tuple[np.ndarray, float]:
    """Image -> ground homography through (N, 4) rows ``u, v, X, Y`` and its largest error (m)."""
    if points.ndim != 2 or points.shape[1] != 4 or len(points) < 4:
        raise SourceError(f"{path}: points needs at least 4 rows of [u, v, X, Y], not an array of shape {points.shape}")
    H, _ = cv2.findHomography(points[:, :2], points[:, 2:], 0)
    if H is None:
        raise SourceError(f"{path}: the points do not determine a homography (are three of them on one line?)")
    error = float(np.max(np.linalg.norm(apply_homography(H, points[:, :2]) - points[:, 2:], axis=1)))
    return H, error


def read_ground_plane(path: str | Path) -> tuple[GroundPlaneCalibration, tuple[str, ...]]:
    """The calibration in ``path`` and any warnings about it."""
    path = require_file(path, "ground-plane file")
    try:
        data = read_json(path)
    except UnicodeDecodeError:
        raise SourceError(f"{path} is not a text (JSON) file") from None
    if not isinstance(data, dict):
        raise SourceError(f"ground-plane file {path} must hold a JSON object")
    unknown = sorted(set(data) - set(KEYS))
    if unknown:
        raise SourceError(f"{path}: unknown key {unknown[0]!r}; known: {', '.join(KEYS)}")
    for key in ("width", "height", "camera_ground", "camera_height"):
        if key not in data:
            raise SourceError(f"{path}: missing key {key!r}")
    if ("image_to_ground" in data) == ("points" in data):
        raise SourceError(f"{path}: give exactly one of image_to_ground (3x3) and points ([[u, v, X, Y], ...])")
    warnings: list[str] = []
    if "points" in data:
        H, error = fit_homography(path, _numbers(path, "points", data["points"]))
        if error > FIT_WARNING_M:
            warnings.append(f"{path}: the homography misses a point by {error:.3f} m (check the points)")
    else:
        H = _numbers(path, "image_to_ground", data["image_to_ground"], (3, 3))
        if not np.linalg.cond(H) < MAX_CONDITION:  # (an all-zero matrix: inf; nan fails too)
            raise SourceError(f"{path}: image_to_ground is singular (all zero, or its rows dependent): it maps the "
                              "picture onto no plane")
    width, height = (_numbers(path, k, data[k], (1,))[0] for k in ("width", "height"))
    if width != int(width) or height != int(height):
        raise SourceError(f"{path}: width and height must be whole pixels")
    pp = data.get("principal_point")
    try:
        calibration = GroundPlaneCalibration(
            width=int(width), height=int(height), image_to_ground=tuple(float(v) for v in H.reshape(-1)),
            camera_ground=tuple(float(v) for v in _numbers(path, "camera_ground", data["camera_ground"], (2,))),
            camera_height=float(_numbers(path, "camera_height", data["camera_height"], (1,))[0]),
            principal_point=None if pp is None else tuple(float(v) for v in _numbers(path, "principal_point", pp, (2,))),
            focal_px=None if data.get("focal_px") is None else float(_numbers(path, "focal_px", data["focal_px"], (1,))[0]),
        )
    except ValueError as err:
        raise SourceError(f"{path}: {err}") from None
    return calibration, tuple(warnings)
