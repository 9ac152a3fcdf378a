"""The layout (template) cue (colorpf.template; opt-in, ``likelihood.template``)."""

import numpy as np
import pytest

from trackreplay.replay.core.engine import ReplayRequest, replay
from trackreplay.trackers.colorpf.config import LikelihoodConfig
from trackreplay.trackers.appearance.color import to_grey
from trackreplay.trackers.colorpf.template import TemplateModel, epanechnikov, template_scores


def _texture(seed: int = 0, shape=(120, 160)) -> np.ndarray:
    """A smooth random grey texture (uint8, 3 channels alike): every patch differs from its shifts."""
    rng = np.random.default_rng(seed)
    small = rng.uniform(0, 255, (shape[0] // 4, shape[1] // 4)).astype(np.float32)
    import cv2

    g = cv2.resize(small, shape[::-1], interpolation=cv2.INTER_CUBIC)
    return np.repeat(np.clip(g, 0, 255).astype(np.uint8)[:, :, None], 3, axis=2)


def _centre(x0: int, y0: int, w: int, h: int) -> tuple[float, float]:
    """The centre of the box covering pixels x0..x0+w-1, y0..y0+h-1 (pixel i covers [i-0.5, i+0.5))."""
    return x0 - 0.5 + w / 2, y0 - 0.5 + h / 2


@pytest.mark.parametrize("max_side, least", [(64, 0.97), (12, 0.85)])  # full resolution; scaled to 0.4
def test_ncc_is_one_where_the_template_was_cut_and_lower_elsewhere(max_side, least):
    """(Scaled, the window's samples fall between the template's: ~0.9 rather than ~1.)"""
    image = _texture()
    x0, y0, w, h = 70, 40, 20, 30
    template = to_grey(image[y0:y0 + h, x0:x0 + w], "mean")
    cx, cy = _centre(x0, y0, w, h)
    xy = np.array([[cx, cy], [cx + 6, cy], [cx, cy - 8], [cx - 30, cy + 20]])
    s = template_scores(image, template, xy, np.array([w, h], float), max_side)
    assert s[0] > least, s
    assert (s[1:] < s[0] - 0.15).all(), s
    assert (np.abs(s) <= 1.0).all()


def test_ncc_ignores_a_uniform_gain_and_offset():
    image = _texture(1)
    x0, y0, w, h = 30, 50, 16, 24
    template = to_grey(image[y0:y0 + h, x0:x0 + w], "mean")
    darker = (image.astype(np.float32) * 0.5 + 20).astype(np.uint8)
    s = template_scores(darker, template, np.array([_centre(x0, y0, w, h)]), np.array([w, h], float), 64)
    assert s[0] > 0.97, s


def test_a_box_outside_the_image_scores_zero():
    image = _texture(2)
    template = to_grey(image[10:40, 10:30], "mean")
    size = np.array([20.0, 30.0])
    xy = np.array([[-30.0, 60.0], [155.0, 60.0], [80.0, 110.0], [80.0, 5.0]])  # past each edge (in part)
    assert np.array_equal(template_scores(image, template, xy, size, 64), np.zeros(4))
    # none inside at all: zeros without a match
    assert np.array_equal(template_scores(image, template, xy[:2], size, 64), np.zeros(2))
    # a box larger than the image
    assert np.array_equal(template_scores(image, template, np.array([[80.0, 60.0]]), np.array([400.0, 300.0])),
                          np.zeros(1))


def test_mask_weights():
    k = epanechnikov(9, 15)
    assert k.shape == (15, 9)
    assert k[7, 4] == k.max() and k[7, 4] > 0.9  # 1 at the centre
    assert k[0, 0] == 0.0 and k[-1, -1] == 0.0  # 0 in the corners
    assert np.allclose(k, k[::-1, ::-1])  # symmetric

    image = _texture(3)
    corners = np.array([40, 30, 60, 70])  # x0, y0, x1, y1: 20 x 40
    assert TemplateModel(image, corners, "none").weights is None
    kern = TemplateModel(image, corners, "kernel")
    assert kern.template.shape == (40, 20) and np.array_equal(kern.weights, epanechnikov(20, 40))
    fg = np.zeros((40, 20), bool)
    fg[5:35, 5:15] = True
    kern.set_foreground(fg)  # only "foreground" takes the mask
    assert np.array_equal(kern.weights, epanechnikov(20, 40))
    model = TemplateModel(image, corners, "foreground")
    assert model.weights is None  # the whole box until there is a foreground
    model.set_foreground(np.zeros((40, 20), bool))  # an empty mask is ignored
    assert model.weights is None
    model.set_foreground(fg)
    assert np.array_equal(model.weights, fg.astype(np.float32))


def test_foreground_weights_ignore_the_box_background():
    """The same figure on a different floor: with its foreground as weights it matches ~1, without
    (the whole box) the changed floor pulls the match down."""
    rng = np.random.default_rng(4)
    figure = rng.uniform(0, 255, (30, 10)).astype(np.float32)
    marked = np.full((100, 100), 100, np.float32)
    marked[35:65, 45:55] = figure
    later = _texture(5, (100, 100))[:, :, 0].astype(np.float32)  # a textured floor
    later[35:65, 45:55] = figure
    corners = np.array([40, 30, 60, 70])  # the figure and 5 px of floor round it
    fg = np.zeros((40, 20), bool)
    fg[5:35, 5:15] = True
    xy, size = np.array([[49.5, 49.5]]), np.array([20.0, 40.0])
    whole = TemplateModel(marked, corners, "none")
    masked = TemplateModel(marked, corners, "foreground")
    masked.set_foreground(fg)
    s_whole = template_scores(later, whole.template, xy, size, 64, whole.weights)[0]
    s_masked = template_scores(later, masked.template, xy, size, 64, masked.weights)[0]
    assert s_masked > 0.97 and s_masked > s_whole + 0.1, (s_masked, s_whole)


def test_blend_moves_the_template_towards_the_box_and_skips_boxes_leaving_the_image():
    image = _texture(6)
    model = TemplateModel(image, np.array([40, 30, 60, 70]), "none")
    before = model.template.copy()
    other = to_grey(image[50:90, 100:120], "mean")
    model.blend(image, np.array([109.5, 69.5, 20.0, 40.0]), 0.25)
    assert np.allclose(model.template, 0.75 * before + 0.25 * other, atol=1e-3)
    kept = model.template.copy()
    model.blend(image, np.array([5.0, 69.5, 20.0, 40.0]), 0.25)  # leaves the image on the left
    assert np.array_equal(model.template, kept)


def test_config_checks():
    assert LikelihoodConfig().template == 0.0  # off by default: the paper's likelihood
    for bad in ({"template": -1.0}, {"template_side": 2}, {"template_rate": 1.5}, {"template_mask": "box"}):
        with pytest.raises(ValueError):
            LikelihoodConfig(**bad)


def test_tracker_runs_with_the_cue_and_is_unchanged_with_weight_zero(scene_log):
    log = scene_log("colorpf-background")
    base = replay(ReplayRequest(log=log, tracker="colorpf", seed=0)).trajectory
    off = replay(ReplayRequest(log=log, tracker="colorpf", seed=0,
                               config={"likelihood": {"template": 0.0, "template_mask": "kernel"}})).trajectory
    assert base.equals(off)
    on = replay(ReplayRequest(log=log, tracker="colorpf", seed=0,
                              config={"likelihood": {"template": 2.0, "template_mask": "kernel",
                                                     "template_rate": 0.05}})).trajectory
    assert on.height == base.height and not on.equals(base)
    assert on["x"].is_not_null().sum() > 0.8 * on.height
