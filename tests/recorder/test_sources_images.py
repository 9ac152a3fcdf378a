"""Image-folder source: natural order, bytes kept, timestamps, size and count errors."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from trackreplay.recorder.record import record
from trackreplay.recorder.sources.images import list_images
from trackreplay.schemas.errors import SourceError


def test_natural_order_and_extensions(tmp_path, make_images):
    folder = make_images(tmp_path / "img", 12, ext="png")
    (folder / "notes.txt").write_text("ignored")
    cv2.imwrite(str(folder / "frame12.BMP"), np.zeros((48, 64, 3), np.uint8))
    names = [p.name for p in list_images(folder)]
    assert names[:3] == ["frame0.png", "frame1.png", "frame2.png"]
    assert names[-3:] == ["frame10.png", "frame11.png", "frame12.BMP"]


@pytest.mark.parametrize("ext, fmt", [("jpg", "jpeg"), ("png", "png")])
def test_encoded_files_keep_their_bytes(tmp_path, make_images, log_messages, ext, fmt):
    folder = make_images(tmp_path / "img", 11, ext=ext)
    record(tmp_path / "out.mcap", images=folder, fps=30, encoding="raw", quiet=True)
    msgs = log_messages(tmp_path / "out.mcap")
    files = list_images(folder)
    assert len(msgs) == 11
    for i, (m, f) in enumerate(zip(msgs, files)):
        assert m.pb.format == fmt and m.pb.data == f.read_bytes()
        assert m.log_time == round(i * 1e9 / 30)


def test_bmp_files_are_encoded_as_asked(tmp_path, make_images, log_messages, decode_image):
    folder = make_images(tmp_path / "img", 3, ext="bmp")
    record(tmp_path / "out.mcap", images=folder, fps=5, encoding="raw", quiet=True)
    msgs = log_messages(tmp_path / "out.mcap")
    for m, f in zip(msgs, list_images(folder)):
        assert m.schema == "foxglove.RawImage"
        assert np.array_equal(decode_image(m.pb, m.schema), cv2.imread(str(f)))


def test_timestamps_file(tmp_path, make_images, log_messages):
    folder = make_images(tmp_path / "img", 3)
    ts = tmp_path / "ts.txt"
    ts.write_text("5000\n6000\n9000\n")
    record(tmp_path / "out.mcap", images=folder, timestamps=ts, quiet=True)
    assert [m.log_time for m in log_messages(tmp_path / "out.mcap")] == [5000, 6000, 9000]


def test_timestamp_count_mismatch_is_checked_before_writing(tmp_path, make_images):
    folder = make_images(tmp_path / "img", 3)
    ts = tmp_path / "ts.txt"
    ts.write_text("1\n2\n")
    with pytest.raises(SourceError, match=r"ts\.txt has 2 timestamps but .*img has 3 images"):
        record(tmp_path / "out.mcap", images=folder, timestamps=ts, quiet=True)
    assert not (tmp_path / "out.mcap").exists()


@pytest.mark.parametrize("text, match", [("1\nabc\n", r"ts\.txt:2: t_ns 'abc' is not an integer"),
                                         ("5\n5\n", r"ts\.txt:2: t_ns 5 is not after"),
                                         ("# nothing\n", "holds no timestamps")])
def test_bad_timestamps_file(tmp_path, make_images, text, match):
    folder = make_images(tmp_path / "img", 2)
    ts = tmp_path / "ts.txt"
    ts.write_text(text)
    with pytest.raises(SourceError, match=match):
        record(tmp_path / "out.mcap", images=folder, timestamps=ts, quiet=True)


def test_wrong_size_mid_sequence_names_file_and_removes_output(tmp_path, make_images):
    folder = make_images(tmp_path / "img", 5)
    cv2.imwrite(str(folder / "frame3.jpg"), np.zeros((40, 64, 3), np.uint8))
    with pytest.raises(SourceError, match=r"frame3\.jpg is 64x40 but frame0\.jpg is 64x48"):
        record(tmp_path / "out.mcap", images=folder, fps=10, quiet=True)
    assert not (tmp_path / "out.mcap").exists()


def test_corrupt_image_names_file(tmp_path, make_images):
    folder = make_images(tmp_path / "img", 3)
    (folder / "frame1.jpg").write_bytes(b"\xff\xd8\xff garbage")
    with pytest.raises(SourceError, match=r"frame1\.jpg cannot be decoded"):
        record(tmp_path / "out.mcap", images=folder, fps=10, quiet=True)


def test_empty_image_file_names_file(tmp_path, make_images):
    """A review's zero-byte 0001.jpg: OpenCV asserted inside imdecode and record exited 70 (internal error)."""
    folder = make_images(tmp_path / "img", 3)
    (folder / "frame0.jpg").write_bytes(b"")
    with pytest.raises(SourceError, match=r"image .*frame0\.jpg is empty \(0 bytes\)"):
        record(tmp_path / "out.mcap", images=folder, fps=10, quiet=True)
    assert not (tmp_path / "out.mcap").exists()


def test_folder_errors(tmp_path, make_images):
    with pytest.raises(SourceError, match=r"missing does not exist"):
        record(tmp_path / "out.mcap", images=tmp_path / "missing", fps=10, quiet=True)
    (tmp_path / "empty").mkdir()
    with pytest.raises(SourceError, match=r"empty holds no"):
        record(tmp_path / "out.mcap", images=tmp_path / "empty", fps=10, quiet=True)
    folder = make_images(tmp_path / "img", 2)
    with pytest.raises(SourceError, match="--fps or a --timestamps"):
        record(tmp_path / "out.mcap", images=folder, quiet=True)
    with pytest.raises(SourceError, match="output .* does not exist"):
        record(tmp_path / "no" / "out.mcap", images=folder, fps=1, quiet=True)
