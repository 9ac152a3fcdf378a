"""`annotate --from-truth`: start a log as its benchmark says, from its own ground truth."""

from __future__ import annotations

from pathlib import Path

import pytest

from trackreplay.recorder.annotate import Mark, clip_mark, marks_from_truth
from trackreplay.recorder.record import record
from trackreplay.replay.cli.main import main
from trackreplay.replay.log.frames import read_hints
from trackreplay.replay.log.reader import LogReader
from trackreplay.schemas import topics as T
from trackreplay.schemas.errors import SourceError


@pytest.fixture
def box_log(tmp_path, make_images) -> Path:
    """Four 64x48 frames; OTB truth absent on frame 0, then 1-based boxes."""
    gt = tmp_path / "groundtruth_rect.txt"
    gt.write_text("0,0,0,0\n11,21,10,8\n13,23,10,8\n")
    log = tmp_path / "boxes.mcap"
    record(log, images=make_images(tmp_path / "img", 4), fps=10, groundtruth=gt, quiet=True)
    return log


@pytest.fixture
def point_log(tmp_path, make_images) -> Path:
    """Four 64x48 frames; point truth on frames 1 (near the left edge) and 3."""
    gt = tmp_path / "labels.csv"
    gt.write_text("frame,visible,x,y\n0,0,-1,-1\n1,1,2.0,30.0\n3,1,40.5,20.5\n")
    log = tmp_path / "points.mcap"
    record(log, images=make_images(tmp_path / "img", 4), fps=10, groundtruth=gt, quiet=True)
    return log


def test_first_visible_box_is_marked_as_the_truth_says(box_log: Path) -> None:
    # OTB 11,21,10,8 (1-based top-left) is the 0-based top-left 10,20 with that size
    (mark,) = marks_from_truth(box_log)
    assert (mark.frame, mark.x, mark.y, mark.w, mark.h, mark.label) == (1, 10.0, 20.0, 10.0, 8.0, "target")
    (mark,) = marks_from_truth(box_log, frame=2, label="ball", mark_size=30)  # a box keeps its own size
    assert (mark.frame, mark.x, mark.y, mark.w, mark.h, mark.label) == (2, 12.0, 22.0, 10.0, 8.0, "ball")


def test_a_point_gets_a_square_round_it(point_log: Path) -> None:
    (mark,) = marks_from_truth(point_log)
    assert (mark.frame, mark.x, mark.y, mark.w, mark.h) == (1, -4.0, 24.0, 12.0, 12.0)
    (mark,) = marks_from_truth(point_log, frame=3, mark_size=5)
    assert (mark.x, mark.y, mark.w, mark.h) == (38.0, 18.0, 5.0, 5.0)
    clipped = clip_mark(marks_from_truth(point_log)[0], 64, 48)  # the square reached 4 px past the left edge
    assert (clipped.frame, clipped.x, clipped.y, clipped.w, clipped.h) == (1, 0.0, 24.0, 8.0, 12.0)


@pytest.mark.parametrize("kwargs, match", [
    ({"frame": 0}, r"does not place any object visibly on frame 0 \(objects visible there: none\)"),
    ({"frame": 2}, r"does not label frame 2 \(it labels 3 frames, 0-3\)"),
    ({"ids": [7]}, r"places no object 7 visibly on any of its 3 frames"),
    ({"frame": 1, "ids": [1, 7]}, r"does not place object 7 visibly on frame 1 \(objects visible there: 1\)"),
    ({"mark_size": 0.5}, r"at least one pixel"),
])
def test_what_cannot_be_marked_is_named(point_log: Path, kwargs, match) -> None:
    with pytest.raises(SourceError, match=match):
        marks_from_truth(point_log, **kwargs)


def test_clip_mark_refuses_a_box_outside_the_picture() -> None:
    with pytest.raises(SourceError, match=r"lies outside the 64x48 picture"):
        clip_mark(Mark(0, 70.0, 10.0, 12.0, 12.0), 64, 48)


def test_cli_marks_from_truth_and_clips_to_the_picture(point_log: Path, box_log: Path, tmp_path: Path,
                                                         capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "marked.mcap"
    assert main(["annotate", str(point_log), "--from-truth", "--label", "ball", "--out", str(out)]) == 0
    assert "1 marked region(s) on frames [1]" in capsys.readouterr().out
    (region,) = read_hints(LogReader(out), T.ANNOTATIONS_INIT)
    assert (region.frame, region.x, region.y, region.w, region.h, region.label) == (1, 4.0, 30.0, 8.0, 12.0, "ball")
    assert main(["annotate", str(box_log), "--from-truth", "--frame", "2", "--in-place"]) == 0
    (region,) = read_hints(LogReader(box_log), T.ANNOTATIONS_INIT)
    assert (region.frame, region.x, region.y, region.w, region.h) == (2, 17.0, 26.0, 10.0, 8.0)
    assert main(["annotate", str(box_log), "--truth-id", "1", "--out", str(out)]) == 2
    assert "--truth-id needs --from-truth" in capsys.readouterr().err


REAL = Path(__file__).resolve().parents[3] / "shared" / "data" / "real"


@pytest.mark.skipif(not (REAL / "otb_crossing").is_dir(), reason="../shared/data/real is absent")
def test_otb_crossing_starts_from_its_first_box(tmp_path: Path) -> None:
    """OTB's protocol: the tracker starts from the first frame's truth box (205,151,17,50, 1-based)."""
    otb = REAL / "otb_crossing"
    log = tmp_path / "crossing.mcap"
    record(log, images=otb / "img", fps=30, groundtruth=otb / "groundtruth_rect.txt", quiet=True)
    assert main(["annotate", str(log), "--from-truth", "--in-place"]) == 0
    (region,) = read_hints(LogReader(log), T.ANNOTATIONS_INIT)
    assert (region.frame, region.x - region.w / 2, region.y - region.h / 2, region.w, region.h) == (0, 204.0, 150.0, 17.0, 50.0)
