"""The log's ground truth in a replay's .rrd: ``truth/boxes``, ``truth/points``, ``truth/world``."""

from pathlib import Path

import numpy as np
import pyarrow as pa
import pytest
import rerun.chunk as rc

from trackreplay.recorder.writer import LogWriter
from trackreplay.replay.cli.main import main
from trackreplay.replay.core.engine import ReplayRequest, replay
from trackreplay.replay.log.reader import LogReader
from trackreplay.replay.views.rerun_sink import rrd_digest
from trackreplay.replay.views.truth import SEEN, UNSEEN
from trackreplay.schemas import topics as T
from trackreplay.schemas.records import GroundTruthFrame, GroundTruthObject

GOLDEN_FLOW = Path(__file__).resolve().parents[2] / "golden" / "flow-sim1-24f.mcap"
FPS = 30


def _copy(out: Path, truth: list[GroundTruthFrame] | None) -> Path:
    """The golden flow log's images and mark, with ``truth`` as its ground truth (None: no truth topic)."""
    reader = LogReader(GOLDEN_FLOW)
    times = {}
    with LogWriter(out) as w:
        for item in reader.messages([T.CAMERA_IMAGE, T.ANNOTATIONS_INIT]):
            w.write(item.topic, item.decode(), item.log_time)
            if item.topic == T.CAMERA_IMAGE:
                times[item.index] = item.log_time
        for gt in truth or ():
            w.write(T.GROUNDTRUTH, GroundTruthFrame(gt.frame, times[gt.frame], gt.objects).to_pb(), times[gt.frame])
    return out


def _truth() -> list[GroundTruthFrame]:
    """A box on frames 0-5 (hidden on 3), a point on 2-3 (3-D on 2), an empty label on 6, nothing after."""
    frames = []
    for k in range(7):
        objects = []
        if k < 6:
            objects.append(GroundTruthObject(1, x=100.0 + k, y=80.0, w=8.0, h=6.0, visible=k != 3))
        if k in (2, 3):
            objects.append(GroundTruthObject(4, x=40.0, y=30.0, **({"X": 1.0, "Y": 2.0, "Z": 3.0} if k == 2 else {})))
        frames.append(GroundTruthFrame(k, 0, tuple(objects)))
    return frames


def _rows(rrd: Path, path: str) -> dict[int, dict[str, list]]:
    """frame -> component -> the instances logged at ``path`` on that frame."""
    out: dict[int, dict[str, list]] = {}
    for chunk in rc.RrdReader(str(rrd)).stream():
        if str(chunk.entity_path) != path:
            continue
        record = chunk.to_record_batch()
        batch = {name: record.column(name).to_pylist() for name in record.schema.names if ":" in name or name == "frame"}
        batch["log_time"] = record.column("log_time").cast(pa.int64()).to_pylist()
        for i, frame in enumerate(batch["frame"]):
            out[frame] = {name.split(":")[-1]: batch[name][i] for name in batch if name != "frame"}
    return out


def test_truth_is_in_the_rrd_at_the_replayed_frames(tmp_path: Path) -> None:
    log = _copy(tmp_path / "gt.mcap", _truth())
    rrd = tmp_path / "gt.rrd"
    replay(ReplayRequest(log=log, tracker="flow", rrd=rrd, end_s=8.5 / FPS))
    boxes = _rows(rrd, "/truth/boxes")
    assert sorted(boxes) == list(range(9))  # every replayed frame: an empty row clears the box after its last label
    assert [len(boxes[f]["centers"]) for f in range(9)] == [1, 1, 1, 1, 1, 1, 0, 0, 0]
    assert boxes[1]["centers"] == [pytest.approx([101.0, 80.0])]
    assert boxes[1]["half_sizes"] == [pytest.approx([4.0, 3.0])]
    assert boxes[1]["labels"] == ["truth 1"]
    rgba = lambda c: (c[0] << 24) | (c[1] << 16) | (c[2] << 8) | 255  # noqa: E731  (Rerun's packed colour)
    assert boxes[2]["colors"] == [rgba(SEEN)] and boxes[3]["colors"] == [rgba(UNSEEN)]
    points = _rows(rrd, "/truth/points")
    assert [len(points[f]["positions"]) for f in range(9)] == [0, 0, 1, 1, 0, 0, 0, 0, 0]
    assert points[2]["labels"] == ["truth 4"]
    world = _rows(rrd, "/truth/world")
    assert [len(world[f]["positions"]) for f in range(9)] == [0, 0, 1, 0, 0, 0, 0, 0, 0]
    assert world[2]["positions"] == [pytest.approx([1.0, 2.0, 3.0])]
    camera = _rows(rrd, "/camera/image")
    assert {f: r["log_time"] for f, r in camera.items()} == {f: r["log_time"] for f, r in boxes.items()}  # same times
    layout = rc.RrdReader(str(rrd))
    assert layout.blueprints()  # the layout still goes with it (the camera view lists truth/boxes, truth/points)


