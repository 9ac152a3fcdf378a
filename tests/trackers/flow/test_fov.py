import numpy as np

from trackreplay.trackers.flow.fov import crop, fov_origin, inside, next_centre, shift_field


def test_crop_inside_is_a_plain_slice() -> None:
    img = np.arange(100 * 80, dtype=np.float32).reshape(80, 100)
    win = crop(img, (50, 40), 11)
    assert fov_origin((50, 40), 11) == (45, 35)
    assert np.array_equal(win, img[35:46, 45:56])


def test_crop_past_the_border_repeats_edge_pixels() -> None:
    img = np.arange(20 * 20, dtype=np.float32).reshape(20, 20)
    win = crop(img, (1, 18), 7)
    assert win.shape == (7, 7)
    assert np.array_equal(win[:, 0], win[:, 1]) and np.array_equal(win[:, 1], win[:, 2])  # columns -2, -1 → 0
    assert np.array_equal(win[-1], win[-2])  # row 21 → 19, row 20 → 19
    assert win[3, 3] == img[18, 1]


def test_next_centre_rounds_and_stays_on_the_image() -> None:
    assert next_centre(np.array([10.5, 3.49]), (50, 60)) == (11, 3)
    assert next_centre(np.array([-7.0, 80.0]), (50, 60)) == (0, 49)
    assert inside(np.array([0.0, 49.4]), (50, 60)) and not inside(np.array([-1.0, 10.0]), (50, 60))
    assert not inside(np.array([np.nan, 1.0]), (50, 60))


def test_shift_field_moves_content() -> None:
    a = np.zeros((5, 5), np.float32)
    a[2, 2] = 1.0
    b = shift_field(a, 1, -2)
    assert b[0, 3] == 1.0 and b.sum() == 1.0
    assert shift_field(a, 9, 0).sum() == 0.0
