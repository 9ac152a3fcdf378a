from pathlib import Path

import pytest
import rerun.chunk as rc

from trackreplay.replay.core import registry
from trackreplay.replay.core.engine import ReplayRequest, replay


def test_rrd_holds_camera_every_flow_intermediate_both_timelines_and_a_layout(short_sim: Path, tmp_path: Path) -> None:
    rrd = tmp_path / "flow.rrd"
    replay(ReplayRequest(log=short_sim, tracker="flow", rrd=rrd))
    reader = rc.RrdReader(str(rrd))
    assert [b.kind for b in reader.blueprints()] == ["blueprint"]
    paths, timelines = set(), set()
    for chunk in reader.stream():
        paths.add(str(chunk.entity_path))
        timelines.update(chunk.timeline_names)
    assert {"frame", "log_time"} <= timelines
    expected = {"/camera/image", "/trackers/flow/fov", "/trackers/flow/flow_field", "/trackers/flow/window/moving",
                "/trackers/flow/window/log10_cond", "/trackers/flow/histogram", "/trackers/flow/velocity/raw_x",
                "/trackers/flow/velocity/filtered_x", "/trackers/flow/kalman/state/x/velocity",
                "/trackers/flow/kalman/sigma/y/position", "/trackers/flow/kalman/position", "/tracks/1"}
    assert expected <= paths


def test_without_rrd_no_rerun_object_is_built(short_sim: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import rerun as rr

    def forbidden(*args, **kwargs):
        raise AssertionError("a Rerun object was built without --rrd")

    entry = registry.get("flow")
    for name in ("RecordingStream", "Boxes2D", "Arrows2D", "Image", "SegmentationImage", "BarChart", "Scalars", "EncodedImage"):
        monkeypatch.setattr(rr, name, forbidden)
    monkeypatch.setattr(entry.view, "log", forbidden)
    monkeypatch.setattr(registry, "get", lambda name: entry)
    assert replay(ReplayRequest(log=short_sim, tracker="flow")).frames == 12


def test_rerun_rrd_compare_passes_for_two_replays_of_the_same_log_without_unordered(tmp_path: Path) -> None:
    """Two replays' chunks come out in the same order (see rerun_sink.canonical_chunks)."""
    import os
    import shutil
    import subprocess
    import sys

    rerun_cli = Path(sys.executable).parent / "rerun"
    if not rerun_cli.exists():
        rerun_cli = Path(shutil.which("rerun") or "rerun")
    golden = Path(__file__).resolve().parents[2] / "golden" / "flow-sim1-24f.mcap"
    paths = [tmp_path / "a.rrd", tmp_path / "b.rrd"]
    for path in paths:
        replay(ReplayRequest(log=golden, tracker="flow", rrd=path))
    env = {**os.environ, **{k: str(tmp_path / "xdg") for k in ("XDG_CONFIG_HOME", "XDG_DATA_HOME", "XDG_CACHE_HOME")}}
    subprocess.run([str(rerun_cli), "analytics", "disable"], env=env, capture_output=True, check=True, timeout=60)
    done = subprocess.run([str(rerun_cli), "rrd", "compare", *map(str, paths)], env=env, capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
