"""`info`: counts, rates, gaps, stereo pairing, encoder coverage, truncated logs."""

from __future__ import annotations

import argparse
import json

import numpy as np
import pytest

from trackreplay.recorder.image_codec import image_message
from trackreplay.recorder.writer import LogWriter
from trackreplay.replay.cli.commands import info as info_cmd
from trackreplay.replay.log.info import format_info, log_info
from trackreplay.schemas import topics as T
from trackreplay.schemas.errors import LogError, TruncatedLogError
from trackreplay.schemas.records import PtzReading

MS = 1_000_000
IMG = np.zeros((8, 8), np.uint8)


def write_log(path, frames=(), encoders=(), left=(), right=(), flush_every=5):
    with LogWriter(path, flush_every=flush_every) as log:
        events = [(t, 0, T.CAMERA_IMAGE) for t in frames] + [(t, 1, T.PTZ_ENCODERS) for t in encoders]
        events += [(t, 2, T.STEREO_LEFT_IMAGE) for t in left] + [(t, 3, T.STEREO_RIGHT_IMAGE) for t in right]
        for t, kind, topic in sorted(events):
            msg = PtzReading(t, 0, 0, 0, 0).to_pb() if kind == 1 else image_message(IMG, "png", t)
            log.write(topic, msg, t)
    return path


def test_counts_rates_and_duration(tmp_path):
    path = write_log(tmp_path / "a.mcap", frames=[i * 40 * MS for i in range(26)], encoders=[i * 10 * MS for i in range(101)])
    info = log_info(path)
    topics = {e["topic"]: e for e in info["topics"]}
    assert topics[T.CAMERA_IMAGE]["count"] == 26 and topics[T.CAMERA_IMAGE]["schema"] == "foxglove.CompressedImage"
    assert topics[T.CAMERA_IMAGE]["rate_hz"] == pytest.approx(25.0)
    assert topics[T.PTZ_ENCODERS]["rate_hz"] == pytest.approx(100.0)
    assert info["messages"] == 127 and info["duration_s"] == pytest.approx(1.0)
    assert not info["truncated"] and info["gaps"][T.CAMERA_IMAGE]["gaps"] == []
    assert info["encoder_coverage"] == [{"image_topic": T.CAMERA_IMAGE, "encoder_topic": T.PTZ_ENCODERS,
                                         "tolerance_ns": 30 * MS, "outside": [], "sparse": []}]
    text = format_info(info)
    assert "/camera/image" in text and "25.00 Hz" in text and "gaps" not in text


def test_time_gaps_listed(tmp_path):
    frames = [i * 40 * MS for i in range(10)] + [1000 * MS + i * 40 * MS for i in range(10)]
    frames.remove(120 * MS)  # one dropped frame: an 80 ms interval
    info = log_info(write_log(tmp_path / "g.mcap", frames=frames))
    g = info["gaps"][T.CAMERA_IMAGE]
    assert g["median_interval_ns"] == 40 * MS
    assert [(x["after"], x["from_ns"], x["interval_ns"]) for x in g["gaps"]] == [(2, 80 * MS, 80 * MS), (8, 360 * MS, 640 * MS)]
    assert "time gaps on /camera/image" in format_info(info)


def test_stereo_pairing_problems(tmp_path):
    left = [0, 10 * MS, 20 * MS, 30 * MS]
    right = [0, 10 * MS, 21 * MS, 30 * MS, 40 * MS]
    info = log_info(write_log(tmp_path / "s.mcap", left=left, right=right))
    (s,) = info["stereo"]
    assert (s["pairs"], s["left_unpaired_ns"], s["right_unpaired_ns"]) == (3, [20 * MS], [21 * MS, 40 * MS])
    assert "stereo pairing: 3 pairs" in format_info(info)


def test_encoder_coverage_problems(tmp_path):
    frames = [i * 100 * MS for i in range(10)]  # 0 .. 900 ms
    encoders = [t * MS for t in range(100, 400, 10)] + [t * MS for t in range(600, 800, 10)]  # hole 390..600, ends at 790
    info = log_info(write_log(tmp_path / "e.mcap", frames=frames, encoders=encoders))
    (c,) = info["encoder_coverage"]
    assert c["outside"] == [0, 8, 9]
    assert [x["frame"] for x in c["sparse"]] == [4, 5] and c["tolerance_ns"] == 30 * MS
    text = format_info(info)
    assert "3 frame(s) of /camera/image outside" in text and "2 frame(s) of /camera/image between" in text


