"""`trackreplay cat`: a log's messages as JSON lines; images as their size and shape, never their bytes."""

import json
from pathlib import Path

import pytest

from trackreplay.replay.cli.main import main
from trackreplay.replay.log.reader import LogReader

GOLDEN = Path(__file__).resolve().parents[2] / "golden"
ROS_BAGS = Path(__file__).resolve().parents[4] / "shared" / "data" / "real" / "mcap_rosbag2"


def lines(capsys) -> list[dict]:
    return [json.loads(line) for line in capsys.readouterr().out.splitlines()]


def test_messages_in_log_time_order_with_decoded_fields(capsys) -> None:
    log = GOLDEN / "flow-sim1-24f.mcap"
    assert main(["cat", str(log), "--topic", "groundtruth/*", "--limit", "3"]) == 0
    rows = lines(capsys)
    assert [r["index"] for r in rows] == [0, 1, 2] and {r["topic"] for r in rows} == {"/groundtruth/objects"}
    assert [r["log_time_ns"] for r in rows] == sorted(r["log_time_ns"] for r in rows)
    first = rows[0]["message"]
    assert first["frame"] == 0 and first["objects"][0]["id"] == 1 and isinstance(first["objects"][0]["x"], float)


def test_an_image_is_its_shape_encoding_and_size(capsys) -> None:
    log = GOLDEN / "flow-sim1-24f.mcap"
    assert main(["cat", str(log), "--topic", "/camera/image", "--limit", "1"]) == 0
    (row,) = lines(capsys)
    (first,) = LogReader(log).messages_at("/camera/image", [0])
    msg = row["message"]
    assert row["schema"] == "foxglove.CompressedImage" and msg["format"] == "png"
    assert msg["data"] == {"size": len(first.decode().data), "shape": [256, 256]}


def test_exclude_and_every_topic(capsys) -> None:
    log = GOLDEN / "flow-sim1-24f.mcap"
    assert main(["cat", str(log), "--exclude", "re:/camera/.*", "--exclude", "/groundtruth/objects"]) == 0
    rows = lines(capsys)
    expected = sum(t.count for name, t in LogReader(log).topics().items() if name not in ("/camera/image", "/groundtruth/objects"))
    assert len(rows) == expected > 0 and all(not r["topic"].startswith("/camera/") for r in rows)


def test_bad_input_is_one_sentence(tmp_path: Path, capsys) -> None:
    log = GOLDEN / "flow-sim1-24f.mcap"
    assert main(["cat", str(log), "--topic", "/lidar/*"]) == 2
    assert capsys.readouterr().err.startswith("trackreplay: error: ") and True
    assert main(["cat", str(tmp_path / "none.mcap")]) == 2
    assert "none.mcap does not exist" in capsys.readouterr().err


def test_a_damaged_chunk_prints_the_rest_then_exits_3(tmp_path: Path, capsys) -> None:
    from mcap.reader import make_reader

    log = GOLDEN / "flow-sim1-24f.mcap"
    with open(log, "rb") as fh:
        chunks = sorted(make_reader(fh).get_summary().chunk_indexes, key=lambda c: c.chunk_start_offset)
    data = bytearray(log.read_bytes())
    data[chunks[0].chunk_start_offset + chunks[0].chunk_length // 2] ^= 0x10
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(bytes(data))
    assert main(["cat", str(bad), "--topic", "/camera/image"]) == 3
    captured = capsys.readouterr()
    assert 0 < len(captured.out.splitlines()) < LogReader(log).topics()["/camera/image"].count
    assert "could not be read" in captured.err and "trackreplay recover" in captured.err and captured.err.count("\n") == 1


@pytest.mark.skipif(not ROS_BAGS.is_dir(), reason="needs ../shared/data/real/mcap_rosbag2")
def test_a_ros2_bag_prints_its_cdr_fields(capsys) -> None:
    bag = next(ROS_BAGS.rglob("talker.mcap"))
    assert main(["cat", str(bag), "--topic", "/topic", "--limit", "2"]) == 0
    rows = lines(capsys)
    assert len(rows) == 2 and rows[0]["schema"] == "std_msgs/msg/String" and isinstance(rows[0]["message"]["data"], str)
