"""The target's own motion, which the colour PF holds an estimate on (``hold``, ours).

A *vouched* estimate is a "measured" row or one the foreground region placed (``refine.mode =
"foreground"``), kept in the marked frame's view (``camera.compensate``: the velocity is the target's,
not the camera's). Between consecutive vouched estimates the track's velocity is exponentially smoothed
(``hold.smoothing``, at the log's frame interval: :func:`.timing.smoothing_for`). The hold
(``ColorPfTracker._hold``) predicts from the last vouched estimate plus that velocity times the frames
since (:func:`.motion.vouched_prediction`), at most ``hold.max_frames`` held frames in a row (``held``, a
:class:`trackreplay.trackers.lifecycle.Run`). With ``hold.early = "region"`` the rows made before eq. (7)'s
background (``early_rows``) are vouched for once it exists (``ColorPfTracker._revouch``).
"""

from __future__ import annotations

import numpy as np

from trackreplay.trackers.lifecycle import Run


class VouchedMotion:
    """The last vouched estimate, the velocity between vouched estimates, the run of held frames."""

    def __init__(self) -> None:
        self.velocity = np.zeros(2)  # smoothed displacement per frame between vouched estimates
        self.last: tuple[int, np.ndarray] | None = None  # the last vouched frame and centre
        self.steps = 0  # displacements between vouched estimates measured so far
        self.held = Run()  # held frames in a row
        # hold.early = "region": the estimates before eq. (7)'s background (frame, box in the marked frame's view)
        self.early_rows: list[tuple[int, np.ndarray]] = []

    def vouch(self, index: int, estimate: np.ndarray, smoothing: float) -> None:
        """Frame ``index``'s vouched estimate (centre first): the velocity from the last one, smoothed."""
        if self.last is not None:
            last, xy = self.last
            self.steps += 1
            self.velocity = smoothing * self.velocity + (1.0 - smoothing) * (estimate[:2] - xy) / max(index - last, 1)
        self.last = (index, estimate[:2].copy())

    def forget(self) -> None:
        """No vouched estimate, no velocity (before the early rows are vouched for again)."""
        self.last, self.velocity, self.steps = None, np.zeros(2), 0

    def take_early_rows(self) -> list[tuple[int, np.ndarray]]:
        rows, self.early_rows = self.early_rows, []
        return rows


__all__ = ["VouchedMotion"]
