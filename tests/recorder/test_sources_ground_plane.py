"""record --ground-plane FILE: JSON matrix or point fit -> /camera/ground_plane -> Frame.ground_plane."""

import json

import numpy as np
import pytest

from trackreplay.recorder.sources.ground_plane import read_ground_plane
from trackreplay.replay.cli.main import main
from trackreplay.replay.log.frames import FrameTopics, iter_frames
from trackreplay.replay.log.reader import LogReader
from trackreplay.schemas.errors import SourceError

H = [[0.02, 0.0, -0.64], [0.0, -0.001, 0.5], [0.0, 0.004, -0.05]]


def _write(path, **data):
    base = {"width": 64, "height": 48, "camera_ground": [0.0, 0.0], "camera_height": 3.0}
    base.update(data)
    path.write_text(json.dumps(base))
    return path


def test_matrix_and_points_give_the_same_plane(tmp_path):
    cal, warnings = read_ground_plane(_write(tmp_path / "m.json", image_to_ground=H))
    assert warnings == () and np.allclose(cal.matrix, H)
    Hm = np.array(H)
    uv = np.array([[5.0, 40.0], [60.0, 40.0], [10.0, 20.0], [50.0, 25.0], [32.0, 30.0]])
    q = np.c_[uv, np.ones(5)] @ Hm.T
    pts = np.c_[uv, q[:, :2] / q[:, 2:]]
    fitted, warnings = read_ground_plane(_write(tmp_path / "p.json", points=pts.tolist()))
    assert warnings == ()
    np.testing.assert_allclose(fitted.matrix / fitted.matrix[2, 1], Hm / Hm[2, 1], atol=1e-6)


@pytest.mark.parametrize("bad, says", [({"image_to_ground": H, "points": []}, "exactly one"),
                                       ({"image_to_ground": [1, 2]}, "needs 9 numbers"),
                                       ({}, "exactly one")])
def test_bad_files_are_one_sentence(tmp_path, bad, says):
    with pytest.raises(SourceError, match=says):
        read_ground_plane(_write(tmp_path / "bad.json", **bad))


def test_record_writes_the_plane_and_replay_hands_it_to_frames(tmp_path, make_images):
    images = make_images(tmp_path / "img", 3)
    log = tmp_path / "g.mcap"
    assert main(["record", str(log), "--images", str(images), "--fps", "10", "--ground-plane",
                 str(_write(tmp_path / "m.json", image_to_ground=H)), "--quiet"]) == 0
    assert LogReader(log).topics()["/camera/ground_plane"].count == 1
    frames = list(iter_frames(LogReader(log), FrameTopics()))
    assert len(frames) == 3 and all(f.ground_plane is not None for f in frames)
    np.testing.assert_allclose(frames[0].ground_plane.image_to_ground, H)
    assert frames[0].ground_plane.camera_height == 3.0
