"""What the golf tracker tells the user once (a notice rides in the intermediates; the engine prints it)."""

from __future__ import annotations

NO_ENCODER_NOTICE = (
    "no PTZ encoder pose for this frame (no /ptz/encoders or lens table): tracking in image "
    "coordinates only - no lines of sight, no 3-D landing prediction; the bounce is caught from "
    "an image-space parabola instead"
)
ENCODER_GAP_NOTICE = (
    "some frames have no PTZ encoder pose (outside the encoders' coverage): those frames are "
    "tracked in image coordinates only, without lines of sight"
)
NO_HINTS_NOTICE = (
    "the log marks no ball (/annotations/init is empty): the golf tracker needs marked ball boxes "
    "to build its colour LUTs and start; nothing is tracked"
)


class Notices:
    """Says "no encoders" (or "encoder gap") and "nothing marked" once each."""

    def __init__(self) -> None:
        self._told_no_encoders = False
        self._had_camera = False
        self._told_no_hints = False

    def check(self, has_camera: bool, has_marks: bool) -> str:
        """This frame's notice ("" for none)."""
        notice = ""
        if not has_camera and not self._told_no_encoders:
            self._told_no_encoders = True
            notice = ENCODER_GAP_NOTICE if self._had_camera else NO_ENCODER_NOTICE
        self._had_camera |= has_camera
        if not has_marks and not self._told_no_hints:
            self._told_no_hints = True
            notice = f"{notice}; {NO_HINTS_NOTICE}" if notice else NO_HINTS_NOTICE
        return notice
