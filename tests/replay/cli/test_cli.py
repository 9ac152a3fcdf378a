"""The `trackreplay` command end to end, in-process (fast) and as a real subprocess."""

import json
import subprocess
import sys
from pathlib import Path

import polars as pl
import pytest

from trackreplay.replay.cli.main import main


def test_replay_export_eval_chain(short_sim: Path, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    traj, summary, metrics = tmp_path / "t.parquet", tmp_path / "s.json", tmp_path / "m.json"
    assert main(["replay", str(short_sim), "--tracker", "flow", "--export", str(traj), "--summary", str(summary), "--quiet"]) == 0
    s = json.loads(summary.read_text())
    assert s["frames"] == 12 and s["tracker"] == "flow" and s["seed"] == 0 and len(s["digest"]) == 64
    assert main(["replay", str(short_sim), "--expect-digest", s["digest"], "--quiet"]) == 0
    assert main(["eval", str(traj), str(short_sim), "--json", str(metrics)]) == 0
    m = json.loads(metrics.read_text())
    assert m["gt_frames"] == 12 and m["tracked_frames"] == 12
    out = capsys.readouterr().out
    assert "centre error" in out
    csv = tmp_path / "t.csv"
    assert main(["export", str(traj), str(csv), "--interpolate", "cubic"]) == 0
    assert pl.read_csv(csv).height == 12


def test_digest_mismatch_fails_clearly(short_sim: Path, capsys: pytest.CaptureFixture) -> None:
    code = main(["replay", str(short_sim), "--expect-digest", "00" * 32, "--quiet"])
    assert code == 4
    assert "digest mismatch for" in capsys.readouterr().err


def test_start_end_select_a_time_range(short_sim: Path, tmp_path: Path) -> None:
    traj = tmp_path / "part.parquet"
    assert main(["replay", str(short_sim), "--start", "0.1", "--end", "0.25", "--export", str(traj), "--interpolate", "none", "--quiet"]) == 0
    frames = pl.read_parquet(traj)["frame"].to_list()
    assert frames == [3, 4, 5, 6, 7]  # 30 fps: 0.1 s <= t < 0.25 s


@pytest.mark.parametrize(
    "argv, message",
    [
        (["replay", "missing.mcap"], "missing.mcap does not exist"),
        (["replay", "{log}", "--tracker", "flow", "--image-topic", "/nope"], "has no topic /nope; topics present:"),
        (["replay", "{log}", "--tracker", "flow", "--config", "{cfg}"], "c.toml: unknown key bogus; known: "),
        (["eval", "{traj}", "{log}"], "does not exist"),
    ],
)
def test_user_errors_are_one_sentence(argv, message, short_sim: Path, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    cfg = tmp_path / "c.toml"
    cfg.write_text("bogus = 1\n")
    args = [a.format(log=short_sim, cfg=cfg, traj=tmp_path / "none.parquet") for a in argv]
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("trackreplay: error: ") and message in err and "\n" not in err


def test_console_entry_point_runs_demo(tmp_path: Path) -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "trackreplay", "demo", "--out", str(tmp_path / "demo")],
        capture_output=True, text=True, timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    for name in ("flow-sim1.mcap", "flow-sim1-flow.rrd", "trajectory.parquet", "summary.json"):
        assert (tmp_path / "demo" / name).stat().st_size > 0
    assert "velocity RMSE" in proc.stdout


def test_bench_reports_both_ratios(short_sim: Path, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "b.json"
    assert main(["bench", str(short_sim), "--repeats", "1", "--json", str(out)]) == 0
    b = json.loads(out.read_text())
    assert b["frames"] == 12 and b["throughput_ratio"] > 0 and b["rerun_ratio"] > 0 and b["rrd_bytes"] > 0
    assert "cost ratio" in capsys.readouterr().out


def test_truncated_and_corrupt_logs(flow_sim1: Path, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    data = flow_sim1.read_bytes()  # 103 messages, flushed every 30: complete chunks before the cut
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: int(len(data) * 0.7)])
    assert main(["replay", str(cut), "--quiet"]) == 3
    assert "run `trackreplay recover" in capsys.readouterr().err
    fixed = tmp_path / "fixed.mcap"
    assert main(["recover", str(cut), str(fixed)]) == 1  # partial salvage
    summary = tmp_path / "s.json"
    assert main(["replay", str(fixed), "--summary", str(summary), "--quiet"]) == 0
    assert 0 < json.loads(summary.read_text())["frames"] < 51  # what was readable still replays
    bad = bytearray(data)
    middle = len(bad) // 2
    bad[middle : middle + 64] = bytes(b ^ 0xFF for b in bad[middle : middle + 64])
    corrupt = tmp_path / "corrupt.mcap"
    corrupt.write_bytes(bytes(bad))
    assert main(["replay", str(corrupt), "--quiet"]) == 7  # finished, but frames were skipped
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert err.startswith("warning: ") and "corrupt.mcap" in err and "skipped" in err and "crc" in err.lower()
    assert main(["replay", str(corrupt), "--quiet", "--strict"]) == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert err.startswith("trackreplay: error: ") and "corrupt.mcap" in err and "without --strict" in err


@pytest.mark.parametrize("name", ["s.frames.parquet", "s.json"])
def test_the_replay_summary_is_complete_or_absent(name: str, disk_full_at, short_sim: Path, tmp_path: Path, capsys) -> None:
    """A review: --summary (and its per-frame sidecar) were written under their final names."""
    disk_full_at(name)
    assert main(["replay", str(short_sim), "--summary", str(tmp_path / "s.json"), "--quiet"]) == 5
    assert f"cannot write {tmp_path / name}" in capsys.readouterr().err
    left = {p.name for p in tmp_path.iterdir()}
    assert name not in left and not any(n.endswith(".partial") for n in left)


def _closed_pipe_run(*argv: str) -> subprocess.CompletedProcess:
    """``trackreplay ARGV | true``: stdout is a pipe whose reader has already gone."""
    import os

    read, write = os.pipe()
    os.close(read)
    try:
        return subprocess.run([sys.executable, "-m", "trackreplay", *argv], stdout=write, stderr=subprocess.PIPE,
                              text=True, timeout=120)
    finally:
        os.close(write)


@pytest.mark.slow  # 6 s on 2 cores: keeps the default suite under its 4-minute budget (CI runs -m slow too)
def test_a_closed_stdout_keeps_the_exit_status(short_sim: Path, tmp_path: Path) -> None:
    """A review: `diff A B | true` exited 0 for two different runs (1 without the pipe)."""
    golden = Path(__file__).resolve().parents[2] / "golden" / "flow-sim1-24f.mcap"
    a, b = tmp_path / "a.json", tmp_path / "b.json"
    assert main(["replay", str(short_sim), "--summary", str(a), "--quiet"]) == 0
    assert main(["replay", str(golden), "--summary", str(b), "--quiet"]) == 0
    differ = _closed_pipe_run("diff", str(a), str(b))
    assert differ.returncode == 1 and differ.stderr == ""
    assert _closed_pipe_run("diff", str(a), str(a)).returncode == 0
    missing = _closed_pipe_run("batch", str(tmp_path / "missing.mcap"), "--serial", "--quiet", "--out", str(tmp_path / "bp"))
    assert missing.returncode == 1 and "Traceback" not in missing.stderr
