"""`record` as a function and as the CLI verb."""

from __future__ import annotations

import argparse
import json

import pytest

from trackreplay.recorder.record import RecordTopics, record
from trackreplay.replay.cli.commands import record as record_cmd
from trackreplay.schemas.errors import TrackreplayError


def run_cli(*argv):
    parser = argparse.ArgumentParser()
    record_cmd.add_parser(parser.add_subparsers())
    args = parser.parse_args(["record", *map(str, argv)])
    return args.func(args)


def test_cli_all_inputs(tmp_path, make_images, log_messages, capsys):
    folder = make_images(tmp_path / "img", 5)
    enc = tmp_path / "enc.csv"
    enc.write_text("t_ns,pan,tilt,zoom,focus\n" + "".join(f"{t},0,0,1,1\n" for t in range(0, 600_000_000, 50_000_000)))
    lens = tmp_path / "lens.csv"
    lens.write_text("1,1,50,50,32,24\n")
    calib = tmp_path / "cam.json"
    calib.write_text(json.dumps({"width": 64, "height": 48, "K": [50, 0, 32, 0, 50, 24, 0, 0, 1]}))
    gt = tmp_path / "gt.txt"
    gt.write_text("1,1,0,0,4,4,1,-1,-1,-1\n")
    out = tmp_path / "out.mcap"
    code = run_cli(out, "--images", folder, "--fps", 10, "--t0", 1000, "--encoders", enc, "--lens-table", lens,
                   "--calibration", calib, "--groundtruth", gt, "--gt-format", "mot", "--flush-every", 3,
                   "--topic", "camera_image=/cam0/image", "--topic", "encoders=/head/ptz")
    assert code == 0
    assert "wrote" in capsys.readouterr().err
    topics = {}
    for m in log_messages(out):
        topics[m.topic] = topics.get(m.topic, 0) + 1
    assert topics == {"/cam0/image": 5, "/camera/calibration": 1, "/ptz/lens_table": 1, "/groundtruth/objects": 5, "/head/ptz": 12}


def test_cli_rejects_bad_topic_and_flush(tmp_path, make_images):
    folder = make_images(tmp_path / "img", 1)
    with pytest.raises(TrackreplayError, match="KEY=/name"):
        run_cli(tmp_path / "o.mcap", "--images", folder, "--fps", 1, "--topic", "nonsense=/x")
    with pytest.raises(TrackreplayError, match="--flush-every must be at least 1"):
        run_cli(tmp_path / "o.mcap", "--images", folder, "--fps", 1, "--flush-every", 0)


def test_cli_user_error_is_one_line_and_exit_2(tmp_path, make_images, capsys):
    from trackreplay.replay.cli.main import main

    folder = make_images(tmp_path / "img", 2)
    enc = tmp_path / "enc.csv"
    enc.write_text("t_ns,pan,tilt,zoom,focus\n0,1,2,3,4\n5,1,2,3\n")
    assert main(["record", str(tmp_path / "o.mcap"), "--images", str(folder), "--fps", "5", "--encoders", str(enc), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("trackreplay: error: ") and "enc.csv:3: expected 5 columns" in err[0]


def test_output_may_not_be_an_input(tmp_path, make_video):
    video = make_video(tmp_path / "v.avi", 2)
    with pytest.raises(TrackreplayError, match="is also an input"):
        record(video, video=video, quiet=True)
    assert video.stat().st_size > 0


def test_default_topics_follow_the_contract():
    t = RecordTopics()
    assert (t.camera_image, t.left_image, t.right_calibration, t.encoders, t.groundtruth) == (
        "/camera/image", "/stereo/left/image", "/stereo/right/calibration", "/ptz/encoders", "/groundtruth/objects")
