"""The golf view logs every intermediate without errors, in PTZ and image mode."""

import numpy as np

from trackreplay.replay.views.rerun_sink import RerunSink
from trackreplay.replay.views import golf as view
from trackreplay.trackers.golf import GolfConfig, GolfTracker
from trackreplay.trackers.golf.config import EkfConfig, ReinitConfig

BIG = 0.4  # m, the ball of the PTZ sequence (see conftest)


def test_view_logs_a_replay(tmp_path, image_sequence, ptz_sequence, monkeypatch):
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path))
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path))
    _, _, _, ptz_frames = ptz_sequence(n=80)
    _, image_frames = image_sequence(n=12)
    for name, frames, cfg in (("ptz", ptz_frames, GolfConfig(ball_diameter_m=BIG, ekf=EkfConfig(drag_k=0.0), reinit=ReinitConfig(after_landing_frames=0))), ("image", image_frames, GolfConfig())):
        path = tmp_path / f"{name}.rrd"
        sink = RerunSink(path, name, view.blueprint("golf"))
        tracker = GolfTracker(cfg, np.random.default_rng(0))
        seen = set()
        for f in frames:
            sink.begin_frame(f)
            states = tracker.step(f)
            view.log(sink.logger, "golf", f, tracker.intermediates, states)
            seen.add(tracker.intermediates.reinit.kind)
        sink.close()
        assert path.stat().st_size > 10_000
        if name == "ptz":
            assert "ekf_landing" in seen
