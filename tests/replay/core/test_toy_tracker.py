"""One declared tracker contract: a tracker defined here, in the test, with its config, its spec and a
tiny Rerun view, is registered and then replayed, smoothed, exported and drawn to an .rrd, with no
edit to ``replay/`` for it: everything the replay side knows of it is its :class:`TrackerSpec`."""

from __future__ import annotations

from dataclasses import dataclass
from operator import attrgetter
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import polars as pl
import pytest
import rerun as rr
import rerun.blueprint as rrb

from trackreplay.replay.analysis.smooth import smooth_trajectory, smoothing_model
from trackreplay.replay.cli.main import main
from trackreplay.replay.core import registry
from trackreplay.replay.core.engine import ReplayRequest, replay
from trackreplay.replay.core.export import read_trajectory, write_trajectory
from trackreplay.schemas.errors import TrackreplayError
from trackreplay.trackers.base import TrackerBase, TrackerSpec, TrackState
from trackreplay.trackers.frame import Frame
from trackreplay.trackers.smoothing import ImageSmoothing

HALFWAY = 6  # the toy's notice from this frame on


@dataclass(frozen=True)
class ToyConfig:
    gain: float = 0.5  # weight of the new centroid in the toy's own (exponential) filter


@dataclass(frozen=True, eq=False)
class ToyIntermediates:
    centroid: np.ndarray  # (2,) the brightness-weighted centroid: the toy's raw measurement, px
    notice: str = ""


class ToyTracker(TrackerBase):
    """Follows the brightness-weighted centroid of the picture through an exponential filter."""

    name = "toy"

    def __init__(self, config: ToyConfig, rng: np.random.Generator) -> None:
        self.config = config
        self.position: np.ndarray | None = None

    def step(self, frame: Frame) -> list[TrackState]:
        grey = frame.image.astype(np.float64)
        if grey.ndim == 3:
            grey = grey.mean(axis=2)
        ys, xs = np.indices(grey.shape)
        c = np.array([(xs * grey).sum(), (ys * grey).sum()]) / grey.sum()
        g = self.config.gain
        self.position = c if self.position is None else (1.0 - g) * self.position + g * c
        self.intermediates = ToyIntermediates(c, "past half-way" if frame.index >= HALFWAY else "")
        x, y = (float(v) for v in self.position)
        return [TrackState(1, x=x, y=y, w=4.0, h=4.0, status="measured", confidence=1.0)]


def _raw_centroid(inter: ToyIntermediates, states, rig, config) -> list[dict]:
    return [{"track_id": 1, "zx": float(inter.centroid[0]), "zy": float(inter.centroid[1])}]


def _blueprint(name: str) -> rrb.Blueprint:
    return rrb.Blueprint(rrb.Spatial2DView(name="toy", origin="/"), collapse_panels=False)


def _log(rec, name: str, frame: Frame, inter: ToyIntermediates, states) -> None:
    rec.log(f"trackers/{name}/centroid", rr.Points2D([inter.centroid], radii=2.0))


SMOOTHING = ImageSmoothing("toy: image constant velocity")
VIEW = SimpleNamespace(blueprint=_blueprint, log=_log)  # a view object (no module of replay/views)
SPEC = TrackerSpec("toy", ToyConfig, ToyTracker, VIEW, mark_labels=("target",), position_frame=lambda tracker: None,
                   observations=_raw_centroid, notice=attrgetter("notice"), smoothing=SMOOTHING)


@pytest.fixture
def toy():
    registry.register(SPEC)
    yield SPEC
    registry.unregister(SPEC.name)


