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


def test_view_plots_the_reported_confidence_beside_the_validation_s(image_sequence, monkeypatch):
    """The confidence a row reports (P(within 10 px)) is a time series next to the validation's own."""
    _, frames = image_sequence(n=12)
    plotted: dict[str, list[float]] = {}
    monkeypatch.setattr(view.parts, "scalar", lambda rec, path, value: plotted.setdefault(path, []).append(float(value)))
    monkeypatch.setattr(view.parts, "draw", lambda *a, **k: None)
    tracker = GolfTracker(GolfConfig(), np.random.default_rng(0))
    reported = []
    for f in frames:
        states = tracker.step(f)
        view.log(_NoLogger(), "golf", f, tracker.intermediates, states)
        reported += [s.confidence for s in states if s.status != "lost"]
    assert reported and plotted["trackers/golf/validation/reported"] == reported
    assert len(plotted["trackers/golf/validation/confidence"]) >= len(reported)


class _NoLogger:
    """Takes whatever the view logs besides scalars (boxes, images, particles) and drops it."""

    def __getattr__(self, name):
        return lambda *a, **k: None
