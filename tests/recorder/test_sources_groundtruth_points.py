"""Importing VOT polygons, point labels, TrackNet labels and reference points."""

from __future__ import annotations

from pathlib import Path

import pytest

from trackreplay.recorder.record import record
from trackreplay.recorder.sources.groundtruth import read_groundtruth
from trackreplay.schemas.errors import SourceError
from trackreplay.schemas.records import GroundTruthFrame, GroundTruthObject

REAL = Path(__file__).resolve().parents[3] / "shared" / "data" / "real"
ABSENT = GroundTruthObject(id=1, visible=False)


def test_vot_polygon_becomes_its_bounding_box_and_absent_lines(tmp_path):
    gt = tmp_path / "groundtruth.txt"
    gt.write_text(
        "10,20,10,5,40,5,40,20\n"  # an axis-aligned rectangle as four corners
        "25,0,50,25,25,50,0,25\n"  # a diamond: bounding box 0..50 both ways
        "nan,nan,nan,nan,nan,nan,nan,nan\n"
        "0,0,0,0,0,0,0,0\n"
        "0\n"  # a toolkit code (no region)
        "1.5\t2.5\t4\t6\n"  # a rectangle x,y,w,h
    )
    table = read_groundtruth(gt)
    assert table.format == "vot" and not table.dense
    assert table.objects_at(0) == (GroundTruthObject(id=1, x=25.0, y=12.5, w=30.0, h=15.0, visible=True),)
    assert table.objects_at(1) == (GroundTruthObject(id=1, x=25.0, y=25.0, w=50.0, h=50.0, visible=True),)
    assert [table.objects_at(f) for f in (2, 3, 4)] == [(ABSENT,)] * 3
    assert table.objects_at(5) == (GroundTruthObject(id=1, x=3.5, y=5.5, w=4.0, h=6.0, visible=True),)
    assert table.objects_at(6) is None


@pytest.mark.parametrize("text, match", [
    ("1,2,3,4,5\n", r"groundtruth\.txt:1: expected a polygon"),
    ("1,2,3,4,nan,6,7,8\n", r"groundtruth\.txt:1: the region .* is neither a region"),
    ("1,2,-3,4\n", r"groundtruth\.txt:1: the rectangle 1,2,-3,4 has a negative"),
])
def test_bad_vot_lines_are_named(tmp_path, text, match):
    gt = tmp_path / "groundtruth.txt"
    gt.write_text(text)
    with pytest.raises(SourceError, match=match):
        read_groundtruth(gt, "vot")


def test_point_labels_have_a_centre_and_no_box(tmp_path):
    gt = tmp_path / "labels.csv"
    gt.write_text("frame,visible,x,y,vis_orig\r\n0,1,10.5,20.25,1\r\n1,0,-1,-1,0\r\n5,1,3,4,2\r\n")
    table = read_groundtruth(gt)
    assert table.format == "points" and not table.normalised
    assert table.objects_at(0) == (GroundTruthObject(id=1, x=10.5, y=20.25, visible=True),)
    assert table.objects_at(1) == (ABSENT,)
    assert table.objects_at(2) is None  # not listed: not labelled
    assert table.objects_at(5)[0].w is None and table.objects_at(5)[0].x == 3.0


@pytest.mark.parametrize("text, match", [
    ("frame,visible,x,y\n0,2,1,1\n", r"labels\.csv:2: visible '2' is not one of 0, 1"),
    ("frame,visible,x,y\n0,1,1,1\n0,1,2,2\n", r"labels\.csv:3: frame 0 is labelled twice"),
    ("frame,visible,x,y\n-1,1,1,1\n", r"labels\.csv:2: frame '-1' is not a 0-based frame number"),
    ("frame,visible,x,y\n0,1,nan,1\n", r"labels\.csv:2: the position nan,1 of a visible target is not finite"),
    ("frame,visible,x,y\n0,1,1\n", r"labels\.csv:2: expected the header's 4 columns"),
    ("frame,visible,x,y\n", r"has a header and no rows"),
])
def test_bad_point_labels_are_named(tmp_path, text, match):
    gt = tmp_path / "labels.csv"
    gt.write_text(text)
    with pytest.raises(SourceError, match=match):
        read_groundtruth(gt)


