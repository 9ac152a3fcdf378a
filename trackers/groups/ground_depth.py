"""Depth from one fixed camera over a ground plane, in place of subtraction stereo (§2).

Each foreground region is taken for people standing on the ground: a foot point goes through the
log's image → ground homography to a ground point G, and a pixel gets the depth of a vertical plane
through G facing the camera (a standing person at that distance). The foot (``ground.foot``) is the
bottom-centre of the region's box ("box": one distance for the region), or by default the region's
lowest pixel in the pixel's own columns, ``ground.column_m`` wide at the region's distance
("column": people side by side in one region, at different distances, each stand at their own). The rest of the pipeline reads that depth as it reads a
disparity: the camera becomes a *virtual* rectified rig (:func:`ground_rig`) of the camera's own
focal length and principal point and a baseline equal to its height over the ground, so a depth z
is the disparity ``d = f h / z`` — for a level camera exactly the foot's rows below the horizon,
whose noise is the foot row's jitter in pixels (``ground.sigma_foot_px``, the EKF's σ_d here).

The camera is found from the homography alone (Zhang's constraints: the ground's two axes are
orthogonal and of equal length seen through ``K``, with square pixels and the principal point at
the image centre unless the log gives it, or the log's ``focal_px``), then posed by OpenCV's
``solvePnP`` on a grid of image points and their ground points; its pose maps the camera frame to
the ground frame (X Y on the ground, Z up), as a stereo rig's ``/stereo/pose`` does.

Each column is then checked against a standing person (``ground.stature_check``,
:meth:`GroundDepth.standing_check`): a column too short for one whose feet the picture shows missing
(MOG2's shadow where the legs would be, or the picture's bottom edge), and the part of a column too
tall for one standing at its foot (someone behind), stand where their top, a head ``stature_m`` up, puts them.

What one camera cannot know (docs/groups_pets.md): heights (everyone stands on the ground, of a mean
stature where the head places them), and depth along a column — two people one behind the other that
the foreground joins get the nearer one's foot, but for what shows above the nearer one's head.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from trackreplay.trackers.geometry.ground_plane import GroundPlane
from trackreplay.trackers.geometry.rig_pose import RigPose
from trackreplay.trackers.geometry.stereo import StereoRig
from trackreplay.trackers.groups.config import GroundConfig

GRID = 9  # image points per side posing the camera (solvePnP on their ground points)


@dataclass(frozen=True, eq=False)
class DepthView:
    """One frame's foreground and depth as the group tracker reads them from either source."""

    fg_left: np.ndarray  # (H, W) bool: the foreground the KLT features live on
    fg_right: np.ndarray  # (H, W) bool: the right view's (one camera: all False)
    disparity: np.ndarray  # (H, W) float32 px, NaN off the foreground
    crops: np.ndarray  # (K, 4) int x0 y0 x1 y1: the stereo crops, or the regions with a depth


def focal_from_homography(ground_to_image: np.ndarray, centre: tuple[float, float]) -> float:
    """Focal length (px) of square pixels with the principal point ``centre``, from a ground → image
    homography ``G = λ K [r1 r2 t]``: ``r1 ⟂ r2`` and ``|r1| = |r2|`` in least squares on ``1/f²``."""
    A = np.asarray(ground_to_image, dtype=np.float64).copy()
    A[0] -= centre[0] * A[2]
    A[1] -= centre[1] * A[2]
    a1, a2 = A[:, 0], A[:, 1]
    b = np.array([a1[0] * a2[0] + a1[1] * a2[1], a1[0] ** 2 + a1[1] ** 2 - a2[0] ** 2 - a2[1] ** 2])
    c = np.array([a1[2] * a2[2], a1[2] ** 2 - a2[2] ** 2])
    w = -float(b @ c) / float(b @ b) if float(b @ b) > 0 else float("nan")
    if not (np.isfinite(w) and w > 0):
        raise ValueError("the ground plane's homography fits no pinhole camera with square pixels (give focal_px)")
    return float(1.0 / np.sqrt(w))


