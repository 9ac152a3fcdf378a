"""The LUT silhouette stage: ``I_c`` inside ``I_s`` (seed 000, §2.1).

The search region's pixels are converted to (Y, Cb, Cr) (only the crop: the HD frame is never
converted whole), the sky or ground LUT is chosen from the crop's luminance histogram
(:meth:`GolfLuts.choose`), and one lookup gives the binary silhouette. Ours: the sky's is closed
with a small square (``lut.sky_close_px``), which joins the pieces a small, blurred ball leaves
over sky into one blob of its size.

Ours, when neither LUT finds the ball near the prediction: :func:`contrast_silhouette`, the pixels
clearly brighter than their local background (a white top-hat of the luminance, the opening's
disc a few ball diameters wide). A white ball against open sky keeps that contrast while its
colour drifts away from what the LUT learned (fading with distance, sun, compression).

Ours, with encoders: :func:`moving_silhouette`. A camera that only rotates and zooms maps its
previous frame onto this one exactly (:func:`~trackreplay.trackers.geometry.ptz.pose_homography`,
whatever the depth), so everything fixed in the world (clouds, turf, tree line, tee markers,
a spare ball) lines up, and what is brighter now than anything near the same place before is
moving: the ball, a bird. A 2-3 px ball among cloud puffs of the same brightness passes no LUT and
no contrast threshold that the puffs do not, but only it moves against the sky.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

import cv2

from trackreplay.trackers.appearance.color import to_ycbcr, to_ycrcb
from trackreplay.trackers.appearance.lut import ColourLut
from trackreplay.trackers.foreground.morphology import disc_top_hat
from trackreplay.trackers.foreground.silhouette import crop_pixels, silhouette
from trackreplay.trackers.golf.config import ContrastConfig
from trackreplay.trackers.golf.lut import LUT_NAMES, SKY, GolfLuts
from trackreplay.trackers.median import median_and_mad

CONTRAST = "contrast"  # lut_name of a contrast silhouette


@dataclass(frozen=True, eq=False)
class LutSilhouette:
    """The silhouette stage's intermediates."""

    lut_name: str  # the LUT applied ("sky" / "ground"; "" if none)
    lut_scores: np.ndarray  # (2,) share of I_s's luminance histogram per name in lut_names (NaN: not built)
    mask: np.ndarray  # (h, w) uint8 0/1, I_c inside I_s
    offset: np.ndarray  # (2,) int64 top-left of the mask in the frame
    lut_names: tuple[str, ...] = LUT_NAMES

    @classmethod
    def empty(cls) -> LutSilhouette:
        return cls("", np.full(len(LUT_NAMES), np.nan), np.zeros((0, 0), np.uint8), np.zeros(2, np.int64))


def named_silhouette(ycc: np.ndarray, luts: GolfLuts, name: str) -> np.ndarray:
    """§2.1's ``I_c`` of the crop ``ycc`` under the LUT ``name``; the sky's closed with a
    ``lut.sky_close_px`` square (the pieces of one small ball joined, :class:`~.config.LutConfig`)."""
    mask = silhouette(ycc, luts.lut(name))
    side = luts.config.sky_close_px
    if name == SKY and side > 1 and mask.size:
        mask = cv2.morphologyEx(mask, cv2.MORPH_CLOSE, np.ones((side, side), np.uint8))
    return mask


def box_silhouette(image: np.ndarray, box: np.ndarray, luts: GolfLuts, name: str) -> tuple[np.ndarray, tuple[int, int], np.ndarray]:
    """The (Y, Cb, Cr) pixels of ``box`` (x0, y0, w, h), their offset in the frame and their silhouette under the LUT ``name``."""
    ycc, offset = crop_pixels(image, box, to_ycbcr)
    return ycc, offset, named_silhouette(ycc, luts, name)


def lut_silhouette(image: np.ndarray, box: np.ndarray, luts: GolfLuts, current: str) -> tuple[LutSilhouette, np.ndarray]:
    """The silhouette in ``box`` (x0, y0, w, h) with the LUT chosen there (``current`` kept unless
    another fits clearly better), and the crop's (Y, Cb, Cr) pixels."""
    ycc, offset = crop_pixels(image, box, to_ycbcr)
    name, scores = luts.choose(ycc[..., 0], current)
    return LutSilhouette(name, scores, named_silhouette(ycc, luts, name), np.array(offset, np.int64)), ycc


