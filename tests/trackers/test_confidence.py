"""The shared logistic that turns a tracker's row evidence into a probability."""

import math

import pytest

from trackreplay.trackers.confidence import logistic


def test_logistic_known_values():
    assert logistic([1.0, 0.0], [0.0, 5.0]) == 0.5
    assert logistic([1.0, 2.0], [1.0, 1.0]) == pytest.approx(1 / (1 + math.exp(-3.0)))
    assert logistic([1.0, 2.0], [-1.0, -1.0]) == pytest.approx(1 / (1 + math.exp(3.0)))


def test_logistic_far_tails_do_not_overflow():
    assert logistic([1.0], [-1000.0]) == 0.0 and logistic([1.0], [1000.0]) == 1.0


def test_logistic_refuses_features_and_coefficients_of_different_lengths():
    with pytest.raises(ValueError, match="3 features for 2 coefficients"):
        logistic([1.0, 2.0, 3.0], [1.0, 2.0])
