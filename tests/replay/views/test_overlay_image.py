"""Image-position overlays (every tracker): boxes and dots coloured by status, ids, trails, truth beside them."""

import numpy as np
import polars as pl
import pytest

from trackreplay.replay.core.trajectory import state_row, trajectory_table
from trackreplay.replay.log.groundtruth import GT_SCHEMA
from trackreplay.replay.views.overlay import (STATUS_BGR, TRUTH_BGR, TRUTH_UNSEEN_BGR, draw_image_frame,
                                              has_lines_of_sight, image_overlay)
from trackreplay.schemas.errors import TrackreplayError
from trackreplay.trackers.base import TrackState

GREY = 40


def _trajectory() -> pl.DataFrame:
    rows = [state_row("flow", k, k, TrackState(1, x=20.0 + 2 * k, y=40.0, w=10.0, h=8.0)) for k in range(6)]
    rows.append(state_row("flow", 5, 5, TrackState(2, x=80.0, y=60.0, status="predicted")))  # no size: a dot
    rows.append(state_row("flow", 6, 6, TrackState(1, x=40.0, y=40.0, w=10.0, h=8.0, status="interpolated")))
    rows.append(state_row("flow", 7, 7, TrackState(1, status="lost")))
    return trajectory_table(rows)


def _truth() -> pl.DataFrame:
    rows = [(5, 5, 7, 60.0, 30.0, 20.0, 10.0, None, None, None, None, None, True, None),
            (5, 5, 8, 20.0, 80.0, None, None, None, None, None, None, None, None, None),  # a point truth
            (6, 6, 7, 60.0, 30.0, 20.0, 10.0, None, None, None, None, None, False, None)]  # placed, not seen
    return pl.DataFrame(rows, schema=GT_SCHEMA, orient="row")


def _image() -> np.ndarray:
    return np.full((100, 120, 3), GREY, np.uint8)


def test_boxes_dots_and_truth_are_drawn_in_their_colours_at_their_places() -> None:
    overlay = image_overlay(_trajectory(), _truth())
    out = draw_image_frame(_image(), overlay, 5)
    assert tuple(out[36, 25]) == STATUS_BGR["measured"]  # track 1's box corner: (30, 40) +- (5, 4)
    assert tuple(out[44, 35]) == STATUS_BGR["measured"]
    assert tuple(out[25, 50]) == TRUTH_BGR  # truth 7's box corner: (60, 30) +- (10, 5)
    assert tuple(out[35, 70]) == TRUTH_BGR
    assert tuple(out[80, 20]) == TRUTH_BGR  # truth 8's cross centre
    assert tuple(out[60, 76]) == STATUS_BGR["predicted"]  # track 2's dot (a 9 px square round (80, 60))
    assert (out[40, 21:28] != GREY).any()  # the trail of track 1 behind its box
    assert (out[0:15, 100:120] == GREY).all() and (out[85:100, 60:120] == GREY).all()  # elsewhere untouched
    labels = out[46:60, 20:60]  # "1 measured" is written above the box, "truth 8" under the cross
    assert (out[20:35, 20:60] != GREY).any() and (labels == GREY).all()


def test_status_and_visibility_change_the_colours_and_a_frame_without_rows_is_untouched() -> None:
    overlay = image_overlay(_trajectory(), _truth())
    out = draw_image_frame(_image(), overlay, 6)
    assert tuple(out[36, 35]) == STATUS_BGR["interpolated"]  # (40, 40) +- (5, 4)
    assert tuple(out[25, 50]) == TRUTH_UNSEEN_BGR
    assert (draw_image_frame(_image(), overlay, 50) == GREY).all()
    grey = draw_image_frame(np.full((100, 120), GREY, np.uint8), image_overlay(_trajectory(), None), 5)
    assert grey.shape == (100, 120, 3) and tuple(grey[25, 50]) == (GREY,) * 3  # no truth given: none drawn


def test_one_track_and_what_cannot_be_drawn() -> None:
    only = image_overlay(_trajectory(), None, track_id=2)
    assert only.tracks.ids.tolist() == [2]
    with pytest.raises(TrackreplayError, match="no track 9 with image positions"):
        image_overlay(_trajectory(), None, track_id=9)
    lost = trajectory_table([state_row("flow", 0, 0, TrackState(1, status="lost"))])
    with pytest.raises(TrackreplayError, match="no image positions"):
        image_overlay(lost, None)
    assert not has_lines_of_sight(_trajectory())
