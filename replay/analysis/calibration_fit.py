"""Fitting a tracker's confidence calibration (:mod:`trackreplay.trackers.confidence`) on a corpus's rows.

Each row has the tracker's features (intercept first), whether it was right, its case and seed. The fit is
a weighted logistic regression by Newton's method (each case weighs alike, an L2 penalty on every slope but
not the intercept); the check leaves each case out of the fit in turn and scores it with the rest's fit.
The score is the expected calibration error over ten equal-width bins, per replay, then the mean over seeds.
"""

from __future__ import annotations

import numpy as np
import polars as pl

BINS = 10


def case_weights(cases: list[str]) -> np.ndarray:
    """Each case weighs alike (1 / its rows), scaled to 100 per case in all."""
    names, counts = np.unique(cases, return_counts=True)
    per = dict(zip(names.tolist(), (1.0 / counts).tolist()))
    w = np.array([per[c] for c in cases])
    return w / w.sum() * len(names) * 100


def fit(x: np.ndarray, right: np.ndarray, weights: np.ndarray, l2: float = 1.0, steps: int = 50) -> np.ndarray:
    """Weighted logistic regression by Newton's method, an L2 penalty on every coefficient but the intercept."""
    beta = np.zeros(x.shape[1])
    penalty = np.r_[0.0, np.ones(x.shape[1] - 1)] * l2
    for _ in range(steps):
        p = 1 / (1 + np.exp(-x @ beta))
        grad = x.T @ (weights * (p - right)) + penalty * beta
        hess = (x * (weights * p * (1 - p))[:, None]).T @ x + np.diag(penalty)
        beta -= np.linalg.solve(hess, grad)
    return beta


def predict(x: np.ndarray, beta: np.ndarray) -> np.ndarray:
    return 1 / (1 + np.exp(-x @ beta))


def ece(confidence: np.ndarray, right: np.ndarray, bins: int = BINS) -> float:
    """Expected calibration error over ``bins`` equal-width bins of the confidence."""
    b = np.clip((confidence * bins).astype(int), 0, bins - 1)
    return float(sum((b == i).mean() * abs(confidence[b == i].mean() - right[b == i].mean())
                     for i in range(bins) if (b == i).any()))


def per_case(rows: pl.DataFrame, confidence: np.ndarray) -> dict[str, float]:
    """ECE per case (``rows`` has ``case``, ``seed``, ``right``): the mean over seeds of each replay's ECE."""
    rows = rows.with_columns(pl.Series("c", confidence))
    out: dict[str, list[float]] = {}
    for (case, _), g in rows.group_by(["case", "seed"], maintain_order=True):
        out.setdefault(case, []).append(ece(g["c"].to_numpy(), g["right"].to_numpy().astype(float)))
    return {c: float(np.mean(v)) for c, v in out.items()}


def fit_rows(rows: pl.DataFrame, features: list[str], l2: float = 1.0) -> np.ndarray:
    """:func:`fit` on ``rows``' ``features`` columns against ``right``, each case weighing alike."""
    return fit(rows.select(features).to_numpy(), rows["right"].to_numpy().astype(float),
               case_weights(rows["case"].to_list()), l2)


def leave_one_case_out(rows: pl.DataFrame, features: list[str], raw: str = "confidence",
                       l2: float = 1.0) -> tuple[np.ndarray, dict[str, tuple[float, float, float]]]:
    """The fit on every row, and per case: the ECE of the ``raw`` confidence, of the fit in sample, and of
    the fit made with the case left out."""
    beta = fit_rows(rows, features, l2)
    before = per_case(rows, rows[raw].to_numpy())
    inside = per_case(rows, predict(rows.select(features).to_numpy(), beta))
    table = {}
    for case in sorted(before):
        held = rows.filter(pl.col("case") == case)
        rest = fit_rows(rows.filter(pl.col("case") != case), features, l2)
        table[case] = (before[case], inside[case], per_case(held, predict(held.select(features).to_numpy(), rest))[case])
    return beta, table


def markdown(table: dict[str, tuple[float, float, float]], raw_name: str) -> str:
    """The leave-one-case-out table, with its mean."""
    lines = [f"| case | ECE, {raw_name} | in-sample fit | left out of the fit |", "|---|---|---|---|"]
    lines += [f"| {c} | {a:.3f} | {b:.3f} | {d:.3f} |" for c, (a, b, d) in table.items()]
    mean = np.mean(list(table.values()), axis=0)
    lines.append("| **mean** | " + " | ".join(f"**{v:.3f}**" for v in mean) + " |")
    return "\n".join(lines)


__all__ = ["case_weights", "ece", "fit", "fit_rows", "leave_one_case_out", "markdown", "per_case", "predict"]
