"""A fixed camera's ground plane from ground truth that places people on the ground
(``record --groundtruth gt.txt --ground-plane-from-truth``).

MOTChallenge truth with world columns (``frame,id,x,y,w,h,conf,X,Y,Z``, PETS 2009's) gives, per
person and frame, an image box and the person's position on the ground in metres. The box's
bottom-centre is where the feet touch the ground, so every row is one image ↔ ground
correspondence: ``(x_c, y_c + h/2) ↔ (X, Y)`` (the box's centre in the recorder's 0-based pixels).
The image → ground homography is fitted to all of them by OpenCV's ``findHomography`` with RANSAC
(a row whose foot is more than ``RANSAC_M`` from the fit is an outlier: a box cut by the picture's
edge, a mislabelled row), then refitted by least squares on the inliers. The camera's ground point
and height, which the file format of ``--ground-plane`` asks for, come from posing a pinhole
camera over the fitted plane (:func:`trackreplay.trackers.groups.ground_depth.ground_rig`: square
pixels, the principal point at the image centre).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from trackreplay.recorder.sources.groundtruth import GroundTruthTable
from trackreplay.schemas.errors import SourceError
from trackreplay.schemas.ground_plane import GroundPlaneCalibration
from trackreplay.trackers.geometry.ground_plane import GroundPlane
from trackreplay.trackers.geometry.homography import apply_homography

RANSAC_M = 0.5  # metres on the ground: a foot farther than this from the fit is an outlier
MIN_ROWS = 8


@dataclass(frozen=True)
class TruthFit:
    """The fitted homography and how well it carries the truth's foot points onto their ground points."""

    image_to_ground: np.ndarray  # 3x3
    rows: int
    inliers: int
    error_median_m: float
    error_p95_m: float
    error_max_m: float

    def summary(self, path: str) -> str:
        return (f"ground plane fitted to the feet of {self.rows} truth rows of {path} ({self.inliers} inliers): ground "
                f"error median {self.error_median_m:.3f} m, 95th percentile {self.error_p95_m:.3f} m, "
                f"largest {self.error_max_m:.3f} m")


def truth_feet(gt: GroundTruthTable) -> tuple[np.ndarray, np.ndarray]:
    """(N, 2) foot pixels (box bottom-centre) and (N, 2) ground metres of every visible truth row with both."""
    feet, ground = [], []
    for frame in sorted(gt.frames):
        for o in gt.frames[frame]:
            if o.visible is False or None in (o.x, o.y, o.h, o.X, o.Y):
                continue
            feet.append((o.x, o.y + o.h / 2.0))
            ground.append((o.X, o.Y))
    return np.asarray(feet, np.float64).reshape(-1, 2), np.asarray(ground, np.float64).reshape(-1, 2)


def fit_truth_plane(gt: GroundTruthTable) -> TruthFit:
    """RANSAC then least squares on the inliers (module docstring); refused when the truth has no ground positions."""
    feet, ground = truth_feet(gt)
    if len(feet) < MIN_ROWS:
        raise SourceError(f"{gt.path}: --ground-plane-from-truth needs truth rows with a box and a ground position "
                          f"(MOTChallenge columns 8-9, X,Y in metres) and it has {len(feet)} (at least {MIN_ROWS})")
    H, inlier = cv2.findHomography(feet, ground, cv2.RANSAC, RANSAC_M)
    if H is None:
        raise SourceError(f"{gt.path}: the truth's foot points and ground positions fit no plane")
    keep = inlier.ravel().astype(bool)
    refit, _ = cv2.findHomography(feet[keep], ground[keep], 0)
    H = refit if refit is not None else H
    error = np.linalg.norm(apply_homography(H, feet) - ground, axis=1)
    return TruthFit(H / H[2, 2], len(feet), int(keep.sum()), float(np.median(error)), float(np.percentile(error, 95)),
                    float(error.max()))


def truth_plane(fit: TruthFit, width: int, height: int) -> GroundPlaneCalibration:
    """The calibration ``record`` writes: the fit, and the camera's ground point and height from a
    pinhole posed over it (pictures of ``width`` x ``height``)."""
    from trackreplay.trackers.groups.ground_depth import ground_rig

    try:
        rig = ground_rig(GroundPlane(fit.image_to_ground), (height, width))
    except ValueError as err:
        raise SourceError(f"the ground plane fitted to the truth gives no camera ({err})") from None
    assert rig.pose is not None
    X, Y, Z = (float(c) for c in rig.pose.t)
    return GroundPlaneCalibration(width=width, height=height, image_to_ground=tuple(float(v) for v in fit.image_to_ground.ravel()),
                                  camera_ground=(X, Y), camera_height=Z, focal_px=float(rig.f))