def contrast_silhouette(ycc: np.ndarray, diameter: float, cfg: ContrastConfig, scale: float,
                        hat: np.ndarray | None = None) -> np.ndarray:
    """Pixels of the crop ``ycc`` brighter than their local background: the white top-hat of Y with
    a disc ``kernel_diameters`` ball diameters wide, above ``min_contrast`` levels and above
    ``noise_sigmas`` times the top-hat's robust spread (so textured ground, where many pixels stand
    out a little, needs more). A 0/1 uint8 mask the size of the crop. ``hat``: :func:`top_hat` of
    the same crop when the caller has it (the moving silhouette needs it too)."""
    y = np.ascontiguousarray(ycc[..., 0], dtype=np.uint8)
    if y.size == 0:
        return np.zeros(y.shape, np.uint8)
    hat = top_hat(ycc, diameter, cfg, scale) if hat is None else hat
    med, mad = median_and_mad(hat, 0, 256)
    noise = 1.4826 * mad
    threshold = max(cfg.min_contrast, med + cfg.noise_sigmas * noise)
    return at_least(hat, threshold)


def top_hat(ycc: np.ndarray, diameter: float, cfg: ContrastConfig, scale: float) -> np.ndarray:
    """The white top-hat of the crop's luminance with a disc ``kernel_diameters`` ball diameters wide
    (at most ``max_kernel_px``, scaled), as :func:`contrast_silhouette` and :func:`moving_silhouette` threshold it."""
    y = np.ascontiguousarray(ycc[..., 0], dtype=np.uint8)
    if y.size == 0:
        return np.zeros(y.shape, np.uint8)
    side = int(np.clip(round(cfg.kernel_diameters * diameter), 3, max(3, cfg.max_kernel_px * scale)))
    side += 1 - side % 2
    return disc_top_hat(y, side)  # OpenCV's MORPH_TOPHAT with the MORPH_ELLIPSE disc, by row segments


def at_least(values: np.ndarray, threshold: float) -> np.ndarray:
    """``(values >= threshold).astype(np.uint8)`` of a 2-D uint8 or int16 image: for integers that is
    ``values > ceil(threshold) - 1``, one ``cv2.threshold`` (numpy compared each value as a float64)."""
    if values.ndim != 2 or values.dtype not in (np.uint8, np.int16) or not math.isfinite(threshold):
        return (values >= threshold).astype(np.uint8)
    info = np.iinfo(values.dtype)
    level = math.ceil(threshold) - 1
    if level < info.min or level >= info.max:  # nothing or everything passes: numpy's answer without OpenCV's edge cases
        return (values >= threshold).astype(np.uint8)
    mask = cv2.threshold(values, level, 1, cv2.THRESH_BINARY)[1]
    return mask if mask.dtype == np.uint8 else mask.astype(np.uint8)


def previous_in_pose(previous: np.ndarray, homography: np.ndarray, offset: tuple[int, int], shape: tuple[int, int]) -> np.ndarray:
    """The luminance of the previous frame (BGR, or its luminance already) brought into this pose
    over a crop at ``offset`` of ``shape`` (h, w): ``homography`` maps previous pixels to this
    frame's. Where the previous frame did not see, 255 (nothing can be brighter than that: no
    motion is claimed there)."""
    h, w = shape
    to_crop = np.array([[1.0, 0.0, -offset[0]], [0.0, 1.0, -offset[1]], [0.0, 0.0, 1.0]]) @ homography
    warped = cv2.warpPerspective(previous, to_crop, (w, h), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT,
                                 borderValue=(255, 255, 255))
    if warped.ndim == 2:
        return warped
    return cv2.extractChannel(to_ycrcb(warped), 0)  # Y, as to_ycbcr gives it, without reordering Cb and Cr


def moving_silhouette(ycc: np.ndarray, previous_y: np.ndarray, diameter: float, cfg: ContrastConfig, scale: float,
                      hat: np.ndarray | None = None) -> np.ndarray:
    """Pixels of the crop that stand above their local background now (white top-hat, as
    :func:`contrast_silhouette`) *and* are brighter than every pixel within
    ``registration_px`` of the same place in the previous frame brought into this pose
    (``previous_y``, :func:`previous_in_pose`): bright and new there, i.e. moving against a
    background fixed in the world. The smaller of the two rises must clear ``moving_min_contrast``
    and ``noise_sigmas`` robust sigmas of its spread over the crop. A 0/1 uint8 mask. ``hat``: as
    for :func:`contrast_silhouette`."""
    y = np.ascontiguousarray(ycc[..., 0], dtype=np.uint8)
    if y.size == 0:
        return np.zeros(y.shape, np.uint8)
    hat = (top_hat(ycc, diameter, cfg, scale) if hat is None else hat).astype(np.int16)
    side = 2 * max(int(round(cfg.registration_px)), 0) + 1
    before = cv2.dilate(np.ascontiguousarray(previous_y, dtype=np.uint8), np.ones((side, side), np.uint8))
    rise = np.minimum(hat, y.astype(np.int16) - before.astype(np.int16))
    med, mad = median_and_mad(rise, -255, 511)
    noise = 1.4826 * mad
    threshold = max(cfg.moving_min_contrast, med + cfg.noise_sigmas * noise)
    return at_least(rise, threshold)
