"""The foreground cue and the neighbour check (colorpf.foreground)."""

import numpy as np

from trackreplay.trackers.colorpf.foreground import brightness_gain, foreground_contrast, neighbour_shares


def _scene(gain: float = 1.0):
    """A grey floor (100) with a dark 10x30 figure at x 45-55, y 35-65, the image scaled by gain."""
    background = np.full((100, 100, 3), 100, np.uint8)
    image = background.copy()
    image[35:65, 45:55] = 20
    return np.clip(image.astype(np.float32) * gain, 0, 255).astype(np.uint8), background


def test_contrast_peaks_on_the_figure_and_ignores_a_uniform_gain():
    for gain in (1.0, 0.4):  # a uniform illumination step is not foreground
        image, background = _scene(gain)
        xy = np.array([[50.0, 50.0], [62.0, 50.0], [50.0, 80.0]])  # on it, beside it, below it
        gain = brightness_gain(image, background)
        c = foreground_contrast(image, background, xy, np.array([12.0, 32.0]), 25.0, 3, gain)
        assert c[0] > 0.5 and c[0] > c[1] + 0.3 and c[0] > c[2] + 0.3, (gain, c)


def test_contrast_is_flat_inside_a_large_moving_region():
    background = np.full((100, 100, 3), 100, np.uint8)
    image = background.copy()
    image[10:90, 10:90] = 20  # a region much larger than the boxes
    c = foreground_contrast(image, background, np.array([[40.0, 50.0], [60.0, 50.0]]), np.array([10.0, 20.0]), 25.0, 3)
    assert np.allclose(c, 0.0)


def test_neighbour_shares_see_a_larger_region_beside_the_box():
    image, background = _scene()
    alone = neighbour_shares(image, background, np.array([50.0, 50.0, 12.0, 32.0]), 25.0, 3)
    assert alone.max() < 0.1
    image[35:65, 55:90] = 30  # a car against the figure's right side
    touched = neighbour_shares(image, background, np.array([50.0, 50.0, 12.0, 32.0]), 25.0, 3)
    assert touched[1] > 0.9 and touched[0] < 0.1


def test_a_changed_scene_is_noticed_and_a_brightness_step_is_not():
    from trackreplay.trackers.colorpf.foreground import scene_changed

    image, background = _scene(0.4)
    assert abs(brightness_gain(image, background) - 0.4) < 0.01
    assert not scene_changed(image, background, 25.0, brightness_gain(image, background))
    rng = np.random.default_rng(0)
    moved = rng.integers(0, 256, background.shape, dtype=np.uint8)  # another view altogether
    assert scene_changed(moved, background, 25.0, brightness_gain(moved, background))


def test_brightness_gain_is_its_np_median_form():
    from trackreplay.trackers.appearance.color import to_grey
    from trackreplay.trackers.colorpf.foreground import SCENE_STEP, brightness_gain
    rng = np.random.default_rng(12)
    for shape in ((240, 360, 3), (61, 83, 3), (40, 40)):
        image, background = rng.integers(0, 256, shape, dtype=np.uint8), rng.integers(0, 256, shape, dtype=np.uint8)
        gi, gb = to_grey(image[::SCENE_STEP, ::SCENE_STEP], "mean"), to_grey(background[::SCENE_STEP, ::SCENE_STEP], "mean")
        ok = gb > 8
        assert brightness_gain(image, background) == float(np.median(gi[ok] / gb[ok]))
