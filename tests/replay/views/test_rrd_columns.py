"""The Rerun sink sends columns (deferred archetypes, images from a template) holding exactly what
row-by-row ``rr.log`` would; ``trackreplay diff`` on .rrd files."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
import rerun as rr

from trackreplay.replay.cli.main import main
from trackreplay.replay.analysis.diff_rrd import diff_rrd
from trackreplay.replay.core.engine import ReplayRequest, ReplayStep, iter_steps, replay
from trackreplay.replay.views.rerun_sink import CAMERA, FrameLogger, RerunSink, _components, _Pixels, rrd_digest

GOLDEN = Path(__file__).resolve().parents[2] / "golden"


@pytest.mark.parametrize("tracker, log", [("flow", "flow-sim1-24f.mcap"), ("golf", "golf-teeshot-640x360.mcap")])
def test_columns_hold_what_row_by_row_logging_holds(tracker: str, log: str, tmp_path: Path) -> None:
    columns, rows = tmp_path / "columns.rrd", tmp_path / "rows.rrd"
    replay(ReplayRequest(log=GOLDEN / log, tracker=tracker, rrd=columns, truth=False))  # the view's rows only
    steps = iter_steps(ReplayRequest(log=GOLDEN / log, tracker=tracker))
    _log_rows(rows, tracker, steps, steps.spec.view)
    result = diff_rrd(columns, rows)
    assert result.identical, result.report()


def _log_rows(path: Path, tracker: str, steps, view) -> None:
    """The old way: one rr.log per archetype, on a bare stream."""
    rec = rr.RecordingStream("trackreplay", recording_id="rows", send_properties=False)
    rec.set_log_time_enabled(False)
    rec.save(str(path))
    for step in steps:
        frame = step.frame
        rec.set_time("frame", sequence=frame.index)
        rec.set_time("log_time", timestamp=np.datetime64(frame.t_ns, "ns"))
        media = "image/jpeg" if frame.encoding == "jpeg" else "image/png"
        rec.log(CAMERA, rr.EncodedImage(contents=frame.encoded, media_type=media))
        view.log(rec, tracker, frame, step.intermediates, list(step.states))
    rec.flush()
    rec.disconnect()


def test_flow_frames_built_in_blocks_hold_what_row_by_row_logging_holds(tmp_path: Path,
                                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    """The flow view keeps whole frames and builds their rows ``BATCH_FRAMES`` at a time, frames with
    nothing to show among them (no centroid, no accepted flow, a non-finite filter)."""
    from trackreplay.replay.views import rerun_sink

    monkeypatch.setattr(rerun_sink, "BATCH_FRAMES", 5)
    steps = iter_steps(ReplayRequest(log=GOLDEN / "flow-sim1-24f.mcap", tracker="flow"))
    view, edited = steps.spec.view, []
    for k, step in enumerate(steps):
        inter = step.intermediates
        if k in (6, 7, 11):
            inter = dataclasses.replace(inter, centroid=np.full(2, np.nan), flow_u=np.full_like(inter.flow_u, np.nan))
        if k in (12, 13):
            inter = dataclasses.replace(inter, kalman_P=np.full_like(inter.kalman_P, np.nan))
        edited.append(ReplayStep(step.frame, step.states, inter))
    columns, rows = tmp_path / "columns.rrd", tmp_path / "rows.rrd"
    sink = RerunSink(columns, "flow-edited", view.blueprint("flow"))
    for step in edited:
        sink.begin_frame(step.frame)
        view.log(sink.logger, "flow", step.frame, step.intermediates, list(step.states))
    sink.close()
    _log_rows(rows, "flow", edited, view)
    result = diff_rrd(columns, rows)
    assert result.identical, result.report()


def test_a_batch_built_in_blocks_is_sent_in_the_same_chunks(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Building a batch's rows during the replay, a few frames at a time, leaves the chunks as they were."""
    from trackreplay.replay.views import rerun_sink

    log = GOLDEN / "flow-sim1-24f.mcap"
    whole, blocks = tmp_path / "whole.rrd", tmp_path / "blocks.rrd"
    replay(ReplayRequest(log=log, tracker="flow", rrd=whole))
    monkeypatch.setattr(rerun_sink, "BATCH_FRAMES", 3)
    replay(ReplayRequest(log=log, tracker="flow", rrd=blocks))
    assert rrd_digest(whole) == rrd_digest(blocks)


