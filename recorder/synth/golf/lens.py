"""A broadcast zoom lens (1x–20x) as the log's lens table.

Zoom and focus are raw encoder counts, 0..``COUNTS``. Magnification grows geometrically with the
zoom counts (``mag = ratio ** (zoom / COUNTS)``); focus counts run from the closest focus (0) to
infinity (``COUNTS``), linear in 1/distance, and change the focal length by about one per cent
("focus breathing"). The principal point wanders a few pixels with zoom, as real lenses do.

The table is sampled on a grid; ``trackers.geometry.ptz.intrinsics_at`` interpolates it linearly,
and the renderer uses that same interpolation, so the table *is* the truth of the synthetic camera.
"""

from __future__ import annotations

import math

import numpy as np

from trackreplay.schemas.records import LensEntry, LensTable

COUNTS = 10000
ZOOM_STEPS = 41
FOCUS_STEPS = (0, 5000, 10000)


class BroadcastLens:
    """Zoom/focus counts <-> magnification / focus distance for an image of ``width`` x ``height``."""

    def __init__(self, width: int, height: int, *, hfov_wide_deg: float = 55.0, ratio: float = 20.0,
                 min_focus_m: float = 2.0, breathing: float = 0.01) -> None:
        self.width, self.height = int(width), int(height)
        self.fx_wide = (self.width / 2.0) / math.tan(math.radians(hfov_wide_deg) / 2.0)
        self.ratio = float(ratio)
        self.min_focus_m = float(min_focus_m)
        self.breathing = float(breathing)

    # -- the lens model ---------------------------------------------------------

    def magnification(self, zoom: float | np.ndarray) -> float | np.ndarray:
        return self.ratio ** (np.clip(zoom, 0, COUNTS) / COUNTS)

    def zoom_for_fx(self, fx: float | np.ndarray) -> float | np.ndarray:
        """Zoom counts giving focal length ``fx`` (px) at infinity focus (clamped to the range)."""
        mag = np.clip(np.asarray(fx, dtype=np.float64) / self.fx_wide, 1.0, self.ratio)
        return COUNTS * np.log(mag) / math.log(self.ratio)

    def focus_for_distance(self, distance_m: float | np.ndarray) -> float | np.ndarray:
        """Focus counts that put ``distance_m`` in focus: linear in 1/distance, infinity = COUNTS."""
        d = np.maximum(np.asarray(distance_m, dtype=np.float64), self.min_focus_m)
        return COUNTS * (1.0 - self.min_focus_m / d)

    def _entry(self, zoom: float, focus: float) -> LensEntry:
        z = zoom / COUNTS
        fx = self.fx_wide * float(self.magnification(zoom)) * (1.0 + self.breathing * (1.0 - focus / COUNTS))
        cx = (self.width - 1) / 2.0 + 3.0 * z * self.width / 1280.0
        cy = (self.height - 1) / 2.0 - 2.0 * z * self.height / 720.0
        return LensEntry(float(zoom), float(focus), fx, fx, cx, cy)

    def table(self, camera_position: tuple[float, float, float]) -> LensTable:
        """The lens table written once to ``/ptz/lens_table``."""
        zooms = np.linspace(0, COUNTS, ZOOM_STEPS)
        entries = tuple(self._entry(float(z), float(f)) for f in FOCUS_STEPS for z in zooms)
        return LensTable(self.width, self.height, entries, tuple(float(c) for c in camera_position))
