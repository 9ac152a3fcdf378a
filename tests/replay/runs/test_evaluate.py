"""`trackreplay evaluate`: a small synthetic corpus end to end, twice (the same cases.parquet bytes),
a failing replay as a row, real-data cases skipped without the data, the CSRT baseline."""

from __future__ import annotations

from pathlib import Path

import polars as pl
import pytest

from trackreplay.replay.cli.main import main
from trackreplay.replay.runs.case_logs import jitter_factor, jitter_offset, prepare_case, recorder_code
from trackreplay.replay.runs.corpus import load_corpus
from trackreplay.replay.runs.csrt import _has_csrt, csrt_venv
from trackreplay.replay.runs.evaluate import EvalOptions, cases_table, plan, run_serial

SMALL = """
[corpus]
name = "small"

[[case]]
name = "walker"
synth = "colorpf-illumination"
seed = 3
synth_options = { frames = 6, empty_frames = 2, width = 320, height = 240 }
object = 1

[[case]]
name = "square"
synth = "flow-sim1"
synth_options = { frames = 6 }
trackers = ["flow"]

[[case]]
name = "square_own_mark"
synth = "flow-sim1"
synth_options = { frames = 6 }
trackers = ["flow", "groups"]
marks = "log"
"""


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "suite.toml"
    path.write_text(text)
    return path


