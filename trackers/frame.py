"""The immutable frame bundle a tracker receives (docs/architecture.md §4 Tracker contract)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from trackreplay.schemas.records import InitRegion, LensTable, PtzReading
from trackreplay.trackers.geometry.ground_plane import GroundPlane
from trackreplay.trackers.geometry.ptz import PtzCamera
from trackreplay.trackers.geometry.stereo import StereoRig


@dataclass(frozen=True, eq=False)
class Frame:
    """One time step: the (left) image, optional right image, PTZ reading and camera model, hints.

    ``image`` is BGR ``uint8`` (H, W, 3) or grey (H, W). ``encoded``/``encoding``
    keep the source bytes (e.g. JPEG) so viewers can log them without re-encoding.
    """

    index: int
    t_ns: int
    image: np.ndarray
    right: np.ndarray | None = None
    ptz: PtzReading | None = None
    lens: LensTable | None = None
    camera: PtzCamera | None = None  # posed from ptz + lens when both exist
    hints: tuple[InitRegion, ...] = field(default_factory=tuple)  # marked on this frame
    all_hints: tuple[InitRegion, ...] = field(default_factory=tuple)  # every region the log marks
    encoded: bytes | None = None
    encoding: str | None = None
    ground_plane: GroundPlane | None = None  # a fixed camera's image <-> ground homography (/camera/ground_plane)
    stereo: StereoRig | None = None  # rectified rig (f, baseline, cx, cy) from /stereo/{left,right}/calibration

    @property
    def grey(self) -> np.ndarray:
        """The image as float32 luminance (cached per frame by the caller if needed)."""
        from trackreplay.trackers.appearance.color import to_grey  # OpenCV on first use, as before

        return to_grey(self.image).astype(np.float32)