def ground_rig(plane: GroundPlane, shape: tuple[int, int]) -> StereoRig:
    """The virtual rectified rig of the camera over ``plane`` (images of ``shape`` = (H, W)):
    f, cx, cy of the camera, baseline = its height, pose camera → ground frame (Z up)."""
    h, w = shape
    cx, cy = plane.principal_point if plane.principal_point is not None else ((w - 1) / 2.0, (h - 1) / 2.0)
    f = plane.focal_px if plane.focal_px is not None else focal_from_homography(plane.ground_to_image, (cx, cy))
    K = np.array([[f, 0.0, cx], [0.0, f, cy], [0.0, 0.0, 1.0]])
    u, v = np.meshgrid(np.linspace(0.1 * w, 0.9 * w, GRID), np.linspace(0.5 * h, 0.95 * h, GRID))
    pixels = np.stack([u.ravel(), v.ravel()], axis=1)
    ground = plane.to_ground(pixels)
    object_points = np.concatenate([ground, np.zeros((len(ground), 1))], axis=1)
    ok, rvec, tvec = cv2.solvePnP(object_points, pixels, K, None, flags=cv2.SOLVEPNP_ITERATIVE)
    if not ok:
        raise ValueError("the camera could not be posed over the ground plane")
    R_wc = cv2.Rodrigues(rvec)[0]  # ground → camera
    centre = -R_wc.T @ tvec.ravel()
    if not centre[2] > 0:
        raise ValueError("the ground plane's frame puts the camera under the ground (its X, Y axes are left-handed "
                         "seen from above): give the ground points with one axis flipped")
    pose = RigPose(tuple(float(x) for x in R_wc.T.ravel()), tuple(float(x) for x in centre))
    return StereoRig(float(f), float(centre[2]), float(cx), float(cy), pose=pose)


def region_feet(stats: np.ndarray) -> np.ndarray:
    """(K, 2) the foot point of each region: the bottom-centre of its box (the bottom edge of its
    lowest row), from ``cv2.connectedComponentsWithStats``' ``x y w h area`` rows."""
    x, y, w, h = (stats[:, k].astype(np.float64) for k in range(4))
    return np.stack([x + (w - 1.0) / 2.0, y + h - 0.5], axis=1)


def _column_reach(lab: np.ndarray, u: np.ndarray, v: np.ndarray, half: np.ndarray, width: int) -> np.ndarray:
    """Per foreground pixel, the largest ``v`` of its region within ``half[lab]`` columns of it."""
    r = int(half.max()) if len(half) else 0
    lowest = np.iinfo(np.int64).min
    bottom = np.full((len(half), width + 2 * r), lowest, np.int64)
    np.maximum.at(bottom, (lab, u + r), v)
    wide = bottom[:, r:r + width].copy()
    for shift in range(-r, r + 1):
        reach = (abs(shift) <= half)[:, None]
        np.maximum(wide, np.where(reach, bottom[:, r + shift:r + shift + width], lowest), out=wide)
    return wide[lab, u]


def column_feet(lab: np.ndarray, u: np.ndarray, v: np.ndarray, half: np.ndarray, width: int) -> np.ndarray:
    """Per foreground pixel (region ``lab``, column ``u``, row ``v``), the foot row of its column: the
    region's lowest pixel within ``half[lab]`` columns of it (the bottom edge of that row), so people
    side by side in one region stand at their own distances and a gap between legs does not lift a foot."""
    return _column_reach(lab, u, v, half, width) + 0.5


def column_tops(lab: np.ndarray, u: np.ndarray, v: np.ndarray, half: np.ndarray, width: int) -> np.ndarray:
    """Per foreground pixel, the top row of its column as :func:`column_feet` finds the foot: the region's
    highest pixel within ``half[lab]`` columns of it (the top edge of that row)."""
    return -_column_reach(lab, u, -v, half, width) - 0.5


def heights_on(rig: StereoRig, rays: np.ndarray, ground: np.ndarray) -> np.ndarray:
    """Height above the ground (m) where each pixel's world ray (``rays``, N × 3, camera z = 1) meets the
    vertical plane through its ground point ``ground`` (N × 2) facing the camera (NaN: it does not)."""
    assert rig.pose is not None
    return rig.pose.t[2] + standing_depth(rig, rays, ground) * rays[:, 2]


def head_ground(rig: StereoRig, rays: np.ndarray, stature_m: float) -> np.ndarray:
    """(N, 2) where a person ``stature_m`` tall stands whose head is on each world ray (N × 3): the ray
    meets the horizontal plane at that height (NaN where it does not, ahead of the camera)."""
    assert rig.pose is not None
    C = rig.pose.t
    with np.errstate(divide="ignore", invalid="ignore"):
        s = (stature_m - C[2]) / rays[:, 2]
    s = np.where((rays[:, 2] < 0) & (s > 0), s, np.nan)
    return C[:2] + s[:, None] * rays[:, :2]


def standing_depth(rig: StereoRig, rays: np.ndarray, ground: np.ndarray) -> np.ndarray:
    """Camera-frame depth z of the pixels whose world rays (per pixel, camera z = 1) are ``rays``
    (N, 3), each on the vertical plane through its ground point ``ground`` (N, 2) facing the camera."""
    assert rig.pose is not None
    C = rig.pose.t
    to_g = ground - C[:2]
    n = to_g / np.maximum(np.linalg.norm(to_g, axis=1, keepdims=True), 1e-9)
    den = np.einsum("nd,nd->n", n, rays[:, :2])
    num = np.einsum("nd,nd->n", n, to_g)
    with np.errstate(divide="ignore", invalid="ignore"):
        z = num / den
    return np.where((den > 1e-9) & (num > 0), z, np.nan)


