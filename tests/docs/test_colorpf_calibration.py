"""docs/colorpf_calibration.py's fit and table on small synthetic rows (the corpus run itself is the script's)."""

import dataclasses
import importlib.util
from pathlib import Path

import numpy as np
import polars as pl
import pytest

from trackreplay.trackers.colorpf.calibration import RowEvidence, calibrated

SCRIPT = Path(__file__).resolve().parents[2] / "docs" / "colorpf_calibration.py"


@pytest.fixture(scope="module")
def cal():
    spec = importlib.util.spec_from_file_location("colorpf_calibration", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def synthetic_rows(beta: np.ndarray, n: int, rng: np.random.Generator) -> pl.DataFrame:
    """Rows whose evidence features are drawn at random and whose ``right`` is drawn from ``beta``'s model."""
    parts = []
    for i, case in enumerate(("a", "b", "c")):
        m = n * (i + 1)  # unequal lengths: the weights even them out
        ev = [RowEvidence(rng.uniform(), bool(rng.integers(2)), bool(rng.integers(2)), rng.uniform(-0.5, 0.5),
                          rng.uniform(), rng.uniform(0, 2), int(rng.integers(0, 60))) for _ in range(m)]
        x = np.stack([e.features() for e in ev])
        p = np.array([calibrated(e, tuple(beta)) for e in ev])
        cols = {"intercept": x[:, 0], **{f: x[:, j + 1] for j, f in enumerate(("colour", "measured", "placed",
                "separation", "effective_share", "spread", "unsupported"))}}
        parts.append(pl.DataFrame({**cols, "confidence": x[:, 1], "right": rng.uniform(size=m) < p,
                                   "case": [case] * m, "seed": rng.integers(0, 2, m)}))
    return pl.concat(parts)


def test_features_are_the_report_time_ones(cal):
    """The script's columns are RowEvidence's fields in features() order: its fit is what calibrated() reads."""
    assert cal.FEATURES == tuple(f.name for f in dataclasses.fields(RowEvidence))
    assert len(cal.FEATURES) + 1 == len(cal.COEFFICIENTS)
    e = RowEvidence(0.3, False, True, 0.9, 0.4, 3.0, 90)
    row = pl.DataFrame([dict(zip(("intercept", *cal.FEATURES), e.features().tolist()))])
    assert np.array_equal(cal.design(row)[0], e.features())
    assert cal.predict(row, np.asarray(cal.COEFFICIENTS))[0] == pytest.approx(calibrated(e))


def test_fit_recovers_known_coefficients(cal):
    beta = np.array([0.5, -1.5, 1.0, 0.8, 2.0, -1.0, -1.2, -0.7])
    rows = synthetic_rows(beta, 2000, np.random.default_rng(0))
    x, right = cal.design(rows), rows["right"].to_numpy().astype(float)
    mle = cal.fit(x, right, np.ones(rows.height), l2=0.0)  # unweighted, unpenalised: maximum likelihood
    assert np.max(np.abs(mle - beta)) < 0.25
    # the script's fit: the cases weigh 100 rows each in all, so the penalty shrinks the slopes (not the intercept)
    fitted = cal.fit_rows(rows)
    assert np.linalg.norm(fitted[1:]) < np.linalg.norm(cal.fit(x, right, cal.case_weights(rows["case"].to_list()),
                                                                 l2=0.0)[1:])
    assert np.max(np.abs(cal.fit_rows(rows.sample(fraction=1.0, seed=1)) - fitted)) < 1e-9  # row order: no effect


def test_each_case_weighs_alike(cal):
    w = cal.case_weights(["a"] * 10 + ["b"] * 30)
    assert w[:10].sum() == pytest.approx(w[10:].sum()) == pytest.approx(100.0)


def test_ece_and_table(cal):
    conf = np.array([0.05, 0.05, 0.95, 0.95])
    assert cal.ece(conf, np.array([0.0, 0.0, 1.0, 1.0])) == pytest.approx(0.05)
    assert cal.ece(conf, np.array([1.0, 1.0, 0.0, 0.0])) == pytest.approx(0.95)
    rows = synthetic_rows(np.array([0.0, 2.0, 0, 0, 0, 0, 0, 0]), 300, np.random.default_rng(2))
    beta, table = cal.loso_table(rows)
    assert list(table) == ["a", "b", "c"] and len(beta) == 8
    assert all(0.0 <= v <= 1.0 for row in table.values() for v in row)
    text = cal.markdown(table)
    assert text.splitlines()[2].startswith("| a | ") and text.splitlines()[-1].startswith("| **mean** | **")
