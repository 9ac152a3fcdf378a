from pathlib import Path

import pytest

from trackreplay.replay.cli.main import main
from trackreplay.replay.log.frames import FrameTopics, read_hints
from trackreplay.replay.log.reader import LogReader
from trackreplay.schemas import topics as T


def _payloads(path: Path) -> list[tuple]:
    reader = LogReader(path)
    topics = [t for t in reader.topics() if t != T.ANNOTATIONS_INIT]
    return [(m.topic, m.log_time, m.sequence, m.data) for m in reader.messages(topics)]


def test_annotate_adds_regions_and_changes_nothing_else(short_sim: Path, tmp_path: Path) -> None:
    out = tmp_path / "marked.mcap"
    marks = tmp_path / "marks.csv"
    marks.write_text("frame,x,y,w,h,label\n3,10,20,6,8,ball\n")
    assert main(["annotate", str(short_sim), "--frame", "1", "--box", "100,110,13,13", "--box", "5,5,4,4",
                 "--label", "ball", "--from-csv", str(marks), "--out", str(out)]) == 0
    regions = read_hints(LogReader(out), T.ANNOTATIONS_INIT)
    added = [r for r in regions if r.label == "ball"]
    assert [(r.frame, r.x, r.y, r.w, r.h) for r in added] == [(1, 106.5, 116.5, 13, 13), (1, 7.0, 7.0, 4, 4), (3, 13.0, 24.0, 6, 8)]
    assert added[0].t_ns == [m.log_time for m in LogReader(out).messages([T.CAMERA_IMAGE])][1]
    assert len(regions) == len(added) + 1  # the scene's own target mark is kept
    assert _payloads(out) == _payloads(short_sim)


def test_in_place_is_atomic_and_bad_marks_are_named(short_sim: Path, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    log = tmp_path / "log.mcap"
    log.write_bytes(short_sim.read_bytes())
    before = log.read_bytes()
    assert main(["annotate", str(log), "--frame", "99", "--box", "1,1,2,2", "--in-place"]) == 2
    assert "has no frame 99 on /camera/image (it has 12 frames)" in capsys.readouterr().err
    assert log.read_bytes() == before and list(tmp_path.glob(".annotate-*")) == []
    bad = tmp_path / "bad.csv"
    bad.write_text("frame,x,y,w,h\n0,1,2,3\n")
    assert main(["annotate", str(log), "--from-csv", str(bad), "--in-place"]) == 2
    assert "bad.csv:2: expected frame,x,y,w,h[,label], got 4 columns" in capsys.readouterr().err
    # a box under a pixel (a review: 0.3 x 0.3 px was accepted, then the colour PF crashed on it)
    assert main(["annotate", str(log), "--frame", "0", "--box=0.1,0.1,0.3,0.3", "--in-place"]) == 2
    assert "covers no whole pixel" in capsys.readouterr().err and log.read_bytes() == before
    assert main(["annotate", str(log), "--frame", "0", "--box", "1,1,2,2", "--in-place"]) == 0
    assert len(read_hints(LogReader(log), T.ANNOTATIONS_INIT)) == 2


def test_a_truncated_or_topicless_source_is_named_and_nothing_is_written(short_sim: Path, tmp_path: Path,
                                                                         capsys: pytest.CaptureFixture) -> None:
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(short_sim.read_bytes()[:-100])
    out = tmp_path / "out.mcap"
    assert main(["annotate", str(cut), "--frame", "0", "--box", "1,1,2,2", "--out", str(out)]) == 3
    assert f"{cut} is truncated or corrupt" in capsys.readouterr().err and not out.exists()
    from trackreplay.recorder.annotate import Mark, annotate
    from trackreplay.schemas.errors import LogError

    with pytest.raises(LogError, match=r"has no topic /nope; topics present: .*/camera/image"):
        annotate(short_sim, tmp_path / "x.mcap", [Mark(0, 1, 1, 2, 2)], image_topic="/nope")


def test_annotated_log_gets_ordinary_permissions_and_missing_folders_are_one_sentence(tmp_path, capsys):
    import os
    import stat

    from trackreplay.recorder.synth.flow_sims import FlowSimConfig, write_flow_sim
    from trackreplay.replay.cli.main import main

    src = tmp_path / "src.mcap"
    write_flow_sim(src, FlowSimConfig(scene="flow-sim1", frames=3))
    out = tmp_path / "marked.mcap"
    assert main(["annotate", str(src), "--frame", "0", "--box", "10,10,20,20", "--out", str(out)]) == 0
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE(out.stat().st_mode) == 0o666 & ~umask
    capsys.readouterr()
    missing = tmp_path / "no" / "marked.mcap"
    assert main(["annotate", str(src), "--frame", "0", "--box", "10,10,20,20", "--out", str(missing)]) == 5
    assert capsys.readouterr().err.strip() == f"trackreplay: error: cannot write {missing} (No such file or directory)"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["marked.mcap", "src.mcap"]
