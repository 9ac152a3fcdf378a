"""A grey picture (issue 31): the H-S histogram is undefined there (one bin for every pixel), Pérez et
al.'s brightness histogram cannot tell a target from a background of the same grey levels, and the
grey-level and gradient-direction histogram (``likelihood.histogram = "gradient"``, chosen by the grey
test) can, by the direction of its edges."""

from __future__ import annotations

import numpy as np
import pytest

from trackreplay.schemas.records import InitRegion
from trackreplay.trackers.appearance.gradient import edge_threshold, grey_gradient_index
from trackreplay.trackers.colorpf.config import PAPER, ColorPfConfig, LikelihoodConfig
from trackreplay.trackers.colorpf.likelihood import ColourModel, box_histogram
from trackreplay.trackers.colorpf.tracker import ColorPfTracker
from trackreplay.trackers.frame import Frame
from trackreplay.replay.core.config import config_from_dict

FRAMES, SIDE = 50, 16


def _striped(vertical: bool) -> np.ndarray:
    """A SIDE x SIDE square of 4 px stripes, grey levels 40 and 190 (the same levels either way)."""
    stripes = np.where((np.arange(SIDE) // 4) % 2 == 0, 40, 190).astype(np.uint8)
    return np.tile(stripes[None, :], (SIDE, 1)) if vertical else np.tile(stripes[:, None], (1, SIDE))


def _scene() -> list[np.ndarray]:
    """Single-channel frames: a horizontally striped target moving right 1 px a frame over a fence of
    vertical stripes of the same two grey levels (every box of the picture has the target's levels)."""
    rng = np.random.default_rng(0)
    fence = np.where((np.arange(160) // 4) % 2 == 0, 40, 190)[None, :].repeat(90, axis=0)
    images = []
    for i in range(FRAMES):
        image = fence.copy()
        image[44:44 + SIDE, 30 + i:30 + i + SIDE] = _striped(vertical=False)
        images.append(np.clip(image + rng.normal(0, 2, image.shape), 0, 255).astype(np.uint8))
    return images


def _track(config: ColorPfConfig) -> tuple[ColorPfTracker, list[float]]:
    """The track's centre error (px) per frame; inf when it has no position."""
    mark = InitRegion(0, 0, 30 + SIDE / 2 - 0.5, 44 + SIDE / 2 - 0.5, SIDE, SIDE, "target")
    tracker = ColorPfTracker(config, np.random.default_rng(0))
    errors = []
    for i, image in enumerate(_scene()):
        row = tracker.step(Frame(index=i, t_ns=i * 33_333_333, image=image, all_hints=(mark,),
                                 hints=(mark,) if i == 0 else ()))[0]
        truth = np.array([30 + i + SIDE / 2 - 0.5, 44 + SIDE / 2 - 0.5])
        errors.append(np.inf if row.x is None else float(np.hypot(row.x - truth[0], row.y - truth[1])))
    return tracker, errors


def test_hs_is_flat_on_grey_and_brightness_cannot_tell_the_fence_but_gradients_can():
    image = _scene()[0]
    target = np.array([37.5, 51.5, SIDE, SIDE])
    scores = {}
    for name in ("hs", "hsv", "gradient"):
        model = ColourModel(LikelihoodConfig(histogram=name, max_pixels=None), edge_threshold(image, 0.5))
        reference = box_histogram(model, image, target)
        scores[name] = [float(np.minimum(box_histogram(model, image, box), reference).sum())
                        for box in (target, np.array([87.5, 25.5, SIDE, SIDE]), np.array([120.0, 70.0, SIDE, SIDE]))]
    assert scores["hs"] == [1.0, 1.0, 1.0]  # every grey pixel is one H-S bin: every box matches fully
    assert min(scores["hsv"][1:]) > 0.95  # the fence has the target's grey levels wherever the box is
    assert max(scores["gradient"][1:]) < 0.6  # its edges point the other way


def test_the_gradient_index_reads_directions_and_crops_like_the_frame():
    image = _scene()[0]
    index, n = grey_gradient_index(image, 10, 8, 100.0)
    assert n == 18
    horizontal_edges = index[44:60, 31:45][np.isin(np.arange(44, 60), [47, 48, 51, 52, 55, 56])]
    assert set(np.unique(horizontal_edges)) == {10 + 2, 10 + 6}  # gradients down (90°) and up (270°)
    fence = index[5:40, 10:150]
    assert set(np.unique(fence[:, np.isin(np.arange(10, 150) % 4, [0, 3])])) == {10 + 0, 10 + 4}  # 0° and 180°
    assert set(np.unique(fence[:, np.isin(np.arange(10, 150) % 4, [1, 2])])) <= {40 * 10 // 256, 190 * 10 // 256}
    model = ColourModel(LikelihoodConfig(histogram="gradient"), 100.0)
    assert np.array_equal(model.crop_index(image, 40, 40, 70, 65), index[40:65, 40:70])  # no border effect


def test_a_grey_log_is_followed_on_gradients_where_brightness_stays_behind():
    tracker, errors = _track(ColorPfConfig(likelihood=LikelihoodConfig(grey="gradient")))
    assert tracker.model.config.histogram == "gradient"
    assert max(errors) < 8.0  # followed over the fence for 50 px
    _, brightness = _track(ColorPfConfig(likelihood=LikelihoodConfig(grey="hsv", grey_template=0.0)))
    assert brightness[-1] > 30.0  # Pérez et al.'s V histogram: every box scores alike, the cloud stays behind
    _, laid_out = _track(ColorPfConfig(likelihood=LikelihoodConfig(grey="hsv")))
    assert max(laid_out) < 8.0  # the layout cue (grey_template, on by default) carries even the V histogram


def test_paper_keeps_the_brightness_fallback():
    tracker = ColorPfTracker(config_from_dict(ColorPfConfig, PAPER), np.random.default_rng(0))
    mark = InitRegion(0, 0, 37.5, 51.5, SIDE, SIDE, "target")
    tracker.step(Frame(index=0, t_ns=0, image=_scene()[0], all_hints=(mark,), hints=(mark,)))
    assert tracker.model.config.histogram == "hsv"



def _started(config: ColorPfConfig) -> tuple[ColorPfTracker, np.ndarray]:
    """The tracker after the grey scene's marked frame, and that frame."""
    tracker = ColorPfTracker(config, np.random.default_rng(0))
    image = _scene()[0]
    mark = InitRegion(0, 0, 37.5, 51.5, SIDE, SIDE, "target")
    tracker.step(Frame(index=0, t_ns=0, image=image, all_hints=(mark,), hints=(mark,)))
    return tracker, image


def test_a_grey_picture_turns_the_layout_cue_on_and_paper_does_not():
    tracker, _ = _started(ColorPfConfig())
    lik = tracker.config.likelihood
    assert (lik.histogram, lik.template, lik.template_mask) == ("gradient", 4.0, "kernel")
    assert tracker.template is not None and tracker.template.template is not None
    assert "layout cue is on" in tracker.intermediates.notice
    explicit, _ = _started(ColorPfConfig(likelihood=LikelihoodConfig(template=2.0)))
    assert explicit.config.likelihood.template == 2.0  # a weight the config sets is kept
    off, _ = _started(ColorPfConfig(likelihood=LikelihoodConfig(grey_template=0.0)))
    assert off.config.likelihood.template == 0.0 and off.template is None
    paper, _ = _started(config_from_dict(ColorPfConfig, PAPER))
    assert paper.config.likelihood.template == 0.0 and not paper.config.likelihood.layout_vouches


def test_a_colour_match_vouches_only_where_the_layout_agrees():
    """``likelihood.layout_vouches``: NCC > 0 with the target's template, else the row is not "measured"."""
    tracker, image = _started(ColorPfConfig())
    flat = image.copy()
    flat[20:80, 60:160] = 120  # a patch of one grey level: no layout (NCC 0)
    assert tracker._layout_agrees(image, np.array([37.5, 51.5, SIDE, SIDE]))  # on the target
    assert not tracker._layout_agrees(flat, np.array([110.0, 50.0, SIDE, SIDE]))
    assert not tracker._layout_agrees(image, np.array([4.0, 51.5, SIDE, SIDE]))  # not wholly in the picture
    inverted = image.copy()  # the target's stripes a half period off: its histogram, the opposite layout
    inverted[44:44 + SIDE, 30:30 + SIDE] = 230 - image[44:44 + SIDE, 30:30 + SIDE]
    assert not tracker._layout_agrees(inverted, np.array([37.5, 51.5, SIDE, SIDE]))
    colour, _ = _started(ColorPfConfig(likelihood=LikelihoodConfig(grey_template=0.0)))
    assert colour._layout_agrees(flat, np.array([110.0, 50.0, SIDE, SIDE]))  # no layout cue: the colour decides
