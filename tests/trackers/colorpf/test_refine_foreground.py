"""The foreground-region refinement (refine.mode = "foreground", colorpf.foreground.foreground_region)."""

import dataclasses
from types import SimpleNamespace

import numpy as np

from trackreplay.replay.core.engine import ReplayRequest, replay
from trackreplay.trackers.colorpf.aspect import AspectEstimate
from trackreplay.trackers.colorpf.config import AspectConfig, ColorPfConfig, RefineConfig
from trackreplay.trackers.colorpf.foreground import IDENTITY, foreground_region, region_layout
from trackreplay.trackers.colorpf.size import WeakPerspectiveSize
from trackreplay.trackers.colorpf.tracker import ColorPfTracker

FIGURE = (105.5, 97.5)  # centre of the figure's pixels, columns 100-111 and rows 80-115 (12 x 36)


def _scene():
    background = np.full((200, 200, 3), 100, np.uint8)
    image = background.copy()
    image[80:116, 100:112] = 20
    return image, background


def _region(image, background, estimate, mark_share=0.6, layout=IDENTITY):
    return foreground_region(image, background, np.asarray(estimate, np.float64), 25.0, 3, 1.0, mark_share, layout)


def test_the_estimate_moves_onto_an_offset_blob():
    image, background = _scene()
    box, why = _region(image, background, [99.5, 92.0, 12.0, 36.0])  # 6 px left of, 5.5 px above the figure
    assert why == "" and box is not None
    assert np.allclose(box[:2], FIGURE, atol=0.01)
    assert np.allclose(box[2:], [12.0, 36.0], atol=0.1)  # a wholly foreground box: the figure's own size


def test_a_blob_merged_with_a_much_larger_region_does_not_move_the_estimate():
    image, background = _scene()
    image[70:120, 112:190] = 30  # a car against the figure's right side: one component
    box, why = _region(image, background, [99.5, 92.0, 12.0, 36.0])
    assert box is None and why


def test_a_blob_beside_a_larger_separate_region_does_not_move_the_estimate():
    image, background = _scene()
    image[80:116, 115:175] = 30  # a car 3 px to the figure's right, a component of its own
    box, why = _region(image, background, [99.5, 92.0, 12.0, 36.0])
    assert box is None and why


def test_a_region_of_another_size_or_share_does_not_move_the_estimate():
    image, background = _scene()
    assert _region(image, background, [99.5, 92.0, 30.0, 90.0])[0] is None  # far smaller than the box
    assert _region(image, background, [99.5, 92.0, 12.0, 36.0], mark_share=0.3)[0] is None  # share 1 vs 0.3


def test_the_layout_places_the_box_as_the_mark_was_on_its_foreground():
    # at the mark only the upper 20 of 36 rows differed from the floor (dark legs on a dark road)
    mask = np.zeros((36, 12), bool)
    mask[:20] = True
    layout = region_layout(mask, np.array([100, 80]), np.array([*FIGURE, 12.0, 36.0]))
    image, background = _scene()
    image[100:116, 100:112] = 100  # now too: only the upper 20 rows are foreground
    box, why = _region(image, background, [99.5, 92.0, 12.0, 36.0], mark_share=20 / 36, layout=layout)
    assert why == "" and np.allclose(box, [*FIGURE, 12.0, 36.0], atol=0.01)
    assert region_layout(np.zeros((5, 5), bool), np.zeros(2), np.array([2.0, 2.0, 5.0, 5.0])) is None


def _tracker(has_plane: bool):
    tracker = ColorPfTracker(ColorPfConfig(n_particles=40), np.random.default_rng(0))  # the cloud set below
    tracker.reference = SimpleNamespace(p_detect=432, p_square=720)  # mark share 0.6
    tracker.layout = IDENTITY
    tracker.size = WeakPerspectiveSize(0.2, 432.0, 10.0 if has_plane else float("nan"))
    tracker.aspect = AspectEstimate(AspectConfig(), 3.0)
    rng = np.random.default_rng(1)
    tracker.pf.particles = np.column_stack([rng.normal(99.5, 2.0, 40), rng.normal(92.0, 2.0, 40),
                                            np.full(40, 12.0), np.full(40, 36.0)])
    return tracker


