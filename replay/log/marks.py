"""Checks on the marks (``/annotations/init``) a user gives a tracker: inside the picture, and
with labels the chosen tracker reads."""

from __future__ import annotations

from collections.abc import Iterable, Sequence

from trackreplay.schemas.errors import LogError, SourceError
from trackreplay.trackers.base import TrackerSpec


def check_labels(labels: Iterable[str], spec: TrackerSpec, where: str) -> None:
    """Refuse labels the tracker would ignore (its ``mark_labels``: the flow tracker reads only
    ``target``; None reads every label, e.g. golf: ball, sky, ground)."""
    known, tracker = spec.mark_labels, spec.name
    if known is None:
        return
    ignored = sorted(set(labels) - set(known))
    if ignored:
        raise LogError(f"{where}: marks labelled {', '.join(repr(x) for x in ignored)} would be ignored by the "
                       f"{tracker} tracker, which reads only {', '.join(repr(x) for x in known)} marks "
                       f"(annotate again with --label {known[0]})")


def check_one_start_per_frame(marks: Iterable, spec: TrackerSpec, where: str) -> None:
    """A tracker that follows one object (``one_start_per_frame``: golf) starts from one mark per
    frame: two different boxes on a frame, neither labelled ``start`` or ``init``, leave the choice to
    their order (a review marked a wrong box first: nothing was tracked, exit 0)."""
    if not spec.one_start_per_frame:
        return
    tracker = spec.name
    boxes: dict[int, set] = {}
    starts: dict[int, bool] = {}
    for m in marks:
        boxes.setdefault(m.frame, set()).add((m.x, m.y, m.w, m.h))
        starts[m.frame] = starts.get(m.frame, False) or any(w in m.label.lower() for w in ("start", "init"))
    for frame in sorted(boxes):
        if len(boxes[frame]) > 1 and not starts[frame]:
            raise LogError(f"{where}: frame {frame} has {len(boxes[frame])} different marks and the {tracker} tracker "
                           "follows one ball: keep one, or label the one to start from `start` (--label start)")


def check_can_track(spec: TrackerSpec, marks: Sequence, windowed: bool, has_stereo: bool, log,
                    has_ground: bool = False) -> None:
    """Refuse a replay its tracker cannot start on: one that starts only from a mark (``needs =
    "mark"``) on a log (or ``--start``/``--end`` window) that marks nothing, one that needs a
    calibrated stereo pair (``needs = "stereo"``) on a log without one, or depth (``needs = "depth"``: a
    stereo pair or a ground plane) on a log with neither. Refused before any frame is
    decoded: a trajectory with no row is no answer to a replay."""
    needs, tracker = spec.needs, spec.name
    if needs == "mark" and not marks:
        raise LogError(f"{log}: the {tracker} tracker starts only from a marked box and the log marks none"
                       + (" on the frames replayed (--start/--end)" if windowed else "")
                       + "; mark one with `trackreplay annotate LOG --frame N --box x,y,w,h` "
                       "(`trackreplay frame LOG N` shows the pixel grid)")
    if needs == "stereo" and not has_stereo:
        raise LogError(f"{log}: the {tracker} tracker needs a calibrated stereo pair (/stereo/left/image and "
                       "/stereo/right/image with their calibration, or a ROS 2 pair with camera_info; "
                       "--stereo-topics names other topics) and the log has none")
    if needs == "depth" and not (has_stereo or has_ground):
        raise LogError(f"{log}: the {tracker} tracker needs a calibrated stereo pair (/stereo/left/image and "
                       "/stereo/right/image with their calibration; --stereo-topics names other topics) or one fixed "
                       "camera with a ground plane (/camera/ground_plane: record --ground-plane FILE, or "
                       "--ground-plane-from-truth with --groundtruth) and the log has neither")


def check_inside(boxes: Iterable[tuple[int, float, float, float, float]], width: int, height: int, where: str) -> None:
    """Each ``(frame, x, y, w, h)`` (top-left corner and size, pixels) lies inside a ``width`` x ``height`` image."""
    for frame, x, y, w, h in boxes:
        if not (0 <= x and 0 <= y and x + w <= width and y + h <= height):  # written so that nan fails too
            raise SourceError(f"{where}: the box {x:g},{y:g},{w:g},{h:g} on frame {frame} is not inside the "
                              f"{width}x{height} image (x from 0 to {width}, y from 0 to {height}, top-left corner "
                              f"and size; `trackreplay frame` shows the pixel grid)")
