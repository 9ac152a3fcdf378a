"""A bin index for pictures without hue: grey level on flat pixels, gradient orientation on edges.

The H-S histogram (colorpf §3.1) is undefined on a grey picture (every pixel has S = 0 and one H),
and Pérez et al.'s V histogram of the uncoloured pixels keeps only brightness, which a dark car shares
with its road's shadows. This index splits the pixels as Pérez et al. split coloured from grey ones:
a pixel whose Sobel gradient magnitude reaches ``edge_min`` gets the bin of its gradient's direction
(signed, ``orientations`` sectors of 360° centred on 0°, 360°/n, ...: the shape's outline and its
light/dark polarity, as a HOG cell counts it), any other its grey level's bin (``levels`` bins of
[0, 256)). One histogram of ``levels + orientations`` bins, counted by the same single ``np.bincount``
as any other bin index (:func:`~trackreplay.trackers.appearance.histogram.box_part_histograms`), so no
weight per pixel: the magnitude decides *whether* a pixel counts as an edge, not how much.
"""

from __future__ import annotations

import cv2
import numpy as np

from trackreplay.trackers.appearance.color import to_grey


def gradients(image: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The grey levels (uint8, luma), and the 3x3 Sobel derivatives (float32) of a BGR or grey image."""
    grey = to_grey(image, "luma")
    gx = cv2.Sobel(grey, cv2.CV_32F, 1, 0, ksize=3)
    gy = cv2.Sobel(grey, cv2.CV_32F, 0, 1, ksize=3)
    return grey, gx, gy


def edge_threshold(image: np.ndarray, quantile: float) -> float:
    """The Sobel magnitude at ``quantile`` of a picture's pixels (e.g. the context of a marked box):
    with 0.5, half of that picture's pixels count as edges. Never below 1 (a flat picture: no edge)."""
    _, gx, gy = gradients(image)
    return max(float(np.quantile(cv2.magnitude(gx, gy), quantile)), 1.0)


def grey_gradient_index(image: np.ndarray, levels: int, orientations: int, edge_min: float,
                        margin: tuple[int, int, int, int] = (0, 0, 0, 0)) -> tuple[np.ndarray, int]:
    """Bin index per pixel (int32): ``levels + o`` for an edge pixel (magnitude >= ``edge_min``) whose
    gradient points into sector ``o`` of ``orientations`` (sector 0 centred on +x, counted towards +y),
    else its grey level's bin ``g * levels // 256``; and the bin count ``levels + orientations``.

    ``margin`` (left, top, right, bottom) pixels of ``image`` are context only (the derivatives at the
    crop's edge read its neighbours, not a reflected border) and are cut from the index returned.
    """
    grey, gx, gy = gradients(image)
    left, top, right, bottom = margin
    rows, cols = slice(top, grey.shape[0] - bottom), slice(left, grey.shape[1] - right)
    grey, gx, gy = grey[rows, cols], gx[rows, cols], gy[rows, cols]
    level = _level_lut(levels)[grey]
    # sectors centred on 0°, 360°/n, ...: an axis-aligned edge (a car's, a building's) falls in the middle
    # of one, not on the border of two where the noise splits it
    turns = cv2.phase(gx, gy) * np.float32(orientations / (2.0 * np.pi)) + np.float32(0.5)
    sector = np.floor(turns).astype(np.int32) % orientations
    edge = cv2.magnitude(gx, gy) >= np.float32(edge_min)
    return np.where(edge, levels + sector, level), levels + orientations


def _level_lut(levels: int) -> np.ndarray:
    return (np.arange(256, dtype=np.int64) * levels // 256).astype(np.int32)