def test_a_tracker_declared_in_a_test_replays_smooths_exports_and_draws(toy: TrackerSpec, short_sim: Path,
                                                                        tmp_path: Path) -> None:
    assert "toy" in registry.NAMES and registry.get("toy").view is VIEW
    rrd = tmp_path / "toy.rrd"
    res = replay(ReplayRequest(log=short_sim, tracker="toy", rrd=rrd, observations=True))
    assert res.frames == 12 and res.trajectory.height == 12 and res.trajectory["tracker"].unique().to_list() == ["toy"]
    assert res.notices == ("past half-way",) and res.config == ToyConfig()
    assert replay(ReplayRequest(log=short_sim, tracker="toy")).digest == res.digest
    # the raw measurement the spec declares, one row a frame, differs from the toy's filtered output
    obs = res.observations
    assert obs["tracker"].unique().to_list() == ["toy"] and obs["frame"].to_list() == list(range(12))
    assert not np.allclose(obs["zx"].to_numpy(), res.trajectory["x"].to_numpy())

    assert smoothing_model("toy") is SMOOTHING
    smoothed, fits = smooth_trajectory(res.trajectory, observations=obs, configs={"toy": res.config})
    assert [(f.tracker, f.observations) for f in fits] == [("toy", 12)] and smoothed["fill"].to_list() == ["rts"] * 12
    from_output, _ = smooth_trajectory(res.trajectory)
    assert not smoothed["x"].equals(from_output["x"])  # the smoother observed the raw centroid

    back = read_trajectory(write_trajectory(smoothed, tmp_path / "toy.parquet"))
    assert back.select("tracker", "frame", "x", "y").equals(smoothed.select("tracker", "frame", "x", "y"))

    import rerun.chunk as rc

    paths = {str(chunk.entity_path) for chunk in rc.RrdReader(str(rrd)).stream()}
    assert {"/trackers/toy/centroid", "/camera/image"} <= paths


def test_the_cli_runs_a_registered_tracker(toy: TrackerSpec, short_sim: Path, tmp_path: Path) -> None:
    out, rrd, summary = tmp_path / "s.parquet", tmp_path / "t.rrd", tmp_path / "summary.json"
    assert main(["replay", str(short_sim), "--tracker", "toy", "--smooth", "--export", str(out), "--rrd", str(rrd),
                 "--summary", str(summary), "--quiet"]) == 0
    assert pl.read_parquet(out).height == 12 and rrd.stat().st_size > 0 and summary.exists()


def test_register_refuses_a_taken_name_and_unregister_forgets(short_sim: Path) -> None:
    with pytest.raises(TrackreplayError, match="already registered"):
        registry.register(TrackerSpec("flow", ToyConfig, ToyTracker, VIEW))
    registry.register(SPEC)
    registry.register(SPEC)  # the same spec again: nothing to do
    try:
        assert registry.NAMES.count("toy") == 1
        with pytest.raises(TrackreplayError, match="already registered"):
            registry.register(TrackerSpec("toy", ToyConfig, ToyTracker, VIEW))
    finally:
        registry.unregister("toy")
    assert "toy" not in registry.NAMES and registry.find("toy") is None
    with pytest.raises(TrackreplayError, match="unknown tracker 'toy'"):
        replay(ReplayRequest(log=short_sim, tracker="toy"))


def test_a_spec_says_what_it_needs_in_words() -> None:
    with pytest.raises(ValueError, match="needs must be one of"):
        TrackerSpec("toy", ToyConfig, ToyTracker, VIEW, needs="lidar")
    with pytest.raises(ValueError, match="a word"):
        TrackerSpec("my toy", ToyConfig, ToyTracker, VIEW)


@pytest.mark.parametrize("declared, refusal", [({"needs": "stereo"}, "needs a calibrated stereo pair"),
                                               ({"mark_labels": ("ball",)}, "would be ignored by the toy tracker")])
def test_the_replay_refuses_what_the_spec_says_the_tracker_cannot_start_on(short_sim: Path, declared: dict,
                                                                           refusal: str) -> None:
    """The checks before the first frame read the spec (the sim has no stereo pair and marks a ``target``)."""
    from dataclasses import replace

    registry.register(replace(SPEC, **declared))
    try:
        with pytest.raises(TrackreplayError, match=refusal):
            replay(ReplayRequest(log=short_sim, tracker="toy"))
    finally:
        registry.unregister("toy")
