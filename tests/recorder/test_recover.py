"""Salvaging truncated and damaged logs."""

from __future__ import annotations

import argparse

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap.records import Chunk, Message
from mcap.stream_reader import StreamReader, breakup_chunk

from trackreplay.recorder.image_codec import image_message
from trackreplay.recorder.recover import recover
from trackreplay.recorder.writer import LogWriter
from trackreplay.replay.cli.commands import recover as recover_cmd
from trackreplay.schemas.errors import LogError
from trackreplay.schemas.records import PtzReading


@pytest.fixture
def intact(tmp_path):
    """60 messages on two topics in chunks of 7, plus metadata and an attachment."""
    path = tmp_path / "intact.mcap"
    rng = np.random.default_rng(0)
    with LogWriter(path, flush_every=7) as log:
        log.add_metadata("source", {"camera": "test"})
        for i in range(30):
            t = i * 10_000_000
            log.write("/camera/image", image_message(rng.integers(0, 255, (24, 32, 3), dtype=np.uint8), "png", t), t)
            log.write("/ptz/encoders", PtzReading(t, i, 0, 1, 2).to_pb(), t)
        log.add_attachment("lens.csv", b"0,0,1,1,0,0\n", "text/csv")
    return path


def messages_of(path):
    with open(path, "rb") as fh:
        reader = make_reader(fh)
        assert reader.get_summary() is not None
        return [(ch.topic, schema.name, m.log_time, m.sequence, m.data) for schema, ch, m in reader.iter_messages(log_time_order=False)]


def complete_chunk_counts(path):
    """(end offset, message count) of each chunk, from the intact file's chunk index."""
    with open(path, "rb") as fh:
        summary = make_reader(fh).get_summary()
        out = []
        for ci in sorted(summary.chunk_indexes, key=lambda c: c.chunk_start_offset):
            fh.seek(ci.chunk_start_offset)
            chunk = next(StreamReader(fh, skip_magic=True, emit_chunks=True).records)
            assert isinstance(chunk, Chunk)
            out.append((ci.chunk_start_offset + ci.chunk_length, sum(isinstance(r, Message) for r in breakup_chunk(chunk))))
        return out


def chunk_starts(path):
    with open(path, "rb") as fh:
        return sorted(ci.chunk_start_offset for ci in make_reader(fh).get_summary().chunk_indexes)


def test_intact_log_is_copied_completely(intact, tmp_path):
    report = recover(intact, tmp_path / "copy.mcap")
    assert report.complete and report.error is None
    assert report.messages_saved == 60 and report.attachments_saved == 1 and report.metadata_saved == 2  # + provenance
    assert messages_of(tmp_path / "copy.mcap") == messages_of(intact)
    with open(tmp_path / "copy.mcap", "rb") as fh:
        reader = make_reader(fh)
        assert [a.name for a in reader.iter_attachments()] == ["lens.csv"]
    with open(tmp_path / "copy.mcap", "rb") as fh:
        metadata = [(m.name, m.metadata) for m in make_reader(fh).iter_metadata()]
    with open(intact, "rb") as fh:  # the source's records as they were, then recover's own provenance
        assert metadata[:-1] == [(m.name, m.metadata) for m in make_reader(fh).iter_metadata()]
    assert [name for name, _ in metadata] == ["trackreplay.provenance", "source", "trackreplay.provenance"]
    assert metadata[-1][1]["source.log"].startswith("intact.mcap sha256:")


