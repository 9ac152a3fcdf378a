"""What a row without support may say (``[colorpf.support]``, ours; issue 31, "honest").

A frame *supports* the track when its row is "measured" (the colour vouches) or a foreground region
placed the estimate (``refine.mode = "foreground"``). Every other row with a position is "predicted":
held on the motion prediction, a colour match that vouches for little (the background scores as well
as the mark, a grey car on a grey road), a match beside a larger moving region, or a colour miss.
None of them is evidence of where the target is, nor of its size. So, counting the frames since the
last supported one (:class:`Support`):

- the box does not grow: the box an unsupported "predicted" row reports is scaled down (aspect kept) to
  fit within the last supported box's width and height (``size_holds``). Only the row: the filter's own
  estimate, cloud and size state go on as they were (shrunk, they narrowed the next frame's search,
  whose spread follows the box: the VOT ball, which grows by half, was found again later or not at all).
  Before, nothing bounded it (eqs. (10)-(11)'s aspect, fed by a likelihood that no longer sees the
  target, the camera's measured scale, the size state): on otb_car4 a "predicted" box reached 839x682 px
  on a 360x240 picture;
- the track turns "lost" once ``lost_unsupported`` frames in a row had no support (a duration, kept in
  seconds at ``frame_rate`` as ``hold.max_frames`` is), whatever the colour says: before, a match that
  vouched for little was no miss, and such a track stayed "predicted" for the rest of the clip;
- a "predicted" row's confidence falls linearly with the frames without support, to 0 when the track
  turns lost: the colour's confidence ``c`` on that frame times ``1 - n / lost_unsupported``, ``n`` the
  frames without support so far (``confidence_falls``; with ``lost_unsupported = 0`` it does not fall).
  Only the reported confidence: the status is decided on the colour's.
"""

from __future__ import annotations

import numpy as np


class Support:
    """The frames since the last supported one and that frame's box size (w, h)."""

    def __init__(self, wh: np.ndarray) -> None:
        self.unsupported = 0  # frames in a row without support
        self.wh = np.asarray(wh, dtype=np.float64)[:2].copy()  # the last supported box's (w, h)

    def note(self, supported: bool, wh: np.ndarray) -> None:
        """This frame's row: supported (its box remembered) or not (one more frame without)."""
        if supported:
            self.unsupported = 0
            self.wh = np.asarray(wh, dtype=np.float64)[:2].copy()
        else:
            self.unsupported += 1

    def expired(self, limit: int | None) -> bool:
        """True once ``limit`` frames in a row had no support (``None``: never)."""
        return limit is not None and self.unsupported >= limit

    def shrink(self, wh: np.ndarray) -> float:
        """The factor (at most 1, the aspect kept) that fits a box of size ``wh`` within the last supported one."""
        wh = np.asarray(wh, dtype=np.float64)[:2]
        return float(min(1.0, *(self.wh / np.maximum(wh, 1e-9))))

    def confidence(self, confidence: float, limit: int | None) -> float:
        """A "predicted" row's confidence after ``unsupported`` frames without support: falls to 0 at ``limit``."""
        if limit is None or self.unsupported == 0:
            return confidence
        return confidence * max(0.0, 1.0 - self.unsupported / limit)


__all__ = ["Support"]
