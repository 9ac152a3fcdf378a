"""Our logs import in Rerun: ``rerun mcap convert`` (the CLI in rerun-sdk) keeps every topic.

The CLI exits 0 even when it rejects a schema (it then writes an empty .rrd), so the tests read
what was written: each topic's entity, its decoded columns and its number of rows.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from collections import defaultdict
from pathlib import Path

import cv2
import numpy as np
import pytest

from trackreplay.recorder.writer import LogWriter
from trackreplay.schemas import messages as m
from trackreplay.schemas import records as r
from trackreplay.schemas import topics as T

GOLDEN = Path(__file__).resolve().parents[1] / "golden"


def _rerun_cli() -> str | None:
    local = Path(sys.executable).parent / "rerun"
    return str(local) if local.exists() else shutil.which("rerun")


RERUN = _rerun_cli()
pytestmark = pytest.mark.skipif(RERUN is None, reason="the rerun CLI (rerun-sdk) is not installed")


@pytest.fixture(scope="module")
def rerun_env(tmp_path_factory) -> dict[str, str]:
    home = tmp_path_factory.mktemp("rerun-home")
    env = dict(os.environ, HOME=str(home), XDG_CONFIG_HOME=str(home / "config"),
               XDG_DATA_HOME=str(home / "data"), XDG_CACHE_HOME=str(home / "cache"))
    subprocess.run([RERUN, "analytics", "disable"], env=env, capture_output=True, timeout=60)
    return env


def convert(log: Path, out: Path, env: dict[str, str]) -> dict[str, dict[str, int]]:
    """``{entity path: {column: rows}}`` of what ``rerun mcap convert`` wrote for ``log``."""
    from rerun.chunk import RrdReader

    proc = subprocess.run([RERUN, "mcap", "convert", str(log), "-o", str(out)], env=env,
                          capture_output=True, text=True, timeout=120)
    assert out.exists(), proc.stderr
    columns: dict[str, dict[str, int]] = defaultdict(lambda: defaultdict(int))
    for chunk in RrdReader(str(out)).stream():
        for name in chunk.to_record_batch().schema.names:
            columns[chunk.entity_path][name] += chunk.num_rows
    assert "Failed to load" not in proc.stderr, proc.stderr
    return columns


def _all_schemas_log(path: Path, frames: int = 4) -> None:
    """A small log with an image per frame and every schema of ours on its default topic."""
    w = LogWriter(path)
    lens = r.LensTable(64, 48, (r.LensEntry(0, 0, 50, 50, 32, 24), r.LensEntry(10, 0, 100, 100, 32, 24)), (0.0, 0.0, 2.0))
    w.write(T.PTZ_LENS_TABLE, lens.to_pb(0), 0)
    plane = m.GroundPlane(timestamp=r.timestamp(0), width=64, height=48, image_to_ground=list(np.eye(3).ravel()),
                          camera_ground_x=0.0, camera_ground_y=0.0, camera_height=3.0, cx=32.0)
    w.write(T.CAMERA_GROUND_PLANE, plane, 0)
    w.write(T.ANNOTATIONS_INIT, r.init_annotations_pb([r.InitRegion(0, 0, 20, 20, 6, 6, "target")], 0), 0)
    for i in range(frames):
        t = i * 33_333_333
        image = np.full((48, 64, 3), 40 * i, np.uint8)
        ok, jpeg = cv2.imencode(".jpg", image)
        w.write(T.CAMERA_IMAGE, m.CompressedImage(timestamp=r.timestamp(t), frame_id="camera", format="jpeg",
                                                  data=jpeg.tobytes()), t)
        w.write(T.PTZ_ENCODERS, r.PtzReading(t, 1.0 * i, -2.0, 5.0, 0.0).to_pb(), t)
        gt = r.GroundTruthFrame(i, t, (r.GroundTruthObject(1, x=20.0 + i, y=20.0, w=6, h=6, X=1.0, Y=2.0, Z=0.5,
                                                           vx=1.0, vy=0.0, visible=True, group=0),))
        w.write(T.GROUNDTRUTH, gt.to_pb(), t)
    w.close()


def _message_rows(columns: dict[str, int]) -> int:
    return max((n for name, n in columns.items() if name.endswith(":message")), default=0)


def test_every_schema_of_ours_imports(tmp_path: Path, rerun_env) -> None:
    log = tmp_path / "all.mcap"
    _all_schemas_log(log)
    got = convert(log, tmp_path / "all.rrd", rerun_env)
    assert got[T.CAMERA_IMAGE]["EncodedImage:blob"] == 4
    expected = {T.GROUNDTRUTH: ("trackreplay.GroundTruthFrame", 4), T.PTZ_ENCODERS: ("trackreplay.PtzEncoders", 4),
                T.ANNOTATIONS_INIT: ("trackreplay.InitAnnotations", 1), T.PTZ_LENS_TABLE: ("trackreplay.LensTable", 1),
                T.CAMERA_GROUND_PLANE: ("trackreplay.GroundPlane", 1)}
    for topic, (schema, rows) in expected.items():
        assert got[topic][f"{schema}:message"] == rows, (topic, dict(got[topic]))


@pytest.mark.parametrize("name", ["golf-teeshot-640x360.mcap", "flow-sim1-24f.mcap"])
def test_synthetic_golden_logs_import(tmp_path: Path, rerun_env, name: str) -> None:
    from trackreplay.replay.log.reader import LogReader

    log = GOLDEN / name
    topics = LogReader(log).topics()
    got = convert(log, tmp_path / "out.rrd", rerun_env)
    images = topics[T.CAMERA_IMAGE].count
    assert got[T.CAMERA_IMAGE]["EncodedImage:blob"] == images > 0
    assert _message_rows(got[T.GROUNDTRUTH]) == topics[T.GROUNDTRUTH].count == images
    assert _message_rows(got[T.ANNOTATIONS_INIT]) == topics[T.ANNOTATIONS_INIT].count >= 1
    if T.PTZ_ENCODERS in topics:
        assert _message_rows(got[T.PTZ_ENCODERS]) == topics[T.PTZ_ENCODERS].count > 0
        assert _message_rows(got[T.PTZ_LENS_TABLE]) == 1