def test_images_from_a_template_equal_images_built_each_time() -> None:
    rng = np.random.default_rng(0)
    logger = FrameLogger(rr.RecordingStream("t"))
    cases = [(rr.Image, lambda: rng.integers(0, 255, (40, 30, 3), dtype=np.uint8)[5:35, 2:20], {"color_model": "BGR"}),
             (rr.Image, lambda: rng.integers(0, 255, (16, 16), dtype=np.uint8), {"color_model": "L"}),
             (rr.SegmentationImage, lambda: rng.integers(0, 3, (9, 7), dtype=np.uint8), {"opacity": 0.5}),
             (rr.EncodedImage, lambda: rng.bytes(1000), {"media_type": "image/jpeg"})]
    for archetype, make, params in cases:
        for k in range(3):  # the first builds the template, the others reuse it
            data = make()
            logger.set_frame(k, k)
            logger.image("p", archetype, data, **params)
            got = [(d, a.arrow() if isinstance(a, _Pixels) else a) for d, a in logger._rows["p"][-1][2]]
            built = archetype(contents=data, **params) if archetype is rr.EncodedImage else archetype(data, **params)
            ref = _components([built])
            assert [str(d) for d, _ in got] == [str(d) for d, _ in ref]
            assert all(a.equals(b) for (_, a), (_, b) in zip(got, ref))
        logger._rows.clear()


def test_diff_of_rrd_files(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    golf = GOLDEN / "golf-teeshot-640x360.mcap"
    a, a2, b = tmp_path / "a.rrd", tmp_path / "a2.rrd", tmp_path / "b.rrd"
    for path, seed in ((a, 0), (a2, 0), (b, 1)):
        replay(ReplayRequest(log=golf, tracker="golf", seed=seed, rrd=path))
    assert main(["diff", str(a), str(a2)]) == 0
    assert capsys.readouterr().out.startswith("identical: 60 frames")
    assert main(["diff", str(a), str(b)]) == 1
    first = capsys.readouterr().out.splitlines()[0]
    assert first.startswith("frame 0: /trackers/golf/particles Points2D:") and "max |Δ|" in first
    assert main(["diff", str(a), str(golf)]) == 2


def test_an_image_path_sent_early_holds_the_same_rows(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """An image path past ``IMAGE_FLUSH_BYTES`` goes out in its own, smaller chunks: the same content."""
    from trackreplay.replay.views import rerun_sink

    log = GOLDEN / "flow-sim1-24f.mcap"
    whole, early = tmp_path / "whole.rrd", tmp_path / "early.rrd"
    replay(ReplayRequest(log=log, tracker="flow", rrd=whole))
    monkeypatch.setattr(rerun_sink, "IMAGE_FLUSH_BYTES", 20_000)  # a chunk every frame or two
    replay(ReplayRequest(log=log, tracker="flow", rrd=early))
    result = diff_rrd(whole, early)
    assert result.identical, result.report()


def test_rows_of_scalars_split_into_series_in_frame_order() -> None:
    """``FrameLogger.scalars`` rows become each path's series; a non-finite value is skipped (as
    ``parts.scalar`` skips it) and a path also given point by point stays in frame order."""
    logger = FrameLogger(rr.RecordingStream("t"))
    for k in range(4):
        logger.set_frame(k, 10 * k)
        if k % 2:
            logger.scalars(("p", "q"), np.array([float(k), np.nan if k == 3 else -k]))
        else:
            logger.scalar("p", 100.0 + k)
    logger._split_series_rows()
    assert logger._series["p"] == ([0, 1, 2, 3], [0, 10, 20, 30], [100.0, 1.0, 102.0, 3.0])
    assert logger._series["q"] == ([1], [10], [-1.0])


def test_a_block_build_cut_short_is_not_built_again_at_the_flush(monkeypatch: pytest.MonkeyPatch) -> None:
    """A review: a Ctrl-C inside a block's build left its records queued, and the flush in the replay's
    `finally` built them again: those frames' rows twice in the kept .rrd."""
    import trackreplay.replay.views.rerun_sink as sink

    monkeypatch.setattr(sink, "BATCH_FRAMES", 2)
    logger = FrameLogger(rr.RecordingStream("t"))
    built: list[list[int]] = []

    def build(rec, records):
        built.append([r[0] for r in records])
        if len(built) == 1:
            raise KeyboardInterrupt

    logger.set_frame(0, 0)
    logger.batch(build, "a", 1)
    logger.set_frame(1, 1)
    with pytest.raises(KeyboardInterrupt):
        logger.batch(build, "b", 1)
    logger.flush()
    assert built == [[0, 1]]  # not [[0, 1], [0, 1]]


def test_a_flush_cut_short_does_not_send_a_path_twice(monkeypatch: pytest.MonkeyPatch) -> None:
    """A review: the flush cleared its buffers only after sending every path, so a Ctrl-C during it left
    the paths already sent queued, and the flush in the replay's `finally` sent them again."""
    import trackreplay.replay.views.rerun_sink as sink

    logger = FrameLogger(rr.RecordingStream("t"))
    for frame in range(2):
        logger.set_frame(frame, frame)
        for path in ("a", "b", "c"):
            logger.entity_rows(path, rr.Clear(recursive=False), [frame], [frame])
    sent: list[str] = []

    def send(rec, path, timelines, rows):
        sent.append(path)
        if len(sent) == 2:
            raise KeyboardInterrupt

    monkeypatch.setattr(sink, "_send", send)
    with pytest.raises(KeyboardInterrupt):
        logger.flush()
    logger.flush()
    assert sent == ["a", "b", "c"]  # not a, b, a, b, c