def test_the_cloud_moves_with_the_estimate_and_the_size_follows_only_without_a_plane():
    image, background = _scene()
    for has_plane in (True, False):
        tracker = _tracker(has_plane)
        before = tracker.pf.particles.copy()
        estimate = tracker.pf.estimate()
        refined, placed = tracker._refine_foreground(image, background, 1.0, estimate)
        assert placed and np.allclose(refined[:2], FIGURE, atol=0.01)
        assert np.allclose(tracker.pf.particles[:, :2] - before[:, :2], refined[:2] - estimate[:2])
        assert np.allclose(refined[2:], [12.0, 36.0], atol=0.1)  # the figure's size is the box's here
    tracker = _tracker(False)
    image[80:116, 100:112] = 100
    image[86:116, 101:111] = 20  # a figure of 10 x 30: without a plane the box moves 20 % towards it
    refined, placed = tracker._refine_foreground(image, background, 1.0, tracker.pf.estimate())
    assert placed and np.allclose(refined[2:], [0.8 * 12 + 0.2 * 10, 0.8 * 36 + 0.2 * 30], atol=0.1)
    assert np.isclose(tracker.size.area0, refined[2] * refined[3]) and np.isclose(tracker.aspect.ratio,
                                                                                  refined[3] / refined[2])


def test_without_a_plane_the_region_moves_the_area_state_and_the_aspect_stays():
    """refine.size_follows = "area": the region sets S' (smoothed from S' itself, not from the PF's
    weighted-mean box, which carries that frame's colour-weighted omega) and eq. (12) the box with the
    aspect stage's R. otb_crossing: the head against the sunlit crossing and the legs over its stripes
    became foreground from frame ~50, and the region's box grew taller than the walker."""
    image, background = _scene()
    image[74:122, 100:112] = 20  # the region is taller (12 x 48): a part that did not differ from the floor now does
    tracker = _tracker(False)  # S' = 432, R = 3 (12 x 36)
    tracker.pf.particles[:, 2:4] = [14.0, 42.0]  # the colour's weighted mean is another box than the state
    estimate = tracker.pf.estimate()
    region, why = _region(image, background, estimate)
    assert why == "" and region[3] / region[2] > 3.5
    refined, placed = tracker._refine_foreground(image, background, 1.0, estimate)
    area = 0.8 * 432.0 + 0.2 * region[2] * region[3]
    assert placed and np.isclose(tracker.size.area0, area)
    assert tracker.aspect.ratio == 3.0  # R stays the aspect stage's (aspect.mode "fixed": the mark's)
    assert np.allclose(refined[2:], [np.sqrt(area / 3.0), 3.0 * np.sqrt(area / 3.0)])
    # "box" (the previous behaviour): w and h each from the estimate's box, the aspect with them
    tracker = _tracker(False)
    tracker.config = dataclasses.replace(tracker.config, refine=RefineConfig(size_follows="box"))
    tracker.pf.particles[:, 2:4] = [14.0, 42.0]
    refined, placed = tracker._refine_foreground(image, background, 1.0, tracker.pf.estimate())
    assert placed and np.allclose(refined[2:], 0.8 * np.array([14.0, 42.0]) + 0.2 * region[2:4])
    assert np.isclose(tracker.aspect.ratio, refined[3] / refined[2])


def test_without_a_background_nothing_moves(scene_log):
    log = scene_log("colorpf-illumination")
    runs = [replay(ReplayRequest(log=log, tracker="colorpf", seed=0,
                                 config={"reference": {"background": "none"}, "refine": {"mode": mode}}))
            for mode in ("none", "foreground")]
    assert runs[0].digest == runs[1].digest


