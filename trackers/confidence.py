"""A row's reported confidence as a probability that the row is right (shared by the trackers).

A tracker's own score (a colour match, a gate's fit) says how well a frame agrees with the model, not
how often such a row is right. Each tracker names what it knows about a row as features (an intercept
first) and reports ``1 / (1 + exp(-beta . features))``, with ``beta`` fitted by weighted maximum
likelihood on its corpus (``replay/analysis/calibration_fit.py``, each case weighing alike, checked by
leaving each case out of the fit in turn).
"""

from __future__ import annotations

import math
from collections.abc import Sequence


def logistic(features: Sequence[float], coefficients: Sequence[float]) -> float:
    """``1 / (1 + exp(-z))`` with ``z = coefficients . features`` (both in the same order, intercept first)."""
    if len(features) != len(coefficients):
        raise ValueError(f"{len(features)} features for {len(coefficients)} coefficients")
    z = math.fsum(c * f for c, f in zip(coefficients, features))
    return 1.0 / (1.0 + math.exp(-z)) if z >= 0 else math.exp(z) / (1.0 + math.exp(z))


__all__ = ["logistic"]
