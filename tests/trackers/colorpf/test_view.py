"""The colour-PF Rerun view logs a replay's every intermediate."""

from trackreplay.replay.core.engine import ReplayRequest, replay


def test_view_writes_an_rrd(scene_log, tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path))
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path))
    rrd = tmp_path / "c.rrd"
    replay(ReplayRequest(log=scene_log("colorpf-approach"), tracker="colorpf", seed=0, rrd=rrd))
    assert rrd.stat().st_size > 50_000
