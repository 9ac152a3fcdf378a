import dataclasses

import numpy as np
import pytest

from trackreplay.schemas.records import InitRegion
from trackreplay.trackers.flow.config import FlowConfig
from trackreplay.trackers.flow.tracker import FlowIntermediates, FlowTracker
from trackreplay.trackers.frame import Frame


def _frames(scene, centres: np.ndarray, side: int = 13, bgr: bool = False) -> list[Frame]:
    back = scene.background()
    frames = []
    for t, c in enumerate(centres):
        img = scene.square_frame(back, c, side)
        if bgr:
            img = np.repeat(img[:, :, None], 3, axis=2)
        hints = (InitRegion(0, 0, float(c[0]), float(c[1]), side, side, "target"),) if t == 0 else ()
        frames.append(Frame(t, t * 33_333_333, img, hints=hints))
    return frames


def _run(frames: list[Frame], config: FlowConfig | None = None):
    tracker = FlowTracker(config or FlowConfig(), np.random.default_rng(0))
    outs, inters = [], []
    for f in frames:
        outs.append(tracker.step(f))
        inters.append(tracker.intermediates)
    return outs, inters


@pytest.fixture(scope="module")
def circle_run(scene):
    centres = scene.circle_centres()
    outs, inters = _run(_frames(scene, centres))
    return centres, outs, inters


def test_follows_a_square_on_a_circle(circle_run) -> None:
    """Simulation 1 (§5.1): 13×13 square of brightness 200 on a circle, FOV 51×51, t = 0…50."""
    centres, outs, inters = circle_run
    est = np.array([[o[0].vx, o[0].vy] for o in outs[1:]])
    truth = np.diff(centres, axis=0).astype(float)
    rmse = np.sqrt(np.mean((est - truth) ** 2, axis=0))
    assert np.all(rmse < 0.5), rmse
    pos = np.array([[o[0].x, o[0].y] for o in outs])
    assert np.abs(pos - centres).max() < 3.0
    for t, inter in enumerate(inters):
        x0, y0, w, h = inter.fov_box
        centre = np.array([x0 + (w - 1) / 2, y0 + (h - 1) / 2])
        if t > 0:  # the window used at step t held the target at t-1 and t
            assert np.abs(centres[t] - centre).max() <= (51 - 13) // 2
            assert np.abs(centres[t - 1] - centre).max() <= (51 - 13) // 2
    assert all(o[0].status == "measured" for o in outs)
    sizes = np.array([[o[0].w, o[0].h] for o in outs[1:]])
    assert np.abs(np.median(sizes, axis=0) - 13).max() < 3.0


def test_first_frame_and_intermediate_shapes(circle_run) -> None:
    centres, outs, inters = circle_run
    first = outs[0][0]
    assert (first.x, first.y, first.w, first.h, first.vx, first.vy) == (centres[0][0], centres[0][1], 13, 13, None, None)
    assert first.status == "measured" and first.track_id == 1
    for inter in (inters[0], inters[10]):
        assert inter.fov_box.shape == (4,) and inter.fov_box.dtype == np.float64
        for name in ("flow_u", "flow_v", "cond"):
            assert getattr(inter, name).shape == (51, 51) and getattr(inter, name).dtype == np.float32
        assert inter.valid.dtype == bool and inter.moving.shape == (51, 51)
        assert inter.hist_u.dtype == np.int64 and len(inter.hist_edges) == len(inter.hist_u) + 1
        assert inter.kalman_x.shape == (2, 3) and inter.kalman_P.shape == (2, 3, 3)
        assert inter.raw_velocity.shape == inter.filtered_velocity.shape == inter.centroid.shape == (2,)
    assert np.isnan(inters[0].raw_velocity).all() and inters[0].moving_pixels == 0
    assert inters[10].moving_pixels > 0 and np.isfinite(inters[10].raw_velocity).all()


def test_same_inputs_give_identical_intermediates(scene) -> None:
    frames = _frames(scene, scene.circle_centres(20))
    (outs_a, inter_a), (outs_b, inter_b) = _run(frames), _run(frames)
    assert outs_a == outs_b
    for a, b in zip(inter_a, inter_b):
        for field in dataclasses.fields(FlowIntermediates):
            x, y = getattr(a, field.name), getattr(b, field.name)
            if isinstance(x, np.ndarray):
                assert x.dtype == y.dtype and x.tobytes() == y.tobytes(), field.name
            else:
                assert x == y or (np.isnan(x) and np.isnan(y)), field.name


def test_bgr_frames_track_like_grey(scene) -> None:
    centres = scene.circle_centres(8)
    grey, _ = _run(_frames(scene, centres))
    bgr, _ = _run(_frames(scene, centres, bgr=True))
    assert grey == bgr


def test_offline_refinement_tracks_too(scene) -> None:
    centres = scene.circle_centres(20)
    outs, _ = _run(_frames(scene, centres), FlowConfig(online=False))
    pos = np.array([[o[0].x, o[0].y] for o in outs])
    assert np.abs(pos - centres).max() < 3.0


def test_start_without_a_hint(scene) -> None:
    still = Frame(0, 0, scene.background())
    tracker = FlowTracker(FlowConfig(init_center=(100.0, 90.0)), np.random.default_rng(0))
    first = tracker.step(still)[0]
    assert (first.x, first.y, first.w) == (100.0, 90.0, None)
    assert tracker.intermediates.fov_box.tolist() == [75.0, 65.0, 51.0, 51.0]
    tracker = FlowTracker(FlowConfig(), np.random.default_rng(0))
    first = tracker.step(still)[0]
    assert (first.x, first.y) == (127.5, 127.5)
    assert first.status == "predicted"  # where the search starts, not a sighting


def test_only_a_mark_makes_the_first_row_measured(scene) -> None:
    mark = InitRegion(0, 0, 100.0, 90.0, 11.0, 11.0, "target")
    tracker = FlowTracker(FlowConfig(init_center=(60.0, 60.0)), np.random.default_rng(0))
    first = tracker.step(Frame(0, 0, scene.background(), hints=(mark,)))[0]
    assert (first.x, first.y, first.status) == (100.0, 90.0, "measured")


def test_nothing_moving_predicts_then_is_lost(scene) -> None:
    frames = [Frame(t, t, scene.background()) for t in range(8)]
    outs, inters = _run(frames, FlowConfig(lost_after=4, init_center=(128.0, 128.0)))
    statuses = [o[0].status for o in outs]
    assert statuses == ["predicted", "predicted", "predicted", "predicted", "lost", "lost", "lost", "lost"]
    assert all(o[0].x is None and o[0].y is None for o in outs[4:])  # lost rows carry no position
    assert all(i.moving_pixels == 0 for i in inters)


def test_target_leaving_the_image_is_lost(scene) -> None:
    centres = np.array([[230 + 3 * t, 128] for t in range(16)])
    outs, _ = _run(_frames(scene, centres))
    statuses = [o[0].status for o in outs]
    assert statuses[-1] == "lost"
    assert "measured" in statuses[1:5]
