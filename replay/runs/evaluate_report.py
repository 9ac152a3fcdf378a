"""What ``trackreplay evaluate`` writes from its table: ``summary.md`` and the plots.

The aggregate of a tracker over a kind of case (boxes, points, several objects) is, per seed, the
mean over the cases that ran of each case's figure (every case weighs the same, whatever its
length), then the mean over seeds ``±`` their standard deviation (the spread over seeds: the
trackers' own randomness and, with ``--jitter``, where the start box was drawn). Figures a case
does not define (ECE of a tracker without a confidence, a rate over no rows) are left out of its
mean and shown ``n/a`` when no case defines them. The worst case is the one with the lowest
headline figure (success AUC, share within 10 px, HOTA) averaged over seeds.

Plots (matplotlib, Agg): success and precision curves of box cases and the error CDF of point
cases, each the curve pooled over every case and seed of a tracker, and the reliability diagram of
``confidence`` pooled the same way.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import polars as pl

from trackreplay.replay.analysis.metrics import CALIBRATION_BINS, IOU_THRESHOLDS, PRECISION_THRESHOLDS_PX

COLUMNS = {
    "box": [("success_auc", "AUC"), ("precision_20px", "prec@20px"), ("wrong_rate", "wrong_rate"),
            ("predicted_wrong_rate", "predicted_wrong_rate"), ("ece", "ECE"), ("coverage", "coverage")],
    "point": [("within_5px", "within 5 px"), ("within_10px", "within 10 px"), ("median_error_px", "median px"),
              ("wrong_rate", "wrong_rate"), ("predicted_wrong_rate", "predicted_wrong_rate"), ("ece", "ECE"),
              ("coverage", "coverage")],
    "objects": [("mota", "MOTA"), ("idf1", "IDF1"), ("hota", "HOTA"), ("id_switches", "ID sw"),
                ("mota_3d", "MOTA 3-D"), ("hota_3d", "HOTA 3-D")],
}
HEADLINE = {"box": "success_auc", "point": "within_10px", "objects": "hota"}
TITLES = {"box": "Box cases (OTB success and precision)", "point": "Point cases (a ball's centre)",
          "objects": "Multi-object cases (CLEAR MOT, IDF1, HOTA)"}
ERROR_CDF_PX = np.arange(0.0, 51.0)
# groups on the ground plane, in metres (replay.analysis.group_ground): on cases whose log has one
GROUND_COLUMNS = [("ground_person_coverage", "person coverage"), ("ground_person_coverage_min", "least person"),
                  ("ground_people_at_goal", "people ≥ 80 %"), ("ground_wrong_rate", "wrong measured"),
                  ("ground_group_mota", "group MOTA"), ("ground_group_idf1", "group IDF1"),
                  ("ground_group_id_switches", "group ID sw"), ("ground_merges_found", "merges found"),
                  ("ground_merges", "merges"), ("ground_splits_found", "splits found"), ("ground_splits", "splits")]


def _fmt(mean: float | None, spread: float | None = None) -> str:
    if mean is None or not math.isfinite(mean):
        return "n/a"
    digits = 3 if abs(mean) < 100 else 1
    text = f"{mean:.{digits}f}"
    if spread is None or not math.isfinite(spread) or spread == 0:
        return text
    shown = f"{spread:.{digits}f}"
    return f"{text} ± {shown}" if float(shown) else f"{text} ± <{10.0 ** -digits:.{digits}f}"


def _table(header: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    return "\n".join(lines + ["| " + " | ".join(r) + " |" for r in rows])


def _seed_spread(values: pl.DataFrame, column: str) -> tuple[float | None, float | None]:
    """Mean and standard deviation over seeds of a per-seed value (``column``, nulls left out)."""
    v = values[column].drop_nulls().drop_nans().to_numpy().astype(float)
    if v.size == 0:
        return None, None
    return float(v.mean()), float(v.std()) if v.size > 1 else None


def aggregate(ok: pl.DataFrame, target: str) -> list[list[str]]:
    """One line per tracker: cases, each column's mean ± spread over seeds, the worst case."""
    names = [c for c, _ in COLUMNS[target]]
    out = []
    for tracker in ok["tracker"].unique(maintain_order=True).to_list():
        mine = ok.filter(pl.col("tracker") == tracker)
        per_seed = mine.group_by("seed", maintain_order=True).agg(
            *(pl.col(c).cast(pl.Float64).fill_nan(None).mean() for c in names))
        cells = [_fmt(*_seed_spread(per_seed, c)) for c in names]
        by_case = mine.group_by("case", maintain_order=True).agg(
            pl.col(HEADLINE[target]).cast(pl.Float64).fill_nan(None).mean()).drop_nulls()
        worst = by_case.sort([HEADLINE[target], "case"]).row(0) if by_case.height else None
        out.append([tracker, str(mine["case"].n_unique()), *cells,
                    f"{worst[0]} ({_fmt(worst[1])})" if worst else "n/a"])
    return out