def test_a_region_keeps_no_lost_track_on_another_walker():
    # The target walks out of the picture past a second walker standing at the exit. Colour loses
    # the target; the foreground cue then pulls the cloud onto the other walker, where a region of
    # the target's size would place the box and keep the track "predicted" for as long as they stay.
    # A region keeps a track only for refine.keep_frames frames since the last measured one and
    # never re-acquires a lost one: the track goes lost and stays lost.
    from trackreplay.recorder.synth.colorpf import (OTHER_COLOURS, TARGET_COLOURS, Camera, ColorPfSceneConfig,
                                                    draw_walker, render_background)
    from trackreplay.schemas.records import InitRegion
    from trackreplay.trackers.frame import Frame

    scene = ColorPfSceneConfig(width=480, height=320, seed=0)
    cam, rng = Camera.of(scene), np.random.default_rng(0)
    background = render_background(scene, cam, rng)
    empty, walk, frames_n = 8, 110, 200
    images, target_boxes = [], []
    for i in range(frames_n):
        image, box = background.copy(), None
        k = i - empty
        if k >= 0:
            draw_walker(image, cam, np.array([-5.0, 11.8]), np.array([0.0, -1.0]), 0.0, OTHER_COLOURS)
            if k <= walk:
                t = k / walk
                box = draw_walker(image, cam, np.array([-9.0 * t, 11.0]), np.array([-1.0, 0.0]), k / 30, TARGET_COLOURS)
        noisy = image + rng.standard_normal(image.shape).astype(np.float32) * 2.0
        images.append(np.clip(np.round(noisy), 0, 255).astype(np.uint8))
        target_boxes.append(box)
    x0, y0, x1, y1 = target_boxes[empty]
    mark = InitRegion(empty, 0, (x0 + x1 - 1) / 2, (y0 + y1 - 1) / 2, x1 - x0, y1 - y0, "target")
    cfg = ColorPfConfig()
    tracker = ColorPfTracker(cfg, np.random.default_rng(0))
    statuses = {}
    for i, image in enumerate(images):
        states = tracker.step(Frame(index=i, t_ns=i * 33_333_333, image=image, all_hints=(mark,),
                                    hints=(mark,) if i == empty else ()))
        if states:
            statuses[i] = states[0].status
    gone = next(i for i in range(empty, frames_n) if target_boxes[i] is None)
    after = [statuses[i] for i in range(gone, frames_n)]
    # refine.keep_frames is None by default (no bound); measured: the track is lost within lost_after + 30
    # frames either way (the region does not keep it on the other walker here)
    bound = cfg.lost_after + (cfg.refine.keep_frames or 30)
    assert "lost" in after[:bound + 1]
    first = after.index("lost")
    assert set(after[first:]) == {"lost"}, after  # lost, and not taken back onto the other walker


def test_the_region_grows_the_box_by_at_most_max_growth_per_side():
    """Issue 31 (refine.max_growth): on otb_car4 a region of moving road grew the placed box 2.6x per side."""
    import dataclasses

    import pytest

    image, background = _scene()
    image[74:122, 100:112] = 20  # the region is 12 x 48: its area 1.33x the box's
    areas = {}
    for growth in (None, 1.1):
        tracker = _tracker(False)  # S' = 432 (12 x 36), the last measured box's area too
        tracker.config = dataclasses.replace(tracker.config, refine=dataclasses.replace(
            tracker.config.refine, max_growth=growth, size_rate=1.0))
        tracker._vouched_area = 12.0 * 36.0
        _, placed = tracker._refine_foreground(image, background, 1.0, tracker.pf.estimate())
        assert placed
        areas[growth] = tracker.size.area0
    assert areas[None] > 1.3 * 432.0 and areas[1.1] == pytest.approx(1.1 ** 2 * 432.0)
