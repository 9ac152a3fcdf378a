"""A log asked for in a folder that does not exist: exit 5 (docs/exit_codes.md), one sentence, from every writer."""

from pathlib import Path

import cv2
import numpy as np
import pytest

from trackreplay.replay.cli.main import main


@pytest.mark.parametrize("verb", [
    ["synth", "flow-sim1", "{out}", "--frames", "2"],
    ["synth", "golf-teeshot", "{out}", "--duration", "0.5"],
    ["synth", "colorpf-illumination", "{out}", "--frames", "2"],
    ["synth", "groups-crossing", "{out}", "--duration", "0.5"],
    ["record", "{out}", "--images", "{images}", "--fps", "30", "--quiet"],
])
def test_a_missing_output_folder_exits_5(verb: list[str], tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    images = tmp_path / "img"
    images.mkdir()
    for i in range(2):
        cv2.imwrite(str(images / f"{i:04d}.png"), np.zeros((16, 16, 3), np.uint8))
    out = tmp_path / "no" / "x.mcap"
    assert main([a.format(out=out, images=images) for a in verb]) == 5
    err = capsys.readouterr().err.strip()
    assert err == f"trackreplay: error: cannot write {out}: output folder {out.parent} does not exist"
    assert not out.parent.exists()


GOLDEN = Path(__file__).resolve().parents[2] / "golden"


@pytest.fixture(scope="module")
def flow_traj(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("traj") / "t.parquet"
    assert main(["replay", str(GOLDEN / "flow-sim1-24f.mcap"), "--tracker", "flow", "--export", str(out), "--quiet"]) == 0
    return out


@pytest.mark.parametrize("verb", [
    ["recover", "{log}", "{out}"],
    ["annotate", "{log}", "--frame", "0", "--box", "1,1,4,4", "--out", "{out}"],
    ["filter", "{log}", "{out}"],
    ["merge", "{log}", "--encoders", "{csv}", "-o", "{out}"],
])
def test_every_verb_writing_a_log_exits_5_for_a_missing_folder(verb, tmp_path: Path, capsys) -> None:
    """docs/exit_codes.md: a log is written only into a folder that exists (`record`, `synth`, `recover`,
    `annotate`, `filter`, `merge`), status 5, one sentence naming the output."""
    csv = tmp_path / "e.csv"
    csv.write_text("t_ns,pan,tilt,zoom,focus\n0,0,0,1,0\n")
    out = tmp_path / "no" / "x.mcap"
    assert main([a.format(log=GOLDEN / "flow-sim1-24f.mcap", out=out, csv=csv) for a in verb]) == 5
    err = capsys.readouterr().err
    assert err.startswith("trackreplay: error: cannot write ") and str(out) in err and err.count("\n") == 1
    assert not out.parent.exists()


@pytest.mark.parametrize("verb, made", [
    (["eval", "{traj}", "{log}", "--json", "{dir}/m.json", "--per-frame", "{dir}/f.csv"], ["m.json", "f.csv"]),
    (["export", "{traj}", "{dir}/t.csv"], ["t.csv"]),
    (["smooth", "{traj}", "{log}", "--out", "{dir}/s.parquet"], ["s.parquet"]),
])
def test_every_verb_writing_results_creates_their_folder(verb, made, flow_traj: Path, tmp_path: Path, capsys) -> None:
    """... and the results (tables, metrics, the replay's own outputs) create theirs, status 0."""
    folder = tmp_path / "new" / "deeper"
    assert main([a.format(traj=flow_traj, log=GOLDEN / "flow-sim1-24f.mcap", dir=folder) for a in verb]) == 0
    assert sorted(p.name for p in folder.iterdir()) == sorted(made)