def per_case(ok: pl.DataFrame, target: str) -> list[list[str]]:
    names = [c for c, _ in COLUMNS[target]]
    out = []
    for (case, tracker), rows in ok.group_by(["case", "tracker"], maintain_order=True):
        cells = [_fmt(*_seed_spread(rows.select(pl.col(c).cast(pl.Float64).fill_nan(None)), c)) for c in names]
        out.append([case, tracker, str(rows.height), *cells])
    return out


def ground_section(ok: pl.DataFrame) -> list[str]:
    """Per case, the group scores on the ground (metres) where a case has them (its log has a ground plane)."""
    if "ground_person_coverage" not in ok.columns:
        return []
    rows = ok.filter(pl.col("ground_person_coverage").is_not_null())
    if rows.is_empty():
        return []
    names = [c for c, _ in GROUND_COLUMNS]
    lines = []
    for (case, tracker), mine in rows.group_by(["case", "tracker"], maintain_order=True):
        lines.append([case, tracker, str(mine.height),
                      *(_fmt(*_seed_spread(mine.select(pl.col(c).cast(pl.Float64).fill_nan(None)), c)) for c in names)])
    return ["## Groups on the ground plane (metres; person within 1.5 m of a measured row)", "",
            _table(["case", "tracker", "seeds", *(label for _, label in GROUND_COLUMNS)], lines), ""]


def summary_markdown(table: pl.DataFrame, *, title: str, command: str, seeds: list[int], jitter: float,
                     skipped: list[str], notes: list[str], scale: tuple[float, float] | None = None) -> str:
    """``summary.md``: aggregate per tracker and per case for each kind of case, failures, skipped cases."""
    ok = table.filter(pl.col("status") == "ok")
    parts = [f"# {title}", "", f"`{command}`", "",
             f"{table['case'].n_unique()} case(s), seeds {', '.join(map(str, seeds))}"
             + (f", start marks moved by up to {jitter:g} px per seed" if jitter else "")
             + (", their sides scaled by {:g}-{:g} per seed".format(*scale) if scale else "")
             + f"; {ok.height} of {table.height} replays scored. Figures: mean over cases, then mean ± standard "
               "deviation over seeds (docs/evaluate.md defines every column).", ""]
    parts += [f"- {n}" for n in notes] + ([""] if notes else [])
    for target in ("box", "point", "objects"):
        rows = ok.filter(pl.col("target") == target)
        if rows.is_empty():
            continue
        header = [label for _, label in COLUMNS[target]]
        parts += [f"## {TITLES[target]}", "", "Aggregate per tracker:", "",
                  _table(["tracker", "cases", *header, "worst case"], aggregate(rows, target)), "",
                  "Per case:", "", _table(["case", "tracker", "seeds", *header], per_case(rows, target)), ""]
    parts += ground_section(ok)
    failed = table.filter(pl.col("status") != "ok").group_by(["case", "tracker", "error"], maintain_order=True).agg("seed")
    if failed.height:
        parts += ["## Failed replays", "", _table(["case", "tracker", "seeds", "error"],
                                                   [[c, t, ", ".join(map(str, s)), (e or "").replace("|", "/")]
                                                    for c, t, e, s in failed.iter_rows()]), ""]
    if skipped:
        parts += ["## Skipped cases", ""] + [f"- {s}" for s in skipped] + [""]
    return "\n".join(parts)


