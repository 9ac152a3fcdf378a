"""Importing MOTChallenge and OTB annotations."""

from __future__ import annotations

import pytest

from trackreplay.recorder.record import record
from trackreplay.recorder.sources.groundtruth import read_groundtruth
from trackreplay.schemas.errors import SourceError
from trackreplay.schemas.records import GroundTruthFrame, GroundTruthObject


def test_mot_rows_become_centre_boxes_on_zero_based_frames(tmp_path):
    gt = tmp_path / "gt.txt"
    gt.write_text(
        "1,3,10,20,4,6,1,-1,-1,-1\n"
        "1,1,0,0,10,10,1,1.5,2.5,0\n"
        "3,1,2,2,10,10,1,-1,-1,-1\n"
        "3,2,2,2,10,10,0,-1,-1,-1\n"  # conf 0: ignored entry
    )
    table = read_groundtruth(gt)
    assert table.format == "mot"
    assert table.objects_at(0) == (
        GroundTruthObject(id=1, x=4.0, y=4.0, w=10.0, h=10.0, X=1.5, Y=2.5, Z=0.0, visible=True),  # 1-based pixels
        GroundTruthObject(id=3, x=11.0, y=22.0, w=4.0, h=6.0, visible=True),
    )
    assert table.objects_at(1) == ()  # no rows: no objects, still a message
    assert [o.id for o in table.objects_at(2)] == [1]


def test_otb_separators_and_absent_target(tmp_path):
    gt = tmp_path / "groundtruth_rect.txt"
    gt.write_text("10,20,30,40\n11\t21\t30\t40\n0 0 0 0\nNaN,NaN,NaN,NaN\n12, 22, 30, 40\n")
    table = read_groundtruth(gt)
    assert table.format == "otb"
    assert table.objects_at(0) == (GroundTruthObject(id=1, x=24.0, y=39.0, w=30.0, h=40.0, visible=True),)  # 1-based -> 0-based
    assert table.objects_at(1)[0].x == 25.0
    for frame in (2, 3):
        assert table.objects_at(frame) == (GroundTruthObject(id=1, visible=False),)
    assert table.objects_at(4)[0].y == 41.0
    assert table.objects_at(5) is None


def test_old_mac_line_endings_and_a_truth_that_starts_later(tmp_path, make_images, log_messages):
    """A review: CR-only line endings read as one line (an error in MOT's column names); a truth file
    shorter than the image folder (OTB's David starts at image 300) recorded silently from frame 0."""
    gt = tmp_path / "groundtruth_rect.txt"
    gt.write_bytes(b"10,20,30,40\r11,21,30,40\r")
    assert sorted(read_groundtruth(gt).frames) == [0, 1]
    assert sorted(read_groundtruth(gt, first_frame=2).frames) == [2, 3]
    with pytest.raises(SourceError, match="first frame must be a frame number >= 0"):
        read_groundtruth(gt, first_frame=-1)
    folder = make_images(tmp_path / "img", 5)
    report = record(tmp_path / "a.mcap", images=folder, fps=20, groundtruth=gt, quiet=True)
    assert len(report.warnings) == 1 and "has 2 boxes for 5 recorded frames: they were taken as frames 0-1" in report.warnings[0]
    record(tmp_path / "b.mcap", images=folder, fps=20, groundtruth=gt, gt_first_frame=3, quiet=True)
    frames = [m.pb.frame for m in log_messages(tmp_path / "b.mcap") if m.topic == "/groundtruth/objects"]
    assert frames == [3, 4]


def test_otb_negative_size_names_the_line(tmp_path):
    gt = tmp_path / "groundtruth_rect.txt"
    gt.write_text("10,20,30,40\n10,20,-30,40\n")
    with pytest.raises(SourceError, match=r"groundtruth_rect.txt:2: width and height must not be negative"):
        read_groundtruth(gt)


