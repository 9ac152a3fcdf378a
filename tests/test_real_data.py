"""The tools on public recordings no one here made (skipped when ../shared/data/real is absent)."""

from pathlib import Path

import pytest

from trackreplay.replay.cli.main import main
from trackreplay.replay.log.reader import LogReader

REAL = Path(__file__).resolve().parents[2] / "shared" / "data" / "real"
ROSBAGS = sorted((REAL / "mcap_rosbag2").rglob("*.mcap")) if REAL.is_dir() else []
OTB = REAL / "otb_crossing"

pytestmark = pytest.mark.skipif(not REAL.is_dir(), reason="../shared/data/real is absent")


@pytest.mark.parametrize("bag", ROSBAGS, ids=[p.name for p in ROSBAGS])
def test_foreign_mcap_is_read_and_replay_says_what_is_missing(bag: Path, capsys: pytest.CaptureFixture) -> None:
    reader = LogReader(bag)
    assert reader.topics()  # written by libmcap / the Go library
    assert main(["info", str(bag)]) == 0
    assert main(["replay", str(bag), "--tracker", "flow", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "has no image topic (schemas foxglove.RawImage, " in err and "; topics present: " in err
    for topic in reader.topics():  # each named with its schema
        assert f"{topic} ({reader.topics()[topic].schema}" in err


def test_otb_image_folder_records_and_tracks_with_its_ground_truth(tmp_path: Path) -> None:
    log = tmp_path / "crossing.mcap"
    assert main(["record", str(log), "--images", str(OTB / "img"), "--fps", "30", "--groundtruth",
                 str(OTB / "groundtruth_rect.txt"), "--quiet"]) == 0
    reader = LogReader(log)
    topics = reader.topics()
    assert topics["/camera/image"].count == 120 and topics["/groundtruth/objects"].count == 120
    first = next(reader.messages(["/camera/image"])).decode()
    assert first.format == "jpeg" and first.data == (OTB / "img" / "0001.jpg").read_bytes()