class GroundDepth:
    """The foreground (MOG2) and each region's standing depth as a virtual disparity (module docstring)."""

    def __init__(self, cfg: GroundConfig, frames: int) -> None:
        self.cfg = cfg
        self.frames = frames  # learnt before the first observation (the log's rate then sets MOG2's history)
        self.buffer: list[np.ndarray] = []
        self.mog: cv2.BackgroundSubtractorMOG2 | None = None
        self.rig: StereoRig | None = None
        self.rays: np.ndarray | None = None  # (H, W, 3) world ray of each pixel (camera z = 1)
        self.shadow: np.ndarray | None = None  # (H, W) bool: this frame's pixels MOG2 called shadow

    def add(self, image: np.ndarray) -> None:
        """One of the first ``frames`` frames, kept until the log's rate is known (:meth:`start`)."""
        self.buffer.append(image)

    def start(self, fps: float) -> None:
        """MOG2 with a history of ``history_s`` at ``fps`` (500 frames when the rate is unknown), taught
        the kept frames in order."""
        history = max(2, int(round(self.cfg.history_s * fps))) if np.isfinite(fps) and fps > 0 else 500
        self.mog = cv2.createBackgroundSubtractorMOG2(history, self.cfg.var_threshold, self.cfg.shadows)
        self.mog.setBackgroundRatio(self.cfg.background_ratio)
        self.mog.setShadowThreshold(self.cfg.shadow_threshold)
        for image in self.buffer:
            self.mog.apply(image)
        self.buffer = []

    @property
    def full(self) -> bool:
        return len(self.buffer) >= self.frames

    def camera(self, plane: GroundPlane, shape: tuple[int, int]) -> StereoRig:
        """The virtual rig (built on the first call; the plane and picture size do not change in a log)."""
        if self.rig is None:
            self.rig = ground_rig(plane, shape)
            h, w = shape
            f, cx, cy = self.rig.f, self.rig.cx, self.rig.cy
            u, v = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
            cam = np.stack([(u - cx) / f, (v - cy) / f, np.ones_like(u)], axis=-1)
            assert self.rig.pose is not None
            self.rays = cam @ self.rig.pose.R.T
        return self.rig

    def foreground(self, image: np.ndarray) -> np.ndarray:
        """MOG2's foreground (shadows left out), opened then closed (bool); the pixels MOG2 called shadow
        are kept in ``self.shadow``."""
        assert self.mog is not None
        raw = self.mog.apply(image)
        self.shadow = raw == 127
        mask = (raw == 255).astype(np.uint8)
        if self.cfg.open_px > 1:
            mask = cv2.morphologyEx(mask, cv2.MORPH_OPEN, np.ones((self.cfg.open_px, self.cfg.open_px), np.uint8))
        if self.cfg.close_px > 1:
            mask = cv2.morphologyEx(mask, cv2.MORPH_CLOSE, np.ones((self.cfg.close_px, self.cfg.close_px), np.uint8))
        return mask.astype(bool)

    def placeable(self, plane: GroundPlane, feet: np.ndarray) -> np.ndarray:
        """(K,) bool: the feet whose ground point ``sigma_foot_px`` rows up or down moves by at most
        ``max_foot_error_m`` (and stays in front of the camera)."""
        assert self.rig is not None and self.rig.pose is not None
        step = np.array([0.0, self.cfg.sigma_foot_px])
        up, down = plane.to_ground(feet - step), plane.to_ground(feet + step)
        spread = np.linalg.norm(up - down, axis=1) / 2.0
        # lower in the picture is nearer the camera for a foot below the horizon (above it: behind the camera)
        ahead = np.einsum("nd,nd->n", plane.to_ground(feet) - self.rig.pose.t[:2], down - up) < 0
        return (spread <= self.cfg.max_foot_error_m) & ahead

    def column_half_widths(self, plane: GroundPlane, stats: np.ndarray, keep: np.ndarray, width: int) -> np.ndarray:
        """(n,) per region, half of ``column_m`` in pixels at the distance of its box's foot (0 for the
        regions left out)."""
        assert self.rig is not None and self.rig.pose is not None
        C = self.rig.pose.t
        dist = np.hypot(np.linalg.norm(plane.to_ground(region_feet(stats)) - C[:2], axis=1), C[2])
        half = np.floor(self.rig.f * self.cfg.column_m / np.where(keep & np.isfinite(dist), dist, np.inf) / 2.0)
        return np.clip(half, 0, width).astype(np.int64)

    def standing_check(self, rig: StereoRig, plane: GroundPlane, lab: np.ndarray, u: np.ndarray, v: np.ndarray,
                       half: np.ndarray, width: int, feet: np.ndarray) -> np.ndarray:
        """The column feet ``feet`` (N × 2, ground) checked against a standing person (``ground.stature_check``): a
        column whose top stands lower than ``min_stature_m`` over its foot has no feet in the foreground
        (cut by the shadow test, hidden, or below the picture), so its pixels stand where a person
        ``stature_m`` tall has their head at that top; the pixels of a column higher than
        ``max_stature_m`` over its foot are someone behind the person whose foot it is, placed the same way."""
        assert self.rays is not None and rig.pose is not None
        cfg = self.cfg
        if not rig.pose.t[2] > cfg.stature_m:  # the head rule needs a camera above the heads
            return feet
        top = column_tops(lab, u, v, 2 * half, width)  # the top edge of the highest pixel within column_m
        row = (top + 0.5).astype(np.int64)
        top_ray = self.rays[row, u] - 0.5 * rig.pose.R[:, 1] / rig.f  # (a ray is linear in the row)
        top_h = heights_on(rig, top_ray, feet)
        own_h = heights_on(rig, self.rays[v, u], feet)
        head = head_ground(rig, top_ray, cfg.stature_m)
        short = (top_h < cfg.min_stature_m) & (row > 0) & np.isfinite(head).all(axis=1)  # (top row: the head may be cut)
        if short.any():  # which end is missing: the feet only where the picture shows why
            short &= self._feet_missing(lab, u, v, half, width, plane.to_image(np.nan_to_num(head))[:, 1]) > 0
        behind = (top_h > cfg.max_stature_m) & (own_h > cfg.stature_m) & np.isfinite(head).all(axis=1)
        return np.where((short | behind)[:, None], head, feet)

    def _feet_missing(self, lab: np.ndarray, u: np.ndarray, v: np.ndarray, half: np.ndarray, width: int,
                      below: np.ndarray) -> np.ndarray:
        """Per pixel of a short column, 1 where its feet are missing from the foreground for a reason the
        picture shows (else 0), within ``half`` columns as the foot is found: the column ends at the
        picture's bottom edge, or most of the rows between its foot and ``below`` (the row where the head
        rule puts the feet) are pixels MOG2 called shadow (legs as dark as a shadow on the ground). A column cut at the top
        instead (a head and torso learnt into the background while the legs still move) has neither."""
        assert self.shadow is not None
        h = self.shadow.shape[0]
        bottom = column_feet(lab, u, v, half, width) - 0.5  # the column's lowest row
        lo = np.clip(bottom + 1, 0, h).astype(np.int64)
        hi = np.clip(np.ceil(below), 0, h).astype(np.int64)
        rows = np.cumsum(np.concatenate([np.zeros((1, self.shadow.shape[1]), np.int64),
                                         self.shadow.astype(np.int64)]), axis=0)
        n_shadow = rows[hi, u] - rows[np.minimum(lo, hi), u]
        dark = 2 * n_shadow >= np.maximum(hi - lo, 1)
        cut = bottom >= h - 1
        return _column_reach(lab, u, (dark | cut).astype(np.int64), half, width)

    def observe(self, image: np.ndarray, plane: GroundPlane) -> DepthView:
        """This frame's foreground and the virtual disparity of each region large enough to be a person."""
        rig = self.camera(plane, image.shape[:2])
        assert self.rays is not None
        fg = self.foreground(image)
        n, labels, stats, _ = cv2.connectedComponentsWithStats(fg.astype(np.uint8), connectivity=8)
        big = np.flatnonzero(stats[1:, cv2.CC_STAT_AREA] >= self.cfg.min_area_px) + 1
        big = big[self.placeable(plane, region_feet(stats[big]))]
        keep = np.zeros(n, bool)
        keep[big] = True
        fg = keep[labels]
        disparity = np.full(fg.shape, np.nan, np.float32)
        if len(big):
            v, u = np.nonzero(fg)
            lab = labels[v, u]
            if self.cfg.foot == "column":
                half = self.column_half_widths(plane, stats, keep, fg.shape[1])
                ground_px = plane.to_ground(np.stack([u, column_feet(lab, u, v, half, fg.shape[1])], axis=1))
                if self.cfg.stature_check:
                    ground_px = self.standing_check(rig, plane, lab, u, v, half, fg.shape[1], ground_px)
            else:
                ground = np.full((n, 2), np.nan)
                ground[big] = plane.to_ground(region_feet(stats[big]))
                ground_px = ground[lab]
            z = standing_depth(rig, self.rays[v, u], ground_px)
            disparity[v, u] = (rig.f * rig.baseline / z).astype(np.float32)
        boxes = stats[big, :4].astype(np.int64)
        crops = np.concatenate([boxes[:, :2], boxes[:, :2] + boxes[:, 2:]], axis=1)
        return DepthView(fg, np.zeros_like(fg), disparity, crops.reshape(-1, 4))