def test_tracknet_normalised_labels_scale_by_the_image_size(tmp_path):
    gt = tmp_path / "00001.csv"
    gt.write_text("Frame,Ball,x,y\n0,1,0.5,0.25\n1,0,-1.000,-1.000\n2,1,1.0,0.0\n")
    table = read_groundtruth(gt)
    assert table.format == "tracknet" and table.normalised
    pixels = read_groundtruth(gt, image_size=(1280, 720))
    assert not pixels.normalised
    assert pixels.objects_at(0) == (GroundTruthObject(id=1, x=640.0, y=180.0, visible=True),)
    assert pixels.objects_at(1) == (ABSENT,)
    assert pixels.objects_at(2)[0].x == 1280.0 and pixels.objects_at(2)[0].y == 0.0


def test_tracknet_pixel_labels_visibility_classes_and_file_names(tmp_path):
    ball = tmp_path / "rally_ball.csv"
    ball.write_text("Frame,Visibility,X,Y,Z,Event,Timestamp,Fast\n0,0,0.0,0.0,0.0,0,0.0,0\n1,3,935.0,912.0,0,0,0.01,0\n")
    table = read_groundtruth(ball)
    assert table.format == "tracknet" and not table.normalised
    assert table.objects_at(0) == (ABSENT,)
    assert table.objects_at(1) == (GroundTruthObject(id=1, x=935.0, y=912.0, visible=True),)  # 3: occluded, placed
    label = tmp_path / "Label.csv"  # TrackNet v1 (tennis): frames named by their image file
    label.write_text("file name,visibility,x-coordinate,y-coordinate,status\n0000.jpg,0,,,0\n0001.jpg,2,600,400,0\n")
    table = read_groundtruth(label)
    assert table.format == "tracknet" and sorted(table.frames) == [0, 1]
    assert table.objects_at(1)[0].x == 600.0 and table.objects_at(0) == (ABSENT,)
    bad = tmp_path / "bad_ball.csv"
    bad.write_text("Frame,Visibility,X,Y\n0,4,1,1\n")
    with pytest.raises(SourceError, match=r"bad_ball\.csv:2: Visibility '4' is not one of 0, 1, 2, 3"):
        read_groundtruth(bad)


def test_reference_points_label_only_their_frames(tmp_path):
    ref = tmp_path / "reference.csv"
    ref.write_text("frame,x,y\r\n458,603.94,1026.98\r\n461,607.55,969.78\r\n")
    table = read_groundtruth(ref)
    assert table.format == "reference" and sorted(table.frames) == [458, 461]
    assert table.objects_at(458) == (GroundTruthObject(id=1, x=603.94, y=1026.98, visible=True),)
    assert table.objects_at(459) is None  # not labelled (not "invisible")
    assert sorted(read_groundtruth(ref, first_frame=2).frames) == [460, 463]


def test_detection_names_an_unknown_header(tmp_path):
    odd = tmp_path / "odd.csv"
    odd.write_text("time,u,v\n0,1,2\n")
    with pytest.raises(SourceError, match=r"odd\.csv:1: cannot tell the annotation format from the header 'time,u,v'"):
        read_groundtruth(odd)


def test_record_writes_point_truth_in_pixels_on_labelled_frames_only(tmp_path, make_images, log_messages):
    folder = make_images(tmp_path / "img", 4, size=(64, 48))
    gt = tmp_path / "labels_ball.csv"
    gt.write_text("Frame,Visibility,X,Y\n1,1,0.5,0.5\n3,0,0,0\n")
    report = record(tmp_path / "out.mcap", images=folder, fps=10, groundtruth=gt, quiet=True)
    assert report.warnings == ()  # two labelled frames of four: no "line 1 = frame ..." warning
    frames = [GroundTruthFrame.from_pb(m.pb) for m in log_messages(tmp_path / "out.mcap") if m.topic == "/groundtruth/objects"]
    assert [(f.frame, f.objects) for f in frames] == [
        (1, (GroundTruthObject(id=1, x=32.0, y=24.0, visible=True),)),  # 0.5 of 64x48
        (3, (ABSENT,)),
    ]


