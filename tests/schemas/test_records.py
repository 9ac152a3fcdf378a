import importlib.util
from pathlib import Path

import pytest

from trackreplay.schemas import records as r


def test_ground_truth_absent_is_not_zero() -> None:
    obj = r.GroundTruthObject(7, x=0.0, visible=False)
    back = r.GroundTruthObject.from_pb(obj.to_pb())
    assert back == obj
    assert back.y is None and back.X is None and back.x == 0.0


def test_round_trips() -> None:
    ptz = r.PtzReading(1_500_000_123, 12.5, -3.0, 1200.0, 300.0)
    assert r.PtzReading.from_pb(ptz.to_pb()) == ptz
    lens = r.LensTable(1280, 720, (r.LensEntry(0, 0, 1000, 1000, 640, 360), r.LensEntry(10, 0, 3000, 3000, 641, 359)), (1.0, 2.0, 3.0))
    assert r.LensTable.from_pb(lens.to_pb(5)) == lens
    region = r.InitRegion(3, 99, 10.0, 20.0, 5.0, 6.0, "ball")
    assert r.InitRegion.from_pb(region.to_pb()) == region
    frame = r.GroundTruthFrame(2, 66, (r.GroundTruthObject(1, x=1.0), r.GroundTruthObject(2, group=4)))
    assert r.GroundTruthFrame.from_pb(frame.to_pb()) == frame


@pytest.mark.skipif(importlib.util.find_spec("grpc_tools") is None, reason="grpcio-tools not installed")
def test_generated_code_is_current(tmp_path: Path) -> None:
    from trackreplay.schemas.generate import GEN_DIR, generate

    for fresh in generate(tmp_path):
        assert fresh.read_bytes() == (GEN_DIR / fresh.name).read_bytes(), f"run python -m schemas.generate ({fresh.name} is stale)"
