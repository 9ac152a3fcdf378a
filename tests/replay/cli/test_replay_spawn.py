"""`replay --spawn`: the viewer is spawned for the replay's own recording; without a display, one sentence."""

from pathlib import Path

import pytest
import rerun as rr
import rerun.chunk as rc

from trackreplay.replay.cli.main import main
from trackreplay.replay.views import rerun_sink


@pytest.fixture
def fake_viewer(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> dict:
    """A viewer that 'starts' without a window: spawn calls are kept, its gRPC stream goes to a file."""
    seen: dict = {"spawns": [], "stream": tmp_path / "viewer.rrd", "listening": True}

    def spawn(**kwargs) -> None:
        seen["spawns"].append(kwargs)

    monkeypatch.setattr(rr, "spawn", spawn)
    monkeypatch.setattr(rr, "GrpcSink", lambda url: rr.FileSink(str(seen["stream"])))
    monkeypatch.setattr(rerun_sink, "_viewer_listening", lambda port: seen["listening"])
    monkeypatch.setenv("DISPLAY", ":0")
    return seen


def test_spawn_binds_the_viewer_to_the_replay_recording(fake_viewer: dict, short_sim: Path) -> None:
    assert main(["replay", str(short_sim), "--tracker", "flow", "--spawn", "--quiet"]) == 0
    (call,) = fake_viewer["spawns"]
    # rr.spawn without `recording` checks the (absent) global recording and ignores the call
    assert isinstance(call.get("recording"), rr.RecordingStream) and call["connect"] is False
    paths = {str(c.entity_path) for c in rc.RrdReader(str(fake_viewer["stream"])).stream()}
    assert f"/{rerun_sink.CAMERA}" in paths  # the replay's images reached the viewer


def test_a_viewer_that_does_not_listen_still_leaves_the_rrd(fake_viewer: dict, short_sim: Path, tmp_path: Path,
                                                            capsys: pytest.CaptureFixture) -> None:
    fake_viewer["listening"] = False
    rrd = tmp_path / "r.rrd"
    assert main(["replay", str(short_sim), "--tracker", "flow", "--spawn", "--rrd", str(rrd), "--quiet"]) == 5
    err = capsys.readouterr().err.strip()
    assert err.startswith("trackreplay: error: cannot open a Rerun viewer: ") and "\n" not in err
    assert f"{rrd} was written" in err and rrd.stat().st_size > 0 and not fake_viewer["stream"].exists()


def test_without_a_display_no_viewer_is_started(fake_viewer: dict, monkeypatch: pytest.MonkeyPatch, short_sim: Path,
                                               tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    for name in ("DISPLAY", "WAYLAND_DISPLAY", "WAYLAND_SOCKET"):
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setattr(rerun_sink.sys, "platform", "linux")
    assert main(["replay", str(short_sim), "--tracker", "flow", "--spawn", "--quiet"]) == 5
    err = capsys.readouterr().err.strip()
    assert "no display" in err and "--rrd FILE" in err and "\n" not in err
    rrd = tmp_path / "r.rrd"
    assert main(["replay", str(short_sim), "--tracker", "flow", "--spawn", "--rrd", str(rrd), "--quiet"]) == 5
    assert rrd.stat().st_size > 0 and fake_viewer["spawns"] == []
