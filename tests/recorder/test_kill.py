"""A recording killed with SIGKILL keeps every flushed chunk, and recover salvages them."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import pytest
from mcap.reader import make_reader

from trackreplay.recorder.recover import recover
from trackreplay.recorder.sources.images import list_images

ROOT = Path(__file__).resolve().parents[2]

# The real recorder, with the image source slowed down so the kill lands mid-recording.
CHILD = """
import sys, time
import trackreplay.recorder.record as r
original = r.read_images
def slow(*args, **kwargs):
    for frame in original(*args, **kwargs):
        time.sleep(0.01)
        yield frame
r.read_images = slow
r.record(sys.argv[1], images=sys.argv[2], fps=30, flush_every=4, quiet=True)
"""


def count_messages(path: Path) -> int:
    with open(path, "rb") as fh:
        reader = make_reader(fh)
        assert reader.get_summary() is not None
        n = 0
        for _, channel, msg in reader.iter_messages(log_time_order=True):
            assert channel.topic == "/camera/image"
            assert msg.log_time == round(n * 1e9 / 30)
            n += 1
    return n


@pytest.mark.slow
def test_sigkill_mid_recording_then_recover(tmp_path):
    folder = tmp_path / "img"
    folder.mkdir()
    for i in range(300):
        img = np.full((24, 32, 3), i % 256, np.uint8)
        img[:, : i % 32] = 255 - i % 256
        cv2.imwrite(str(folder / f"f{i}.jpg"), img)
    files = list_images(folder)
    out = tmp_path / "live.mcap"
    partial = tmp_path / "live.mcap.partial"  # the name a log has until it is complete
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    child = subprocess.Popen([sys.executable, "-c", CHILD, str(out), str(folder)], env=env, cwd=ROOT)
    try:
        deadline = time.monotonic() + 20
        while not (partial.exists() and partial.stat().st_size > 8000):
            assert child.poll() is None, "the recording ended before it could be killed"
            assert time.monotonic() < deadline, "the recording never flushed"
            time.sleep(0.02)
        snapshot = tmp_path / "snapshot.mcap"
        shutil.copyfile(partial, snapshot)  # what was certainly flushed before the kill
        child.send_signal(signal.SIGKILL)
        child.wait(timeout=10)
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()
    assert child.returncode == -signal.SIGKILL
    assert not out.exists()  # no half log under the final name

    flushed = recover(snapshot, tmp_path / "flushed.mcap")
    report = recover(partial, tmp_path / "fixed.mcap")
    assert not report.complete and report.error
    assert 0 < flushed.messages_saved <= report.messages_saved < len(files)
    assert count_messages(tmp_path / "fixed.mcap") == report.messages_saved

    # Every recovered image decodes and is the source file's bytes, in order.
    with open(tmp_path / "fixed.mcap", "rb") as fh:
        from mcap_protobuf.decoder import DecoderFactory

        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        for i, (_, _, _, pb) in enumerate(reader.iter_decoded_messages(log_time_order=True)):
            assert pb.data == files[i].read_bytes()
            assert cv2.imdecode(np.frombuffer(pb.data, np.uint8), cv2.IMREAD_COLOR).shape == (24, 32, 3)
