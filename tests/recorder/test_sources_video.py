"""Video source: frame times from fps, encodings, errors."""

from __future__ import annotations

import numpy as np
import pytest

from trackreplay.recorder.record import record
from trackreplay.recorder.sources.base import FrameClock
from trackreplay.recorder.sources.video import read_video
from trackreplay.schemas.errors import SourceError


def test_video_frames_timed_by_file_fps_and_lossless_png(tmp_path, make_video, log_messages, decode_image):
    video = make_video(tmp_path / "v.avi", 8, fps=20.0)
    report = record(tmp_path / "out.mcap", video=video, encoding="png", quiet=True)
    assert report.frames == 8 and report.topics == {"/camera/image": 8}
    msgs = log_messages(tmp_path / "out.mcap")
    assert [m.log_time for m in msgs] == [i * 50_000_000 for i in range(8)]
    source = [f.pixels for f in read_video(video, FrameClock(fps=20.0))]
    for m, pixels in zip(msgs, source):
        assert m.schema == "foxglove.CompressedImage" and m.pb.format == "png"
        assert np.array_equal(decode_image(m.pb, m.schema), pixels)


@pytest.mark.parametrize("encoding, schema", [("jpeg", "foxglove.CompressedImage"), ("raw", "foxglove.RawImage")])
def test_video_fps_override_t0_and_encodings(tmp_path, make_video, log_messages, decode_image, encoding, schema):
    video = make_video(tmp_path / "v.avi", 5, fps=25.0, fourcc="MJPG")
    record(tmp_path / "out.mcap", video=video, fps=10.0, t0_ns=1_000, encoding=encoding, quiet=True)
    msgs = log_messages(tmp_path / "out.mcap")
    assert [m.log_time for m in msgs] == [1_000 + i * 100_000_000 for i in range(5)]
    assert {m.schema for m in msgs} == {schema}
    assert decode_image(msgs[0].pb, schema).shape == (48, 64, 3)


def test_video_with_timestamps_file(tmp_path, make_video, log_messages):
    video = make_video(tmp_path / "v.avi", 4)
    ts = tmp_path / "ts.txt"
    ts.write_text("# capture times\n100\n250\n\n400\n900\n")
    record(tmp_path / "out.mcap", video=video, timestamps=ts, quiet=True)
    assert [m.log_time for m in log_messages(tmp_path / "out.mcap")] == [100, 250, 400, 900]


def test_video_timestamp_count_mismatch_names_file_and_removes_output(tmp_path, make_video):
    video = make_video(tmp_path / "v.avi", 4)
    ts = tmp_path / "ts.txt"
    ts.write_text("1\n2\n3\n")
    with pytest.raises(SourceError, match=r"ts\.txt has 3 timestamps"):
        record(tmp_path / "out.mcap", video=video, timestamps=ts, quiet=True)
    assert not (tmp_path / "out.mcap").exists()


def test_missing_and_unreadable_video(tmp_path):
    with pytest.raises(SourceError, match=r"video .*nope\.avi does not exist"):
        record(tmp_path / "out.mcap", video=tmp_path / "nope.avi", quiet=True)
    junk = tmp_path / "junk.avi"
    junk.write_bytes(b"not a video at all" * 10)
    with pytest.raises(SourceError, match=r"junk\.avi"):
        record(tmp_path / "out.mcap", video=junk, fps=10, quiet=True)
    assert not (tmp_path / "out.mcap").exists()


def test_exactly_one_image_source(tmp_path, make_video):
    with pytest.raises(SourceError, match="exactly one image source"):
        record(tmp_path / "out.mcap", quiet=True)
    video = make_video(tmp_path / "v.avi", 2)
    with pytest.raises(SourceError, match="exactly one image source"):
        record(tmp_path / "out.mcap", video=video, images=tmp_path, quiet=True)


def test_a_truncated_video_is_recorded_up_to_the_damage_and_says_so(tmp_path, make_video, log_messages):
    """A review cut a video to half its bytes: `record` wrote the first half as the whole clip, exit 0.
    Now every readable frame is kept (a valid log), a warning names the shortfall and the CLI exits 7."""
    from trackreplay.replay.cli.main import main as cli

    video = make_video(tmp_path / "v.avi", 40, fps=20.0, size=(160, 120), fourcc="MJPG")
    cut = tmp_path / "cut.avi"
    cut.write_bytes(video.read_bytes()[: video.stat().st_size // 2])
    report = record(tmp_path / "out.mcap", video=cut, quiet=True)
    assert report.frames_lost and 5 < report.frames < 35
    assert any("decoding stopped after frame" in w and "of the 40 the file declares" in w for w in report.warnings)
    msgs = log_messages(tmp_path / "out.mcap")
    assert [m.log_time for m in msgs] == [i * 50_000_000 for i in range(report.frames)]  # the frames before it, on time
    assert cli(["record", str(tmp_path / "cli.mcap"), "--video", str(cut), "--quiet"]) == 7
    whole = record(tmp_path / "whole.mcap", video=video, quiet=True)
    assert whole.frames == 40 and not whole.frames_lost and whole.warnings == ()
