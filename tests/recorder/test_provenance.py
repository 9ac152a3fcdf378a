"""Every log says where it came from; replay summaries say what ran."""

from __future__ import annotations

import hashlib
import json
import tomllib
from pathlib import Path

import cv2
import numpy as np
from mcap.reader import make_reader

from trackreplay import __version__
from trackreplay.replay.cli.main import main


def provenance_records(path: Path) -> list[dict[str, str]]:
    with open(path, "rb") as fh:
        return [dict(m.metadata) for m in make_reader(fh).iter_metadata() if m.name == "trackreplay.provenance"]


def test_record_synth_annotate_and_replay_carry_provenance(tmp_path: Path, capsys) -> None:
    folder = tmp_path / "img"
    folder.mkdir()
    for i in range(4):
        cv2.imwrite(str(folder / f"{i}.png"), np.full((16, 24, 3), 40 * i, np.uint8))
    encoders = tmp_path / "enc.csv"
    encoders.write_text("t_ns,pan,tilt,zoom,focus\n0,1,2,3,4\n")
    log = tmp_path / "rec.mcap"
    assert main(["record", str(log), "--images", str(folder), "--fps", "10", "--encoders", str(encoders), "--quiet"]) == 0
    [rec] = provenance_records(log)
    assert rec["tool"] == "trackreplay" and rec["version"] == __version__
    assert rec["command_line"].startswith("trackreplay record ") and str(folder) in rec["command_line"]
    digest = hashlib.sha256(encoders.read_bytes()).hexdigest()
    assert rec["source.encoders"] == f"enc.csv sha256:{digest} {encoders.stat().st_size} bytes"
    assert rec["source.images"].startswith("img/ listing-sha256:") and rec["source.images"].endswith(" 4 files")

    marked = tmp_path / "marked.mcap"
    assert main(["annotate", str(log), "--frame", "1", "--box", "2,2,6,6", "--out", str(marked)]) == 0
    first, second = provenance_records(marked)
    assert first == rec and second["command_line"].startswith("trackreplay annotate ") and second["marks"] == "1"
    assert second["source.log"].startswith(f"rec.mcap sha256:{hashlib.sha256(log.read_bytes()).hexdigest()}")

    synth = tmp_path / "s.mcap"
    assert main(["synth", "flow-sim1", str(synth), "--frames", "3"]) == 0
    [syn] = provenance_records(synth)
    assert syn["command_line"] == f"trackreplay synth flow-sim1 {synth} --frames 3"
    capsys.readouterr()
    assert main(["info", str(synth)]) == 0
    assert "trackreplay.provenance" in capsys.readouterr().out

    summary = tmp_path / "s.json"
    assert main(["replay", str(synth), "--quiet", "--summary", str(summary)]) == 0
    s = json.loads(summary.read_text())
    assert s["version"] == __version__ and tomllib.loads(s["config_toml"])["flow"]["epsilon"] == s["config"]["epsilon"]
