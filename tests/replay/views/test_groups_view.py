"""The groups view sends its foreground masks and disparity as PNG by default (lossless: the same
pixels), raw with ``replay --rrd-full``; the right image once, as the sink's ``camera/right``."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pyarrow as pa
import pytest

from trackreplay.replay.analysis.diff_rrd import rrd_cells
from trackreplay.replay.cli.main import main
from trackreplay.replay.core.engine import ReplayRequest, replay
from trackreplay.replay.views import groups
from trackreplay.replay.views.rerun_sink import rrd_digest

GOLDEN = Path(__file__).resolve().parents[2] / "golden"
LOG = GOLDEN / "groups-crossing-320x240.mcap"


def test_a_mask_overlay_decodes_to_the_mask_in_the_foreground_colour() -> None:
    mask = np.zeros((48, 64), bool)
    mask[10:20, 30:41] = True
    bgra = cv2.imdecode(np.frombuffer(groups.mask_overlay(mask), np.uint8), cv2.IMREAD_UNCHANGED)
    assert bgra.shape == (48, 64, 4)
    np.testing.assert_array_equal(bgra[..., 3] > 0, mask)
    assert tuple(bgra[15, 35, 2::-1]) == groups.FOREGROUND and not bgra[~mask].any()


@pytest.fixture(scope="module")
def rrds(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("groups-rrd")
    out = {}
    for name in ("png", "again", "full"):
        out[name] = folder / f"{name}.rrd"
    for name in ("png", "again"):
        replay(ReplayRequest(log=LOG, tracker="groups", rrd=out[name]))
    assert main(["replay", str(LOG), "--tracker", "groups", "--rrd", str(out["full"]), "--rrd-full", "--quiet"]) == 0
    return out


def _components(path: Path) -> dict[str, set[str]]:
    found: dict[str, set[str]] = {}
    for entity, component in rrd_cells(path):
        found.setdefault(entity, set()).add(component.split(":")[0])
    return found


def test_masks_and_disparity_are_png_by_default_and_raw_when_full(rrds: dict[str, Path]) -> None:
    png, full = _components(rrds["png"]), _components(rrds["full"])
    root = "/trackers/groups"
    for side in ("left", "right"):
        assert "EncodedImage" in png[f"{root}/foreground/{side}"] and "SegmentationImage" not in png[f"{root}/foreground/{side}"]
        assert "SegmentationImage" in full[f"{root}/foreground/{side}"]
    assert "EncodedImage" in png[f"{root}/disparity"] and "Image" in full[f"{root}/disparity"]
    assert f"{root}/right/image" not in png and f"{root}/right/image" not in full  # the sink sends camera/right
    assert "Image" in png["/camera/right"]


def test_the_png_disparity_holds_the_raw_pixels(rrds: dict[str, Path]) -> None:
    png, full = rrd_cells(rrds["png"]), rrd_cells(rrds["full"])
    blobs = png[("/trackers/groups/disparity", "EncodedImage:blob")]
    buffers = full[("/trackers/groups/disparity", "Image:buffer")]
    assert blobs.keys() == buffers.keys() and len(blobs) > 5
    for frame in sorted(blobs)[:: max(1, len(blobs) // 5)]:
        decoded = cv2.imdecode(_bytes(blobs[frame][0]), cv2.IMREAD_UNCHANGED)
        np.testing.assert_array_equal(decoded.reshape(-1), _bytes(buffers[frame][0]))


def _bytes(cell: pa.Array) -> np.ndarray:
    """An image cell's bytes (a list of lists of uint8 in the Arrow column)."""
    while pa.types.is_list(cell.type) or pa.types.is_large_list(cell.type):
        cell = cell.flatten()
    return cell.to_numpy(zero_copy_only=False).astype(np.uint8)


def test_the_default_is_deterministic(rrds: dict[str, Path]) -> None:
    assert rrd_digest(rrds["png"]) == rrd_digest(rrds["again"]) != rrd_digest(rrds["full"])
