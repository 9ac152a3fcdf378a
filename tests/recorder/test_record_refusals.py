"""Issue 33, defect 5: nonsense that was recorded silently is refused at record/annotate time, the
field named: a ROS camera_info calibration with nan (OpenCV reads it as 1.8e308), an all-zero
image_to_ground plane, a mark outside a 1x1 picture."""

import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from trackreplay.recorder.annotate import Mark, annotate
from trackreplay.recorder.record import record
from trackreplay.recorder.sources.ground_plane import read_ground_plane
from trackreplay.recorder.sources.stereo import load_calibration
from trackreplay.schemas.errors import SourceError

CAMERA_INFO = """image_width: {width}
image_height: 48
camera_name: cam
camera_matrix:
  rows: 3
  cols: 3
  data: [50, 0, 32, 0, {fy}, 24, 0, 0, 1]
distortion_model: plumb_bob
distortion_coefficients:
  rows: 1
  cols: 5
  data: [0, 0, 0, 0, {k1}]
"""


@pytest.mark.parametrize("fields, key", [
    ({"fy": "nan"}, "K"), ({"fy": "NaN"}, "K"), ({"k1": "nan"}, "D"), ({"width": "nan"}, "width"),
])
def test_a_ros_camera_info_with_nan_is_refused_naming_the_field(tmp_path: Path, fields: dict, key: str) -> None:
    path = tmp_path / "camera_info.yaml"
    path.write_text(CAMERA_INFO.format(**{"width": 64, "fy": 50, "k1": 0, **fields}))
    with pytest.raises(SourceError, match=rf"calibration {path}: {key}"):
        load_calibration(path)


def test_a_clean_ros_camera_info_still_reads(tmp_path: Path) -> None:
    path = tmp_path / "camera_info.yaml"
    path.write_text(CAMERA_INFO.format(width=64, fy=50, k1=0))
    assert load_calibration(path).left.K[4] == 50


@pytest.mark.parametrize("matrix", [[[0, 0, 0]] * 3, [[1, 2, 3], [2, 4, 6], [0, 0, 1]]], ids=["all-zero", "rank-2"])
def test_a_singular_image_to_ground_plane_is_refused(tmp_path: Path, matrix) -> None:
    path = tmp_path / "plane.json"
    path.write_text(json.dumps({"width": 64, "height": 48, "image_to_ground": matrix, "camera_ground": [0, 0],
                                "camera_height": 5}))
    with pytest.raises(SourceError, match=rf"{path}: image_to_ground is singular"):
        read_ground_plane(path)


def test_a_mark_outside_a_1x1_picture_is_refused_by_annotate(tmp_path: Path) -> None:
    folder = tmp_path / "img"
    folder.mkdir()
    for i in range(3):
        cv2.imwrite(str(folder / f"f{i}.png"), np.full((1, 1, 3), 40 * i, np.uint8))
    log = record(tmp_path / "one.mcap", images=folder, fps=10, quiet=True).path
    with pytest.raises(SourceError, match=r"marks.csv:2: the box x,y,w,h = 3,3,1,1 on frame 0 is not inside the 1x1"):
        annotate(log, tmp_path / "out.mcap", [Mark(0, 3, 3, 1, 1, "target", source="marks.csv:2")])
    assert not (tmp_path / "out.mcap").exists()
    assert annotate(log, tmp_path / "out.mcap", [Mark(0, 0, 0, 1, 1, "target")])[0].w == 1
