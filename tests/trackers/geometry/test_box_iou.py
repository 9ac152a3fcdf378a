"""The one IoU (trackers.geometry.box.iou): known answers, both box formats, any pairing."""

import numpy as np
import pytest

from trackreplay.replay.analysis.mot import iou_distance
from trackreplay.trackers.geometry.box import iou


def test_known_answers_row_by_row() -> None:
    centred_a = np.array([[5.0, 5.0, 10.0, 10.0], [0.0, 0.0, 2.0, 2.0]])
    centred_b = np.array([[10.0, 5.0, 10.0, 10.0], [10.0, 10.0, 2.0, 2.0]])
    assert iou(centred_a, centred_b, centred=True) == pytest.approx([50 / 150, 0.0])
    # the same boxes by their top-left corners
    assert iou(centred_a - [5, 5, 0, 0], centred_b - [5, 5, 0, 0]) == pytest.approx([50 / 150, 0.0])


def test_every_pair_and_empty_boxes() -> None:
    a = np.array([[0.0, 0.0, 2.0, 2.0], [0.0, 0.0, 0.0, 0.0]])
    b = np.array([[1.0, 0.0, 2.0, 2.0], [0.0, 0.0, 2.0, 2.0], [0.0, 0.0, 0.0, 0.0]])
    got = iou(a[:, None], b[None])
    assert got.shape == (2, 3)
    assert got[0] == pytest.approx([2 / 6, 1.0, 0.0])
    assert np.array_equal(got[1], [0.0, 0.0, 0.0])  # an empty box overlaps nothing (no 0/0)
    assert np.array_equal(iou_distance(a, b, np.inf), 1.0 - got)


def _centred_rows(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The row-by-row centre-box IoU replay.analysis.eval had (the form this one replaced)."""
    ax0, ay0, ax1, ay1 = a[:, 0] - a[:, 2] / 2, a[:, 1] - a[:, 3] / 2, a[:, 0] + a[:, 2] / 2, a[:, 1] + a[:, 3] / 2
    bx0, by0, bx1, by1 = b[:, 0] - b[:, 2] / 2, b[:, 1] - b[:, 3] / 2, b[:, 0] + b[:, 2] / 2, b[:, 1] + b[:, 3] / 2
    inter = np.clip(np.minimum(ax1, bx1) - np.maximum(ax0, bx0), 0, None) * np.clip(np.minimum(ay1, by1) - np.maximum(ay0, by0), 0, None)
    union = a[:, 2] * a[:, 3] + b[:, 2] * b[:, 3] - inter
    return np.where(union > 0, inter / np.where(union > 0, union, 1), 0.0)


def _corner_pairs(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The every-pair top-left-box 1 - IoU replay.analysis.mot had (the form this one replaced)."""
    lo = np.maximum(a[:, None, :2], b[None, :, :2])
    hi = np.minimum(a[:, None, :2] + a[:, None, 2:], b[None, :, :2] + b[None, :, 2:])
    inter = np.prod(np.clip(hi - lo, 0.0, None), axis=2)
    union = np.prod(a[:, 2:], axis=1)[:, None] + np.prod(b[:, 2:], axis=1)[None, :] - inter
    return 1.0 - inter / np.where(union > 0, union, 1.0)


def test_bit_for_bit_the_forms_it_replaced() -> None:
    rng = np.random.default_rng(0)
    for _ in range(20):
        a = np.column_stack([rng.uniform(0, 100, (30, 2)), rng.uniform(0, 30, (30, 2))])
        b = np.column_stack([rng.uniform(0, 100, (30, 2)), rng.uniform(0, 30, (30, 2))])
        assert np.array_equal(iou(a, b, centred=True), _centred_rows(a, b))
        assert np.array_equal(1.0 - iou(a[:, None], b[None]), _corner_pairs(a, b))
