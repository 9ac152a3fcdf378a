"""trackreplay bench: what read+decode counts, and where its --json goes."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from trackreplay.replay.runs import bench
from trackreplay.replay.cli.main import main
from trackreplay.replay.cli.commands import bench as bench_cmd

GOLDEN = Path(__file__).resolve().parents[2] / "golden"
FAKE = bench.ReplayTiming(frames=10, read_decode_s=1.0, replay_s=2.0, replay_rrd_s=3.0, rrd_bytes=100)


def test_read_decode_decodes_both_images_of_a_stereo_pair(monkeypatch) -> None:
    """A review: only the left image was decoded, so a stereo replay's ratio was understated ~2x."""
    decoded: list[str] = []
    real = bench.decode_image

    def counting(data, schema, where):
        decoded.append(where.split(": ")[1].rsplit(" message", 1)[0])
        return real(data, schema, where)

    monkeypatch.setattr(bench, "decode_image", counting)
    frames = bench.read_decode(GOLDEN / "groups-crossing-320x240.mcap")
    assert frames > 0 and sorted(set(decoded)) == ["/stereo/left/image", "/stereo/right/image"]
    assert decoded.count("/stereo/left/image") == decoded.count("/stereo/right/image") == frames
    decoded.clear()
    assert bench.read_decode(GOLDEN / "flow-sim1-24f.mcap") == len(decoded) == 24  # one camera: one image a frame


def test_a_json_in_a_missing_folder_fails_before_timing(monkeypatch, short_sim: Path, tmp_path: Path, capsys) -> None:
    def never(*args, **kwargs):
        raise AssertionError("timed before checking --json")

    monkeypatch.setattr(bench_cmd, "time_replay", never)
    target = tmp_path / "nodir" / "x.json"
    assert main(["bench", str(short_sim), "--json", str(target)]) == 5
    assert capsys.readouterr().err.strip() == (f"trackreplay: error: cannot write --json {target}: the folder "
                                               f"{target.parent} does not exist")


def test_the_json_is_complete_or_absent(monkeypatch, disk_full_at, short_sim: Path, tmp_path: Path, capsys) -> None:
    monkeypatch.setattr(bench_cmd, "time_replay", lambda *args: FAKE)
    target = tmp_path / "b.json"
    assert main(["bench", str(short_sim), "--json", str(target)]) == 0
    assert json.loads(target.read_text())["throughput_ratio"] == pytest.approx(0.5)
    target.unlink()
    disk_full_at("b.json")
    assert main(["bench", str(short_sim), "--json", str(target)]) == 5
    assert "cannot write" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []
