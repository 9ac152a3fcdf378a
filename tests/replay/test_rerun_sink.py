from pathlib import Path

import pytest
import rerun.chunk as rc

from trackreplay.replay import registry
from trackreplay.replay.engine import ReplayRequest, replay


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
                "/trackers/flow/kalman/sigma/y/position", "/trackers/flow/estimate"}
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