def test_format_detection_by_columns(tmp_path):
    otb = tmp_path / "boxes.txt"
    otb.write_text("\n1 2 3 4\n")
    assert read_groundtruth(otb).format == "otb"
    with pytest.raises(SourceError, match=r"boxes\.txt:2: expected frame,id,"):  # an explicit format wins
        read_groundtruth(otb, "mot")
    odd = tmp_path / "odd.txt"
    odd.write_text("1,2,3\n")
    with pytest.raises(SourceError, match=r"odd\.txt:1: cannot tell the annotation format"):
        read_groundtruth(odd)


def test_groundtruth_recorded_at_frame_times(tmp_path, make_images, log_messages):
    folder = make_images(tmp_path / "img", 4)
    gt = tmp_path / "groundtruth_rect.txt"
    gt.write_text("1,1,4,4\nnan,nan,nan,nan\n3,3,4,4\n")  # 3 lines for 4 frames
    record(tmp_path / "out.mcap", images=folder, fps=20, groundtruth=gt, quiet=True)
    frames = [(m.log_time, GroundTruthFrame.from_pb(m.pb)) for m in log_messages(tmp_path / "out.mcap") if m.topic == "/groundtruth/objects"]
    assert [(t, f.frame, f.t_ns) for t, f in frames] == [(0, 0, 0), (50_000_000, 1, 50_000_000), (100_000_000, 2, 100_000_000)]
    assert frames[1][1].objects[0].visible is False and frames[1][1].objects[0].x is None
    assert frames[2][1].objects[0].x == 4.0  # 1-based 3 + 4/2 -> 0-based 4


def test_mot_every_frame_gets_a_message_and_extra_frames_warn(tmp_path, make_images, log_messages):
    folder = make_images(tmp_path / "img", 3)
    gt = tmp_path / "gt.txt"
    gt.write_text("2,1,0,0,2,2,1,-1,-1,-1\n9,1,0,0,2,2,1,-1,-1,-1\n")
    report = record(tmp_path / "out.mcap", images=folder, fps=20, groundtruth=gt, gt_format="mot", quiet=True)
    assert len(report.warnings) == 1 and "1 frame(s) after the last recorded frame (3)" in report.warnings[0]
    counts = [len(m.pb.objects) for m in log_messages(tmp_path / "out.mcap") if m.topic == "/groundtruth/objects"]
    assert counts == [0, 1, 0]


@pytest.mark.parametrize("name, text, match", [
    ("gt.txt", "1,1,0,0,2,2,1,-1,-1,-1\n0,1,0,0,2,2,1,-1,-1,-1\n", r"gt\.txt:2: frame '0' is not a 1-based frame number"),
    ("gt.txt", "1,1,0,0,2,2,1\n1,1,0,0,2,2,1\n", r"gt\.txt:2: id 1 appears twice in frame 1"),
    ("gt.txt", "1,1,0,0,-2,2,1\n", r"gt\.txt:1: box .* positive size"),
    ("gt.txt", "1,a,0,0,2,2,1\n", r"gt\.txt:1: id 'a' is not a number"),
    ("groundtruth_rect.txt", "1,2,3,4\n1,2,3\n", r"groundtruth_rect\.txt:2: expected x,y,w,h, got 3 values"),
    ("groundtruth_rect.txt", "1,2,3,four\n", r"groundtruth_rect\.txt:1: h 'four' is not a number"),
    ("groundtruth_rect.txt", "\n\n", r"groundtruth_rect\.txt is empty"),
    # a review: one NaN, or an infinity, was taken silently as "target absent"
    ("groundtruth_rect.txt", "1,2,3,4\n160,NaN,17,45\n", r"groundtruth_rect\.txt:2: the box 160,NaN,17,45 is neither a box nor"),
    ("groundtruth_rect.txt", "inf,140,17,45\n", r"groundtruth_rect\.txt:1: the box inf,140,17,45 is neither"),
])
def test_bad_annotation_rows(tmp_path, name, text, match):
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(SourceError, match=match):
        read_groundtruth(path)


def test_missing_annotation_file_and_bad_format(tmp_path):
    with pytest.raises(SourceError, match=r"annotation file .*gone\.txt does not exist"):
        read_groundtruth(tmp_path / "gone.txt")
    with pytest.raises(SourceError, match="format must be one of"):
        read_groundtruth(tmp_path / "gone.txt", "voc")