def pooled_reliability(rows: pl.DataFrame) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Bins pooled over rows: count, mean confidence, accuracy, and the pooled ECE (NaN: no confidence)."""
    count = np.zeros(CALIBRATION_BINS)
    conf = np.zeros(CALIBRATION_BINS)
    right = np.zeros(CALIBRATION_BINS)
    for c, m, a in rows.select("rel_count", "rel_confidence", "rel_accuracy").iter_rows():
        if c is None:
            continue
        c = np.asarray(c, float)
        filled = c > 0
        count += c
        conf[filled] += c[filled] * np.asarray(m, float)[filled]
        right[filled] += c[filled] * np.asarray(a, float)[filled]
    with np.errstate(invalid="ignore", divide="ignore"):
        mean_conf, accuracy = conf / count, right / count
    total = count.sum()
    filled = count > 0
    ece = float(np.sum(count[filled] / total * np.abs(accuracy[filled] - mean_conf[filled]))) if total else float("nan")
    return count, mean_conf, accuracy, ece


def _mean_curve(rows: pl.DataFrame, column: str) -> np.ndarray | None:
    curves = [np.asarray(c, float) for c in rows[column].to_list() if c is not None]
    return np.nanmean(np.vstack(curves), axis=0) if curves else None


def _error_cdf(rows: pl.DataFrame) -> np.ndarray | None:
    """Share of visible truth frames with a measured centre within each radius, pooled."""
    visible = int(rows["n_visible"].fill_null(0).sum())
    if not visible:
        return None
    errors = np.concatenate([np.asarray(e, float) for e in rows["errors"].to_list() if e is not None] or [np.zeros(0)])
    return (errors[None, :] <= ERROR_CDF_PX[:, None]).sum(axis=1) / visible


def write_plots(table: pl.DataFrame, folder: Path) -> list[Path]:
    """The curves and the reliability diagram as PNG files in ``folder``; the paths written."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ok = table.filter(pl.col("status") == "ok")
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    box, point = ok.filter(pl.col("target") == "box"), ok.filter(pl.col("target") == "point")
    specs = [("success.png", box, "success_curve", IOU_THRESHOLDS, "IoU threshold", "success rate", "AUC"),
             ("precision.png", box, "precision_curve", PRECISION_THRESHOLDS_PX, "centre error threshold (px)",
              "precision", "@20px")]
    for name, rows, column, xs, xlabel, ylabel, tag in specs:
        if rows.is_empty():
            continue
        fig, ax = plt.subplots(figsize=(6, 4.5))
        for tracker, mine in rows.group_by("tracker", maintain_order=True):
            curve = _mean_curve(mine, column)
            if curve is not None:
                value = curve.mean() if tag == "AUC" else curve[int(PRECISION_THRESHOLDS_PX.searchsorted(20.0))]
                ax.plot(xs, curve, label=f"{tracker[0]} ({tag} {value:.3f})")
        ax.set(xlabel=xlabel, ylabel=ylabel, ylim=(0, 1), title=f"{ylabel}, box cases (mean over cases and seeds)")
        ax.legend()
        written.append(_save(fig, folder / name))
    if not point.is_empty():
        fig, ax = plt.subplots(figsize=(6, 4.5))
        for tracker, mine in point.group_by("tracker", maintain_order=True):
            cdf = _error_cdf(mine)
            if cdf is not None:
                ax.plot(ERROR_CDF_PX, cdf, label=f"{tracker[0]} (within 10 px {cdf[10]:.3f})")
        ax.set(xlabel="centre error (px)", ylabel="share of visible truth frames", ylim=(0, 1),
               title="error CDF of measured rows, point cases (pooled frames)")
        ax.legend()
        written.append(_save(fig, folder / "error_cdf.png"))
    written += _reliability_plot(ok, folder, plt)
    return written


def _reliability_plot(ok: pl.DataFrame, folder: Path, plt) -> list[Path]:
    single = ok.filter(pl.col("target") != "objects")
    if single.is_empty():
        return []
    fig, ax = plt.subplots(figsize=(5, 5))
    ax.plot([0, 1], [0, 1], color="grey", linestyle=":", label="calibrated")
    drawn = False
    for (tracker, target), mine in single.group_by(["tracker", "target"], maintain_order=True):
        count, conf, acc, ece = pooled_reliability(mine)
        if count.sum() == 0:
            continue
        filled = count > 0
        ax.plot(conf[filled], acc[filled], marker="o", label=f"{tracker}, {target} (ECE {ece:.3f}, {int(count.sum())} rows)")
        drawn = True
    if not drawn:
        plt.close(fig)
        return []
    ax.set(xlabel="confidence (bin mean)", ylabel="share of rows that are right", xlim=(0, 1), ylim=(0, 1),
           title="reliability of confidence")
    ax.legend(fontsize=8)
    return [_save(fig, folder / "reliability.png")]


def _save(fig, path: Path) -> Path:
    import matplotlib.pyplot as plt

    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path