def test_truncated_copies_keep_every_complete_chunk(intact, tmp_path):
    data = intact.read_bytes()
    chunks = complete_chunk_counts(intact)
    assert len(chunks) >= 8
    original = messages_of(intact)
    mid_first = (chunks[0][0] + 40)
    cuts = [20, mid_first, chunks[2][0], chunks[2][0] + 3, (chunks[4][0] + chunks[5][0]) // 2, len(data) - 30, len(data) - 1]
    for cut in cuts:
        broken, out = tmp_path / f"cut{cut}.mcap", tmp_path / f"fixed{cut}.mcap"
        broken.write_bytes(data[:cut])
        report = recover(broken, out)
        expected = sum(n for end, n in chunks if end <= cut)
        assert not report.complete and report.error, cut
        assert report.messages_saved == expected, cut
        assert messages_of(out) == original[:expected], cut


def test_not_mcap_writes_nothing(tmp_path):
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(b"PK\x03\x04 definitely a zip" * 4)
    with pytest.raises(LogError, match=r"junk\.mcap is not an MCAP file"):
        recover(junk, tmp_path / "out.mcap")
    assert not (tmp_path / "out.mcap").exists()
    (tmp_path / "empty.mcap").write_bytes(b"")
    with pytest.raises(LogError, match=r"empty\.mcap is not an MCAP file"):
        recover(tmp_path / "empty.mcap", tmp_path / "out.mcap")
    with pytest.raises(LogError, match=r"gone\.mcap does not exist"):
        recover(tmp_path / "gone.mcap", tmp_path / "out.mcap")


def test_recover_refuses_to_overwrite_its_input(intact):
    with pytest.raises(LogError, match="new output path"):
        recover(intact, intact)


def test_damaged_chunk_costs_only_that_chunk(intact, tmp_path):
    chunks = complete_chunk_counts(intact)
    original = messages_of(intact)
    data = bytearray(intact.read_bytes())
    pos = (chunks[2][0] + chunks[3][0]) // 2  # inside the fourth chunk
    data[pos:pos + 8] = b"\x00" * 8
    (tmp_path / "bad.mcap").write_bytes(bytes(data))
    report = recover(tmp_path / "bad.mcap", tmp_path / "out.mcap")
    assert not report.complete and "crc" in report.error.lower() and report.exit_code == 1
    lost = chunks[3][1]
    before = sum(n for _, n in chunks[:3])
    assert report.messages_saved == len(original) - lost
    assert messages_of(tmp_path / "out.mcap") == original[:before] + original[before + lost:]
    starts = chunk_starts(intact)
    assert [(d.start, d.end) for d in report.damage] == [(starts[3], starts[4])]


def test_damage_in_the_first_chunk_keeps_every_later_chunk(intact, tmp_path):
    """The first chunk holds the channel and schema records: they come back from the summary."""
    chunks = complete_chunk_counts(intact)
    original = messages_of(intact)
    data = bytearray(intact.read_bytes())
    for k, pos in enumerate(range(chunk_starts(intact)[0], chunks[0][0], 97)):  # flips inside the first chunk
        bad = bytearray(data)
        bad[pos] ^= 0x5A
        (tmp_path / "bad.mcap").write_bytes(bytes(bad))
        report = recover(tmp_path / "bad.mcap", tmp_path / f"out{k}.mcap")
        assert not report.complete, pos
        assert messages_of(tmp_path / f"out{k}.mcap") == original[chunks[0][1]:], pos


def test_truncated_and_damaged_keeps_intact_chunks_on_both_sides(intact, tmp_path):
    """No summary to fall back on: chunks after the damage whose channels were defined before it survive."""
    chunks = complete_chunk_counts(intact)
    original = messages_of(intact)
    data = bytearray(intact.read_bytes()[:chunks[6][0]])
    pos = (chunks[2][0] + chunks[3][0]) // 2
    data[pos] ^= 0xFF
    (tmp_path / "bad.mcap").write_bytes(bytes(data))
    report = recover(tmp_path / "bad.mcap", tmp_path / "out.mcap")
    before, lost = sum(n for _, n in chunks[:3]), chunks[3][1]
    after = sum(n for _, n in chunks[4:7])
    assert report.messages_saved == before + after
    assert messages_of(tmp_path / "out.mcap") == original[:before] + original[before + lost:before + lost + after]


def test_zero_byte_and_magic_only_files(tmp_path):
    (tmp_path / "magic.mcap").write_bytes(b"\x89MCAP0\r\n")
    report = recover(tmp_path / "magic.mcap", tmp_path / "out.mcap")
    assert report.messages_saved == 0 and report.exit_code == 2
    assert messages_of(tmp_path / "out.mcap") == []
    assert not (tmp_path / "out.mcap.partial").exists()


def run_cli(*argv):
    parser = argparse.ArgumentParser()
    recover_cmd.add_parser(parser.add_subparsers())
    args = parser.parse_args(["recover", *map(str, argv)])
    return args.func(args)


def test_cli_exit_codes(intact, tmp_path, capsys):
    assert run_cli(intact, tmp_path / "a.mcap") == 0
    assert "was complete" in capsys.readouterr().out
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(intact.read_bytes()[:-100])
    assert run_cli(cut, tmp_path / "b.mcap") == 1
    assert "saved 60 messages" in capsys.readouterr().out
    junk = tmp_path / "junk.mcap"
    junk.write_text("hello")
    from trackreplay.replay.cli.main import main

    assert main(["recover", str(junk), str(tmp_path / "c.mcap")]) == 2
    assert "trackreplay: error:" in capsys.readouterr().err


def test_damage_in_the_summary_is_reported_and_every_message_kept(intact, tmp_path):
    """No chunk is touched, but the summary's CRC does not match: the log is damaged, nothing is lost."""
    from trackreplay.recorder.mcap_scan import scan, Damage

    data = bytearray(intact.read_bytes())
    pos = len(data) - 8 - 2  # the footer's summary CRC (the last field before the closing magic)
    data[pos] ^= 0x01
    (tmp_path / "bad.mcap").write_bytes(bytes(data))
    damage = [d for d in scan(bytes(data)) if isinstance(d, Damage)]
    assert [d.reason for d in damage] == ["the summary section fails its CRC"]
    report = recover(tmp_path / "bad.mcap", tmp_path / "out.mcap")
    assert not report.complete and report.exit_code == 1 and report.messages_saved == 60
    assert messages_of(tmp_path / "out.mcap") == messages_of(intact)


def test_marks_and_ground_truth_are_renumbered_past_lost_images(tmp_path):
    """Frames count images from the log's start: after a damaged chunk drops images, a mark (and a
    ground-truth frame) names the image at its own time in the recovered log, or is dropped with it."""
    from trackreplay.replay.log.frames import read_hints
    from trackreplay.replay.log.groundtruth import read_groundtruth
    from trackreplay.replay.log.reader import LogReader
    from trackreplay.schemas.records import GroundTruthFrame, GroundTruthObject, InitRegion, init_annotations_pb

    path = tmp_path / "marked.mcap"
    rng = np.random.default_rng(1)
    times = [i * 10_000_000 for i in range(30)]
    with LogWriter(path, flush_every=7) as log:
        for i, t in enumerate(times):
            log.write("/camera/image", image_message(rng.integers(0, 255, (24, 32, 3), dtype=np.uint8), "png", t), t)
            obj = GroundTruthObject(1, float(i), 5.0, 2.0, 2.0)
            log.write("/groundtruth/objects", GroundTruthFrame(i, t, (obj,)).to_pb(), t)
        marks = [InitRegion(k, times[k], 10.0, 10.0, 4.0, 4.0, "target") for k in range(30)]  # one on every frame
        log.write("/annotations/init", init_annotations_pb(marks, times[0]), times[0])
    chunks = complete_chunk_counts(path)
    data = bytearray(path.read_bytes())
    data[(chunks[2][0] + chunks[3][0]) // 2] ^= 0x5A  # inside the fourth chunk: frames in the middle are lost
    (tmp_path / "bad.mcap").write_bytes(bytes(data))
    report = recover(tmp_path / "bad.mcap", tmp_path / "out.mcap")
    out = LogReader(tmp_path / "out.mcap")
    kept_times = [m.log_time for m in out.messages(["/camera/image"])]
    assert 0 < len(kept_times) < 30
    assert not report.complete and report.marks_dropped == 30 - len(kept_times)  # the marks on the lost images
    hints = read_hints(out, "/annotations/init")
    assert [(h.frame, h.t_ns) for h in hints] == [(k, t) for k, t in enumerate(kept_times)]
    gt = read_groundtruth(out)
    assert gt.height > 20 and set(gt["t_ns"]) <= set(kept_times)  # some truth went with its own damaged chunk
    assert gt["frame"].to_list() == [kept_times.index(t) for t in gt["t_ns"]]
    assert gt["x"].to_list() == [float(times.index(t)) for t in gt["t_ns"]]  # each truth with its own image
