"""The golf tracker's calibrated confidence: refit ``trackers/golf/calibration.COEFFICIENTS`` and the
leave-one-case-out table of docs/ball_corpus.md ("Calibrated confidence").

    python docs/golf_calibration.py --out ball-out-j2   # OUT/logs: an evaluate run's recordings, reused

Replays every case of benchmarks/corpora/ball.toml with seeds 0-2 and the marks jittered by up to 2 px (as
``trackreplay evaluate ball.toml --seeds 0-2 --jitter 2`` makes them), with the calibration off, and keeps
the "measured" and "predicted" rows on the truth's frames: the :class:`RowEvidence` (the validation's
confidence, measured or not, the misses in a row over ``lost_after``) and whether the row is within 10 px of
a visible ball. Then the fit of ``replay/analysis/calibration_fit.py`` (each case weighs alike, an L2
penalty of 1 on the slopes), printed as COEFFICIENTS, the ECE per case of the validation's confidence, of
the fit in sample and of the fit with the case left out, and the pooled ECE over all rows. A case that
cannot be prepared (the broadcasts' refused marks) is skipped with one line.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np
import polars as pl

ROOT = Path(__file__).resolve().parents[1]

from trackreplay.replay.analysis.calibration_fit import ece, leave_one_case_out, markdown, predict  # noqa: E402
from trackreplay.replay.core.engine import ReplayRequest, iter_steps  # noqa: E402
from trackreplay.replay.runs.case_logs import recorder_code  # noqa: E402
from trackreplay.replay.runs.corpus import DATA_ROOT_ENV, load_corpus  # noqa: E402
from trackreplay.replay.runs.evaluate import EvalOptions, prepared_replays  # noqa: E402
from trackreplay.schemas.errors import TrackreplayError  # noqa: E402
from trackreplay.trackers.golf.calibration import COEFFICIENTS  # noqa: E402

CORPUS = ROOT / "benchmarks" / "corpora" / "ball.toml"
SEEDS = (0, 1, 2)
JITTER = 2.0
RIGHT_PX = 10.0
FEATURES = ["intercept", "gate", "measured", "misses"]  # RowEvidence.features(), in order


def replay_rows(log: Path, seed: int) -> pl.DataFrame:
    """One replay's "measured" / "predicted" rows with the :class:`RowEvidence` the tracker reports in its
    intermediates (its features, in order)."""
    rows = []
    for step in iter_steps(ReplayRequest(log=log, tracker="golf", seed=seed, config={"calibrate": False})):
        evidence = step.intermediates.evidence
        if evidence is None or not step.states or step.states[0].status not in ("measured", "predicted"):
            continue
        s = step.states[0]
        rows.append((step.frame.index, s.status, s.x, s.y, s.confidence, *evidence.features()))
    return pl.DataFrame(rows, orient="row", schema={
        "frame": pl.Int64, "status": pl.String, "x": pl.Float64, "y": pl.Float64, "confidence": pl.Float64,
        **{f: pl.Float64 for f in FEATURES}})


def collect(out: Path, environ: dict[str, str] | None) -> pl.DataFrame:
    """Every case's rows for every seed on a frame the truth lists, with ``right``: within 10 px of a visible ball."""
    parts = []
    opts = EvalOptions(out, SEEDS, JITTER, None, recorder_code())
    for case, seed, log, truth in prepared_replays(load_corpus(CORPUS, environ), opts):
        truth = truth.select("frame", pl.col("x").alias("x_truth"), pl.col("y").alias("y_truth"), "visible")
        try:
            rows = replay_rows(log, seed).join(truth, on="frame", how="inner")
        except TrackreplayError as err:  # a refused mark (the tracker's own error) skips the replay
            print(f"{case} seed {seed}: skipped ({str(err).splitlines()[0][:160]})", file=sys.stderr)
            continue
        d = np.hypot(rows["x"].to_numpy() - rows["x_truth"].to_numpy().astype(float),
                     rows["y"].to_numpy() - rows["y_truth"].to_numpy().astype(float))
        seen = rows["visible"].fill_null(True).to_numpy() & np.isfinite(d)
        parts.append(rows.with_columns(pl.lit(case).alias("case"), pl.lit(seed).alias("seed"),
                                       pl.Series("right", seen & (np.nan_to_num(d, nan=np.inf) <= RIGHT_PX))))
        print(f"{case} seed {seed}: {rows.height} rows", file=sys.stderr, flush=True)
    return pl.concat(parts)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, help="evaluate's output folder whose logs/ to reuse (and add to); "
                    "default: a temporary one, every case recorded again")
    ap.add_argument("--data-root", type=Path,
                    help=f"the real clips' folder (else {DATA_ROOT_ENV} or the corpus's data_root)")
    args = ap.parse_args()
    environ = {DATA_ROOT_ENV: str(args.data_root)} if args.data_root else None
    with tempfile.TemporaryDirectory() as tmp:
        rows = collect(args.out or Path(tmp), environ)
    beta, table = leave_one_case_out(rows, FEATURES)
    right = rows["right"].to_numpy().astype(float)
    print("COEFFICIENTS = (" + ", ".join(f"{b:.3f}" for b in beta) + ")")
    print(f"committed:     {COEFFICIENTS}")
    print(markdown(table, "the validation's confidence"))
    print(f"pooled over {rows.height} rows: ECE of the validation's confidence "
          f"{ece(rows['confidence'].to_numpy(), right):.3f}, of the fit "
          f"{ece(predict(rows.select(FEATURES).to_numpy(), beta), right):.3f}")


if __name__ == "__main__":
    main()