@pytest.mark.slow  # 4 s: the default suite took 4 min 13 s on a fresh clone (budget 4 min); CI runs -m slow
def test_a_small_corpus_end_to_end_twice_gives_the_same_table(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    suite, out = _write(tmp_path, SMALL), tmp_path / "out"
    args = ["evaluate", str(suite), "--out", str(out), "--seeds", "0-1", "--serial", "--no-baseline", "--quiet"]
    assert main(args) == 1  # the groups row fails (no stereo pair): the run goes on and says so
    first = (out / "cases.parquet").read_bytes()
    logs = {p.name: p.stat().st_mtime_ns for p in (out / "logs").iterdir()}
    assert main(args) == 1
    assert (out / "cases.parquet").read_bytes() == first
    assert {p.name: p.stat().st_mtime_ns for p in (out / "logs").iterdir()} == logs  # recorded once, then cached
    elsewhere = tmp_path / "elsewhere"  # another folder, recorded afresh: still the same bytes
    assert main([*args[:3], str(elsewhere), *args[4:]]) == 1
    assert (elsewhere / "cases.parquet").read_bytes() == first

    table = pl.read_parquet(out / "cases.parquet")
    assert table.height == (2 + 1 + 2) * 2  # walker: colorpf, flow; square: flow; own mark: flow, groups; × 2 seeds
    assert table.select("case", "tracker", "seed").rows()[:3] == [("walker", "colorpf", 0), ("walker", "colorpf", 1),
                                                                ("walker", "flow", 0)]
    failed = table.filter(pl.col("status") != "ok")
    assert failed["tracker"].to_list() == ["groups", "groups"]
    assert "stereo pair" in failed["error"][0] and str(out) not in failed["error"][0]
    ok = table.filter(pl.col("status") == "ok")
    assert ok["digest"].null_count() == 0 and ok["success_auc"].null_count() == 0
    assert (ok["success_auc"].is_between(0, 1)).all() and (ok["n_visible"] > 0).all()
    square = ok.filter(pl.col("case") == "square")
    assert square["mark"][0].startswith("0:") and square["start"][0] == "0"
    assert ok.filter(pl.col("case") == "square_own_mark")["start"][0] == "log"
    timings = pl.read_parquet(out / "timings.parquet")
    assert timings.height == ok.height and (timings["ms_per_frame"] > 0).all()

    summary = (out / "summary.md").read_text()
    for words in ("wrong_rate", "ECE", "AUC", "colorpf", "flow", "worst case", "Failed replays"):
        assert words in summary
    assert {p.name for p in (out / "plots").iterdir()} >= {"success.png", "precision.png", "reliability.png"}
    assert "replays scored" in capsys.readouterr().err


def test_real_data_cases_are_skipped_with_one_line_when_absent(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    suite = _write(tmp_path, """
[corpus]
data_root = "no-such-folder"

[[case]]
name = "clip"
video = "clip.mp4"
truth = "labels.csv"
""")
    assert main(["evaluate", str(suite), "--out", str(tmp_path / "out"), "--serial"]) == 2
    err = capsys.readouterr().err
    assert "skipping case clip:" in err and "no case to run" in err


def test_jitter_moves_the_mark_per_seed_within_bounds(tmp_path: Path) -> None:
    a, b = jitter_offset("rally", 0, 12, 3.0), jitter_offset("rally", 1, 12, 3.0)
    assert a == jitter_offset("rally", 0, 12, 3.0) and a != b
    assert all(abs(v) <= 3.0 for v in a + b) and jitter_offset("rally", 0, 12, 0.0) == (0.0, 0.0)
    suite = _write(tmp_path, '[[case]]\nname = "square"\nsynth = "flow-sim1"\nsynth_options = { frames = 3 }\n')
    case = load_corpus(suite).cases[0]
    prep = prepare_case(case, tmp_path / "logs", recorder_code(), (0, 1), 2.0)
    (_, log0, (m0,)), (_, log1, (m1,)) = prep.marked
    assert log0 != log1 and (m0.x, m0.y) != (m1.x, m1.y)
    truth_x = 148.0 - 13 / 2  # the square's truth on frame 0 (centre 148, side 13)
    assert abs(m0.x - truth_x) <= 2.0 and abs(m1.x - truth_x) <= 2.0


def test_jitter_scale_draws_each_seeds_box_size_round_the_same_centre(tmp_path: Path) -> None:
    k0, k1 = jitter_factor("rally", 0, 12, (0.7, 1.5)), jitter_factor("rally", 1, 12, (0.7, 1.5))
    assert k0 == jitter_factor("rally", 0, 12, (0.7, 1.5)) and k0 != k1 and 0.7 <= min(k0, k1) <= max(k0, k1) <= 1.5
    assert jitter_factor("rally", 0, 12, None) == 1.0
    suite = _write(tmp_path, '[[case]]\nname = "square"\nsynth = "flow-sim1"\nsynth_options = { frames = 3 }\n')
    case = load_corpus(suite).cases[0]
    plain = prepare_case(case, tmp_path / "logs", recorder_code(), (0, 1), 2.0)
    sized = prepare_case(case, tmp_path / "logs", recorder_code(), (0, 1), 2.0, (0.7, 1.5))
    for (seed, _, (m,)), (_, log, (s,)) in zip(plain.marked, sized.marked):
        k = jitter_factor("square", seed, s.frame, (0.7, 1.5))
        assert (s.w, s.h) == pytest.approx((m.w * k, m.h * k))  # the square's 13 px truth box, scaled
        assert (s.x + s.w / 2, s.y + s.h / 2) == pytest.approx((m.x + m.w / 2, m.y + m.h / 2))  # the same moved centre
        assert log.is_file()
    with pytest.raises(SystemExit) as refused:
        main(["evaluate", str(suite), "--out", str(tmp_path / "o"), "--jitter-scale", "1.5:0.7", "--serial"])
    assert refused.value.code == 2


@pytest.mark.skipif(not _has_csrt(csrt_venv() / "bin" / "python"), reason="the CSRT venv is not built here")
def test_csrt_baseline_row_on_a_box_case(tmp_path: Path) -> None:
    suite = _write(tmp_path, '[[case]]\nname = "square"\nsynth = "flow-sim1"\nsynth_options = { frames = 5 }\n'
                             'trackers = ["flow"]\n')
    cases, tasks = plan(load_corpus(suite), (0,))
    assert [t.tracker for t in tasks] == ["flow", "csrt"]
    opts = EvalOptions(tmp_path / "out", (0,), 0.0, csrt_venv() / "bin" / "python", recorder_code())
    table = cases_table(run_serial(cases, tasks, opts))
    csrt = table.filter(pl.col("tracker") == "csrt").row(0, named=True)
    assert csrt["status"] == "ok" and csrt["success_auc"] > 0.5
    assert csrt["ece"] is None and csrt["n_calibrated"] == 0  # no confidence: ECE not applicable
    assert csrt["digest"] is None


def test_no_case_left_after_trackers(tmp_path: Path) -> None:
    suite = _write(tmp_path, '[[case]]\nname = "square"\nsynth = "flow-sim1"\n')
    assert plan(load_corpus(suite), (0,), ("golf",)) == ([], [])


def test_the_aggregate_is_the_mean_over_cases_then_over_seeds_and_the_reliability_pools_bins() -> None:
    from trackreplay.replay.runs.evaluate_report import aggregate, pooled_reliability

    rows = [  # case, seed, auc, wrong_rate
        ("a", 0, 0.2, 0.5), ("b", 0, 0.6, None), ("a", 1, 0.4, 0.1), ("b", 1, 0.8, 0.3)]
    bins = 10
    count_a, count_b = [0] * bins, [0] * bins
    count_a[9], count_b[9], count_b[0] = 4, 1, 5  # a: 4 rows at 0.95 conf, 3 right; b: 1 at 0.9 (right), 5 at 0.0 (1 right)
    conf_a, conf_b = [None] * 9 + [0.95], [0.0] + [None] * 8 + [0.9]
    acc_a, acc_b = [None] * 9 + [0.75], [0.2] + [None] * 8 + [1.0]
    table = pl.DataFrame({
        "case": [r[0] for r in rows], "tracker": ["colorpf"] * 4, "seed": [r[1] for r in rows],
        "success_auc": [r[2] for r in rows], "precision_20px": [1.0] * 4, "wrong_rate": [r[3] for r in rows],
        "predicted_wrong_rate": [None] * 4, "ece": [float("nan")] * 4, "coverage": [1.0] * 4,
        "rel_count": [count_a, count_b] * 2, "rel_confidence": [conf_a, conf_b] * 2, "rel_accuracy": [acc_a, acc_b] * 2,
    }, schema_overrides={"predicted_wrong_rate": pl.Float64})
    (line,) = aggregate(table, "box")
    # AUC per seed: (0.2 + 0.6) / 2 = 0.4, (0.4 + 0.8) / 2 = 0.6 -> 0.5 ± 0.1; wrong_rate: 0.5 (b has none), 0.2 -> 0.35 ± 0.15
    assert line[:4] == ["colorpf", "2", "0.500 ± 0.100", "1.000"]
    assert line[4] == "0.350 ± 0.150" and line[5] == "n/a" and line[6] == "n/a"
    assert line[-1] == "a (0.300)"  # the worst case: a's AUC over seeds (0.2 + 0.4) / 2
    count, conf, acc, ece = pooled_reliability(table)
    assert count[9] == 10 and count[0] == 10
    assert conf[9] == pytest.approx((8 * 0.95 + 2 * 0.9) / 10) and acc[9] == pytest.approx((6 + 2) / 10)
    assert ece == pytest.approx(0.5 * abs(0.8 - 0.94) + 0.5 * abs(0.2 - 0.0))


def test_prepared_replays_yield_each_seeds_marked_log_and_the_followed_truth(tmp_path: Path, capsys) -> None:
    from trackreplay.replay.runs.evaluate import prepared_replays

    suite = _write(tmp_path, '[[case]]\nname = "square"\nsynth = "flow-sim1"\nsynth_options = { frames = 3 }\n'
                             '[[case]]\nname = "clip"\nvideo = "absent.mp4"\ntruth = "absent.txt"\n')
    corpus = load_corpus(suite)
    got = list(prepared_replays(corpus, EvalOptions(tmp_path / "out", (0, 1), 2.0, None, recorder_code())))
    assert [(case, seed) for case, seed, _, _ in got] == [("square", 0), ("square", 1)]
    assert got[0][2] != got[1][2] and all(log.is_file() for _, _, log, _ in got)  # each seed's own marks
    assert got[0][3]["id"].n_unique() == 1 and got[0][3].height == 3
    assert "clip: skipped" in capsys.readouterr().err
