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