def test_a_window_sends_only_its_frames_truth(tmp_path: Path) -> None:
    log = _copy(tmp_path / "gt.mcap", _truth())
    rrd = tmp_path / "w.rrd"
    replay(ReplayRequest(log=log, tracker="flow", rrd=rrd, start_s=2.5 / FPS, end_s=5.5 / FPS))
    assert sorted(_rows(rrd, "/truth/boxes")) == [3, 4, 5]


def test_without_truth_the_rrd_is_what_it_was(tmp_path: Path) -> None:
    """A log without truth, and --no-truth on a log with it, write the same content (the tracker's
    chunks do not move when truth is sent beside them)."""
    bare = _copy(tmp_path / "bare.mcap", None)
    labelled = _copy(tmp_path / "gt.mcap", _truth())
    end = 6.5 / FPS
    replay(ReplayRequest(log=bare, tracker="flow", rrd=tmp_path / "bare.rrd", end_s=end))
    assert main(["replay", str(labelled), "--tracker", "flow", "--rrd", str(tmp_path / "off.rrd"), "--no-truth",
                 "--end", str(end), "--quiet"]) == 0
    replay(ReplayRequest(log=labelled, tracker="flow", rrd=tmp_path / "on.rrd", end_s=end))
    assert rrd_digest(tmp_path / "bare.rrd") == rrd_digest(tmp_path / "off.rrd")
    assert not _rows(tmp_path / "off.rrd", "/truth/boxes")
    on = {str(c.entity_path) for c in rc.RrdReader(str(tmp_path / "on.rrd")).stream()}
    off = {str(c.entity_path) for c in rc.RrdReader(str(tmp_path / "off.rrd")).stream()}
    assert on - off == {"/truth/boxes", "/truth/points", "/truth/world"}


def test_truth_blocks_hold_what_one_block_holds(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Sent every few frames (what a live viewer sees during the replay) or at the end: the same rows."""
    import trackreplay.replay.views.truth as truth

    log = _copy(tmp_path / "gt.mcap", _truth())
    replay(ReplayRequest(log=log, tracker="flow", rrd=tmp_path / "one.rrd", end_s=8.5 / FPS))
    monkeypatch.setattr(truth, "BLOCK_FRAMES", 2)
    replay(ReplayRequest(log=log, tracker="flow", rrd=tmp_path / "many.rrd", end_s=8.5 / FPS))
    for path in ("/truth/boxes", "/truth/points", "/truth/world"):
        a, b = _rows(tmp_path / "one.rrd", path), _rows(tmp_path / "many.rrd", path)
        assert a == b and len(a) == 9
    chunks = [c for c in rc.RrdReader(str(tmp_path / "many.rrd")).stream() if str(c.entity_path) == "/truth/boxes"]
    assert len(chunks) == 5
    assert np.all(np.diff([c.to_record_batch().column("frame")[0].as_py() for c in chunks]) == 2)


def test_a_truth_that_cannot_be_read_is_left_out_with_a_warning(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                                 capsys: pytest.CaptureFixture) -> None:
    """The replay does not need the truth: a damaged one costs the .rrd its truth/ entities, not the replay."""
    from trackreplay.replay.core import engine
    from trackreplay.schemas.errors import LogError

    def damaged(reader):
        raise LogError(f"{reader.path}: message 3 on topic /groundtruth/objects is lost (damaged chunk)")

    monkeypatch.setattr(engine, "read_groundtruth", damaged)
    log = _copy(tmp_path / "gt.mcap", _truth())
    result = replay(ReplayRequest(log=log, tracker="flow", rrd=tmp_path / "d.rrd", end_s=3.5 / FPS))
    assert result.frames == 4
    assert "ground truth is left out of the Rerun stream" in capsys.readouterr().err
    assert not _rows(tmp_path / "d.rrd", "/truth/boxes") and _rows(tmp_path / "d.rrd", "/camera/image")
