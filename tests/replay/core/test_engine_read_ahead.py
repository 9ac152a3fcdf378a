"""The engine's read-ahead hook (TrackerSpec.read_ahead): frames spread evenly over the replayed window,
handed to the tracker before its first step; the same frames for the same log and window."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from trackreplay.recorder.image_codec import image_message
from trackreplay.recorder.writer import LogWriter
from trackreplay.replay.core import registry
from trackreplay.replay.core.engine import ReplayRequest, iter_steps, replay
from trackreplay.replay.log.frames import FrameTopics, image_times, spread_images, spread_indices
from trackreplay.replay.log.reader import LogReader
from trackreplay.schemas import topics as T
from trackreplay.schemas.errors import TrackreplayError
from trackreplay.trackers.base import READ_AHEAD_MAX, TrackerBase
from trackreplay.trackers.flow.tracker import FlowTracker

MS = 1_000_000


def _log(path: Path, frames: int = 20, raw_short: tuple[int, ...] = (), other_size: tuple[int, ...] = ()) -> Path:
    """``frames`` grey 10x8 images at 100 ms, frame k filled with k (a raw image cut short or of another
    size where asked)."""
    with LogWriter(path) as log:
        for k in range(frames):
            shape = (9, 10) if k in other_size else (8, 10)
            msg = image_message(np.full(shape, k, np.uint8), "raw" if k in raw_short else "png", k * 100 * MS)
            if k in raw_short:
                msg.data = msg.data[:-5]
            log.write(T.CAMERA_IMAGE, msg, k * 100 * MS)
    return path


def _spread(path: Path, count: int, start_ns: int | None = None, end_ns: int | None = None) -> list[tuple[int, int, int]]:
    reader = LogReader(path)
    return [(i, t, int(image[0, 0])) for i, t, image in spread_images(reader, FrameTopics.detect(reader), count,
                                                                        start_ns, end_ns)]


def test_the_middle_of_each_equal_run_is_chosen() -> None:
    assert spread_indices(list(range(12)), 4) == [1, 4, 7, 10]
    assert spread_indices(list(range(10, 20)), 5) == [11, 13, 15, 17, 19]
    assert spread_indices([3, 5, 8], 5) == [3, 5, 8]  # fewer than asked: all of them
    assert spread_indices([], 5) == [] and spread_indices([1, 2], 0) == []
    picked = spread_indices(list(range(795)), 40)
    assert len(picked) == 40 == len(set(picked)) and picked == sorted(picked) and picked[0] < 20 and picked[-1] > 775


def test_spread_images_are_the_log_s_frames_decoded_bounded_and_honour_the_window(tmp_path: Path) -> None:
    log = _log(tmp_path / "a.mcap")
    assert _spread(log, 4) == [(k, k * 100 * MS, k) for k in (2, 7, 12, 17)]  # frame k holds the value k
    assert len(_spread(log, 50)) == 20  # never more than the window holds
    # --start 0.5 s --end 1.5 s: frames 5..14 only
    assert [i for i, _, _ in _spread(log, 5, 500 * MS, 1500 * MS)] == [6, 8, 10, 12, 14]
    assert _spread(log, 3) == _spread(log, 3)  # deterministic


def test_undecodable_or_odd_sized_frames_are_left_out(tmp_path: Path) -> None:
    log = _log(tmp_path / "odd.mcap", raw_short=(7,), other_size=(12,))
    assert [i for i, _, _ in _spread(log, 4)] == [2, 17]  # 7 does not decode, 12 is 10x9 (the others 10x8)


def test_lost_frames_are_not_chosen(flow_sim1: Path, tmp_path: Path) -> None:
    from mcap.reader import make_reader

    with open(flow_sim1, "rb") as fh:
        summary = make_reader(fh).get_summary()
    chunk = sorted(summary.chunk_indexes, key=lambda c: c.chunk_start_offset)[1]
    data = bytearray(flow_sim1.read_bytes())
    data[chunk.chunk_start_offset + chunk.chunk_length // 2] ^= 0x04
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(bytes(data))
    reader = LogReader(bad)
    lost = {m.index for m in reader.messages([T.CAMERA_IMAGE]) if m.lost is not None}
    kept = [m.index for m in reader.messages([T.CAMERA_IMAGE]) if m.lost is None]
    assert lost
    got = [i for i, _, _ in spread_images(reader, FrameTopics.detect(reader), 10)]
    assert got == spread_indices(kept, 10) and not lost & set(got)


FLOW = registry.get("flow")  # (before a test patches registry.get)


def _recording(seen: list, count):
    class Recording(FlowTracker):
        def read_ahead(self, frames) -> None:
            seen.append([(i, int(image.mean() > -1)) for i, _, image in frames])

        def step(self, frame):
            seen.append(("step", frame.index))
            return super().step(frame)

    return dataclasses.replace(FLOW, tracker_cls=Recording, read_ahead=count)


def test_the_engine_hands_the_frames_before_the_first_step(short_sim: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    assert TrackerBase.read_ahead(FlowTracker.__new__(FlowTracker), iter(())) is None  # the documented no-op
    seen: list = []
    asked: list = []

    def count(config, stereo: bool) -> int:
        asked.append(stereo)
        return 4

    monkeypatch.setattr(registry, "get", lambda name: _recording(seen, count))
    steps = iter_steps(ReplayRequest(log=short_sim, tracker="flow"))
    assert asked == [False] and [i for i, _ in seen[0]] == [1, 4, 7, 10]  # 12 frames, on construction
    next(steps)
    assert seen[1] == ("step", 0)
    steps.close()
    seen.clear()
    times = image_times(LogReader(short_sim))
    t0 = LogReader(short_sim).time_range()[0]
    start_s, end_s = (times[3] - t0) / 1e9, (times[9] - t0) / 1e9  # --start/--end: frames 3..8
    steps = iter_steps(ReplayRequest(log=short_sim, tracker="flow", start_s=start_s, end_s=end_s))
    assert [i for i, _ in seen[0]] == [3, 5, 6, 8] == spread_indices(list(range(3, 9)), 4)
    assert next(steps).frame.index == 3
    steps.close()


def test_no_frames_are_read_unless_asked_and_a_count_out_of_range_is_refused(short_sim: Path,
                                                                             monkeypatch: pytest.MonkeyPatch) -> None:
    seen: list = []
    for count in (None, lambda config, stereo: 0):
        monkeypatch.setattr(registry, "get", lambda name, c=count: _recording(seen, c))
        replay(ReplayRequest(log=short_sim, tracker="flow"))
        assert all(isinstance(x, tuple) for x in seen)  # steps only
    for bad in (READ_AHEAD_MAX + 1, -1, True, 2.0):
        monkeypatch.setattr(registry, "get", lambda name, b=bad: _recording(seen, lambda config, stereo: b))
        with pytest.raises(TrackreplayError, match=f"from 0 to {READ_AHEAD_MAX}"):
            iter_steps(ReplayRequest(log=short_sim, tracker="flow"))