def test_record_command_takes_groundtruth_format(tmp_path, make_images, log_messages):
    from trackreplay.replay.cli.main import main

    folder = make_images(tmp_path / "img", 2)
    gt = tmp_path / "truth.txt"
    gt.write_text("1,1,5,1,5,9,1,9\n")  # eight values on a line: VOT either way
    assert main(["record", str(tmp_path / "out.mcap"), "--images", str(folder), "--fps", "5", "--groundtruth", str(gt),
                 "--groundtruth-format", "vot", "--quiet"]) == 0
    objs = [m.pb.objects[0] for m in log_messages(tmp_path / "out.mcap") if m.topic == "/groundtruth/objects"]
    assert [(o.x, o.y, o.w, o.h) for o in objs] == [(3.0, 5.0, 4.0, 8.0)]


REAL_FILES = {
    "ball_clips/badminton_alz_rawdata_00001/labels.csv": "points",
    "ball_clips/badminton_alz_rawdata_00001/labels_orig.csv": "tracknet",
    "ball_clips/badminton_chis_rally_cam1/labels.csv": "points",
    "ball_clips/badminton_chis_rally_cam1/labels_orig.csv": "tracknet",
    "ball_clips/vot2014_ball/labels.csv": "points",
    "ball_clips/vot2014_ball/groundtruth.txt": "vot",
    "sot_sequences/otb_car4/groundtruth_rect.txt": "otb",
    "sot_sequences/uav123_person12_1/groundtruth.txt": "otb",
    "otb_crossing/groundtruth_rect.txt": "otb",
    "pets09_s2l1/gt.txt": "mot",
    "golf_iron_shot_sky/reference.csv": "reference",
}


@pytest.mark.skipif(not REAL.is_dir(), reason="../shared/data/real is absent")
def test_every_real_annotation_is_detected_and_read():
    found = sorted(p.relative_to(REAL).as_posix() for pattern in ("ball_clips/*/labels*.csv", "ball_clips/*/groundtruth.txt",
                                                                   "sot_sequences/*/groundtruth*.txt", "otb_crossing/*.txt",
                                                                   "pets09_s2l1/gt.txt", "golf_iron_shot_sky/reference.csv")
                   for p in REAL.glob(pattern))
    assert set(REAL_FILES) <= set(found)
    for name in found:
        table = read_groundtruth(REAL / name)
        assert table.format == REAL_FILES.get(name, table.format), name
        assert any(o.visible for objs in table.frames.values() for o in objs), name
    # the VOT polygons' centres are the clip's point labels (to the labels' two decimals)
    vot = read_groundtruth(REAL / "ball_clips/vot2014_ball/groundtruth.txt")
    points = read_groundtruth(REAL / "ball_clips/vot2014_ball/labels.csv")
    assert all(abs(vot.objects_at(f)[0].x - points.objects_at(f)[0].x) < 0.006 for f in vot.frames)
    # TrackNet's normalised labels are the pixel labels beside them (rounded to 0.1 px there)
    orig = read_groundtruth(REAL / "ball_clips/badminton_alz_rawdata_00001/labels_orig.csv", image_size=(1280, 720))
    labels = read_groundtruth(REAL / "ball_clips/badminton_alz_rawdata_00001/labels.csv")
    assert sorted(orig.frames) == sorted(labels.frames)
    assert all(abs(orig.objects_at(f)[0].y - labels.objects_at(f)[0].y) < 0.06
               for f in orig.frames if orig.objects_at(f)[0].visible)
