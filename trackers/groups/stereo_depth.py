"""§2 depth from a calibrated stereo pair: background subtraction in both views (median of the
first frames) and subtraction stereo, SGBM on foreground crops only
(:mod:`trackreplay.trackers.geometry.subtraction_stereo`). The group tracker's other depth source is
:mod:`.ground_depth` (one camera over a ground plane); both give a :class:`.ground_depth.DepthView`."""

from __future__ import annotations

import numpy as np

from trackreplay.trackers.foreground.background import MedianBackground, foreground_mask
from trackreplay.trackers.geometry.subtraction_stereo import make_matcher, subtraction_stereo
from trackreplay.trackers.groups.config import GroupsConfig
from trackreplay.trackers.groups.ground_depth import DepthView


class StereoDepth:
    """Both views' median backgrounds, then per pair the foregrounds and the subtraction-stereo disparity."""

    def __init__(self, config: GroupsConfig) -> None:
        self.bg = (MedianBackground(config.background.frames), MedianBackground(config.background.frames))
        self.models: tuple[np.ndarray, np.ndarray] | None = None
        self.matcher = make_matcher(config.stereo.sgbm)

    def add(self, left: np.ndarray, right: np.ndarray) -> None:
        """Both views' frames into the median backgrounds; once full, the models."""
        self.bg[0].add(left)
        self.bg[1].add(right)
        if self.bg[0].full:
            self.models = (self.bg[0].model(), self.bg[1].model())
            self.bg[0].clear()
            self.bg[1].clear()

    def observe(self, left: np.ndarray, right: np.ndarray, config: GroupsConfig) -> DepthView:
        assert self.models is not None
        bgc, stc = config.background, config.stereo
        fg_left = foreground_mask(left, self.models[0], bgc.threshold, open_px=bgc.open_px)
        fg_right = foreground_mask(right, self.models[1], bgc.threshold, open_px=bgc.open_px)
        stereo = subtraction_stereo(left, right, fg_left, stc.sgbm, right_mask=fg_right,
                                    margin=stc.margin_px, right_tolerance_px=stc.right_tolerance_px, matcher=self.matcher)
        return DepthView(fg_left, fg_right, stereo.disparity, stereo.crops)
