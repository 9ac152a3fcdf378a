"""`trackreplay frame` (a PNG with a pixel grid) and the checks `annotate`/replay make on marks."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from trackreplay.replay.cli.main import main
from trackreplay.replay.core.engine import ReplayRequest, replay
from trackreplay.replay.log.reader import LogReader
from trackreplay.schemas.errors import LogError


def test_frame_png_has_the_pixels_and_a_grid(short_sim: Path, tmp_path: Path, capsys) -> None:
    out = tmp_path / "f.png"
    assert main(["frame", str(short_sim), "3", "--out", str(out), "--grid", "10", "--scale", "2"]) == 0
    assert "frame 3 of /camera/image" in capsys.readouterr().out
    plain = tmp_path / "p.png"
    assert main(["frame", str(short_sim), "3", "--out", str(plain), "--plain"]) == 0
    pixels = cv2.imread(str(plain), cv2.IMREAD_UNCHANGED)
    item = [m for m in LogReader(short_sim).messages(["/camera/image"]) if m.index == 3][0]
    expected = cv2.imdecode(np.frombuffer(item.decode().data, np.uint8), cv2.IMREAD_UNCHANGED)
    assert np.array_equal(pixels, expected)
    grid = cv2.imread(str(out))
    h, w = expected.shape[:2]
    assert grid.shape[0] > 2 * h and grid.shape[1] > 2 * w  # enlarged, plus margins for the labels
    assert main(["frame", str(short_sim), "99", "--out", str(out)]) == 2
    assert "has no frame 99 on /camera/image (it has 12 frames)" in capsys.readouterr().err


def test_annotate_refuses_boxes_outside_the_image(short_sim: Path, tmp_path: Path, capsys) -> None:
    width = cv2.imdecode(np.frombuffer(LogReader(short_sim).first("/camera/image").data, np.uint8), 0).shape[1]
    out = tmp_path / "m.mcap"
    assert main(["annotate", str(short_sim), "--frame", "0", "--box", f"{width - 5},10,10,10", "--out", str(out)]) == 2
    assert "is not inside the" in capsys.readouterr().err and not out.exists()
    assert main(["annotate", str(short_sim), "--frame", "0", "--box=-1,10,10,10", "--out", str(out)]) == 2


def test_labels_a_tracker_ignores_are_refused(short_sim: Path, tmp_path: Path, capsys) -> None:
    out = tmp_path / "ball.mcap"
    assert main(["annotate", str(short_sim), "--frame", "0", "--box", "10,10,8,8", "--label", "ball",
                 "--tracker", "flow", "--out", str(out)]) == 2
    assert "reads only 'target'" in capsys.readouterr().err
    assert main(["annotate", str(short_sim), "--frame", "0", "--box", "10,10,8,8", "--label", "ball",
                 "--tracker", "golf", "--out", str(out)]) == 0
    with pytest.raises(LogError, match="labelled 'ball' would be ignored by the flow tracker"):
        replay(ReplayRequest(log=out, tracker="flow"))


def test_two_golf_marks_on_a_frame_need_one_labelled_start(short_sim: Path, tmp_path: Path, capsys) -> None:
    """A review marked a wrong box and the ball on one frame: the golf tracker started from the first
    (the wrong one) and tracked nothing, exit 0; swapped, it tracked the ball."""
    two = tmp_path / "two.mcap"
    args = ["annotate", str(short_sim), "--frame", "0", "--box", "10,10,8,8", "--box", "40,40,8,8", "--label", "ball"]
    assert main(args + ["--tracker", "golf", "--out", str(two)]) == 2
    assert "frame 0 has 2 different marks and the golf tracker follows one ball" in capsys.readouterr().err
    assert main(args + ["--out", str(two)]) == 0  # without --tracker annotate does not know who will read them
    with pytest.raises(LogError, match=r"frame 0 has \d different marks"):  # (and the log's own mark)
        replay(ReplayRequest(log=two, tracker="golf"))
    start = tmp_path / "start.mcap"  # one of them labelled start: that one starts the track
    assert main(["annotate", str(two), "--frame", "0", "--box", "12,12,8,8", "--label", "start", "--out", str(start)]) == 0
    replay(ReplayRequest(log=start, tracker="golf"))
    same = tmp_path / "same.mcap"  # the same box twice is one mark
    assert main(["annotate", str(short_sim), "--frame", "0", "--box", "10,10,8,8", "--box", "10,10,8,8", "--label", "ball",
                 "--tracker", "golf", "--out", str(same)]) == 0


def test_a_csv_mark_outside_the_image_names_its_line(short_sim: Path, tmp_path: Path, capsys) -> None:
    """A review: a --from-csv mark outside the picture was refused without its CSV line."""
    marks = tmp_path / "marks.csv"
    marks.write_text("frame,x,y,w,h\n0,10,10,8,8\n1,5000,10,8,8\n")
    assert main(["annotate", str(short_sim), "--from-csv", str(marks), "--out", str(tmp_path / "o.mcap")]) == 2
    assert f"{marks}:3: the box 5000,10,8,8 on frame 1 is not inside" in capsys.readouterr().err