def test_truncated_log(tmp_path):
    path = write_log(tmp_path / "t.mcap", frames=[i * 40 * MS for i in range(40)])
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    with pytest.raises(TruncatedLogError, match=r"cut\.mcap is truncated: .*it ends early .*trackreplay recover .*cut\.mcap OUT"):
        log_info(cut)
    info = log_info(cut, partial_ok=True)
    assert info["truncated"] and not info["complete"] and info["error"] and 0 < info["messages"] < 40


def test_not_a_log(tmp_path):
    (tmp_path / "x.mcap").write_text("hello world, not mcap")
    with pytest.raises(LogError, match=r"x\.mcap is not an MCAP file"):
        log_info(tmp_path / "x.mcap")
    with pytest.raises(LogError, match=r"y\.mcap does not exist"):
        log_info(tmp_path / "y.mcap")


def run_cli(*argv):
    parser = argparse.ArgumentParser()
    info_cmd.add_parser(parser.add_subparsers())
    args = parser.parse_args(["info", *map(str, argv)])
    return args.func(args)


def test_cli_json_and_truncated_exit(tmp_path, capsys):
    path = write_log(tmp_path / "a.mcap", frames=[i * 40 * MS for i in range(40)])
    assert run_cli(path, "--json") == 0
    data = json.loads(capsys.readouterr().out)
    assert data["topics"][0]["count"] == 40
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(path.read_bytes()[:-50])
    from trackreplay.replay.cli.main import main

    assert main(["info", str(cut)]) == 3
    captured = capsys.readouterr()
    assert "TRUNCATED" in captured.out and "trackreplay recover" in captured.err


def test_info_names_damaged_stretches_and_counts_the_rest(flow_sim1, tmp_path, capsys):
    """A flipped byte inside a chunk: info reads past it, says where, and fails with status 3."""
    from mcap.reader import make_reader

    from trackreplay.replay.cli.main import main
    from trackreplay.replay.log.info import log_info

    with open(flow_sim1, "rb") as fh:
        summary = make_reader(fh).get_summary()
    first = min(summary.chunk_indexes, key=lambda c: c.chunk_start_offset)
    data = bytearray(flow_sim1.read_bytes())
    data[first.chunk_start_offset + first.chunk_length // 2] ^= 0x10
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(bytes(data))
    info = log_info(bad, partial_ok=True)
    assert not info["truncated"] and not info["complete"] and len(info["damaged"]) == 1
    assert info["damaged"][0]["start_byte"] == first.chunk_start_offset and info["damaged"][0]["chunks"] == [1]
    intact = log_info(flow_sim1)
    assert 0 < info["messages"] < intact["messages"] == info["messages_expected"]
    assert main(["info", str(bad)]) == 3
    captured = capsys.readouterr()
    out, err = captured.out, captured.err
    assert f"bytes {first.chunk_start_offset}-" in out and "DAMAGED: 1 unreadable stretch" in out
    # worded by what is true: one chunk unreadable, the end intact; not "TRUNCATED", not "no valid MCAP end"
    assert "TRUNCATED" not in out and "no valid MCAP end" not in err
    n = len(summary.chunk_indexes)
    assert (f"bad.mcap is damaged: chunk 1 of {n} at bytes {first.chunk_start_offset}-" in err
            and f"the log's end is intact; {info['messages']} of {intact['messages']} messages readable" in err)
    assert err.count("\n") == 1 and "trackreplay recover" in err


def test_a_bag_folder_is_read_through_its_one_mcap(tmp_path, capsys) -> None:
    """A ROS 2 bag is a folder (metadata.yaml beside the .mcap): the verbs take the folder (a review
    found it refused as 'not a file'); a folder with no or several .mcap files is named as such."""
    import shutil
    from pathlib import Path

    from trackreplay.replay.cli.main import main

    bag = tmp_path / "bag"
    bag.mkdir()
    (bag / "metadata.yaml").write_text("rosbag2_bagfile_information: {}\n")
    shutil.copy(Path(__file__).resolve().parents[2] / "golden" / "flow-sim1-24f.mcap", bag / "bag_0.mcap")
    assert main(["info", str(bag)]) == 0
    assert main(["replay", str(bag), "--tracker", "flow", "--quiet"]) == 0
    shutil.copy(bag / "bag_0.mcap", bag / "bag_1.mcap")
    capsys.readouterr()
    assert main(["info", str(bag)]) == 2
    assert "is a folder with 2 .mcap files: bag_0.mcap, bag_1.mcap" in capsys.readouterr().err
