"""The log's ground truth as a table: boxes and point truths (a centre, no size) alike."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import polars as pl

from trackreplay.recorder.record import record
from trackreplay.replay.log.groundtruth import groundtruth_with_frames, read_groundtruth
from trackreplay.replay.log.reader import LogReader


def _log(tmp_path: Path, name: str, text: str) -> Path:
    folder = tmp_path / "img"
    folder.mkdir(exist_ok=True)
    for i in range(4):
        cv2.imwrite(str(folder / f"{i:04d}.png"), np.full((24, 32, 3), 40 * i, np.uint8))
    truth = tmp_path / name
    truth.write_text(text)
    log = tmp_path / f"{name}.mcap"
    record(log, images=folder, fps=10, groundtruth=truth, quiet=True)
    return log


def test_point_truth_has_a_centre_and_null_size(tmp_path: Path) -> None:
    log = _log(tmp_path, "labels.csv", "frame,visible,x,y\n0,1,3.5,4.5\n2,0,-1,-1\n3,1,30,20\n")
    gt, annotated = groundtruth_with_frames(LogReader(log))
    assert annotated["frame"].to_list() == [0, 2, 3]  # frame 1 is not labelled
    assert gt.select("frame", "id", "x", "y", "w", "h", "visible").rows() == [
        (0, 1, 3.5, 4.5, None, None, True), (2, 1, None, None, None, None, False), (3, 1, 30.0, 20.0, None, None, True)]


def test_vot_and_tracknet_truths_read_back_in_pixels(tmp_path: Path) -> None:
    vot = read_groundtruth(LogReader(_log(tmp_path, "groundtruth.txt", "1,2,1,6,5,6,5,2\nnan,nan,nan,nan,nan,nan,nan,nan\n")))
    assert vot.select("frame", "x", "y", "w", "h", "visible").rows() == [(0, 3.0, 4.0, 4.0, 4.0, True),
                                                                         (1, None, None, None, None, False)]
    tracknet = read_groundtruth(LogReader(_log(tmp_path, "rally_ball.csv", "Frame,Visibility,X,Y\n1,2,0.25,0.5\n")))
    assert tracknet.select("frame", "x", "y", "w").rows() == [(1, 8.0, 12.0, None)]  # of a 32x24 picture
    assert tracknet.schema["w"] == pl.Float64
