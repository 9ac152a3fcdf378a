"""MOTChallenge result files and sequence folders (gt/gt.txt + seqinfo.ini) as `eval` reads them."""

from pathlib import Path

import polars as pl
import pytest

from trackreplay.replay.analysis.eval import evaluate
from trackreplay.replay.analysis.mot import mot_metrics
from trackreplay.replay.analysis.mot_files import drop_distractor_matches, read_mot_result, read_mot_sequence
from trackreplay.replay.core.export import write_mot
from trackreplay.replay.core.trajectory import state_row, trajectory_table
from trackreplay.schemas.errors import TrackreplayError
from trackreplay.trackers.base import TrackState


def sequence(root: Path, gt_lines: list[str], length: int | None = 5, name: str = "MOT17-02") -> Path:
    (root / "gt").mkdir(parents=True)
    (root / "gt" / "gt.txt").write_text("\n".join(gt_lines) + "\n")
    if length is not None:
        (root / "seqinfo.ini").write_text(f"[Sequence]\nname={name}\nimDir=img1\nframeRate=30\nseqLength={length}\n"
                                          "imWidth=640\nimHeight=480\nimExt=.jpg\n")
    return root


def test_a_result_reads_back_what_export_wrote(tmp_path: Path) -> None:
    """1-based frames and pixels become 0-based; every row is `measured`; conf in [0, 1] is the confidence."""
    rows = [state_row("flow", f, f * 10, TrackState(3, x=20.5 + f, y=30.0, w=8.0, h=6.0, status="measured")) for f in range(4)]
    table = trajectory_table(rows)
    path = tmp_path / "res.txt"
    write_mot(table, path)
    assert path.read_text().splitlines()[0] == "1,3,17.500,28.000,8.000,6.000,1.000,-1.000,-1.000,-1.000"
    back = read_mot_result(path)
    assert back["frame"].to_list() == [0, 1, 2, 3] and back["track_id"].unique().to_list() == [3]
    assert back["x"].to_list() == pytest.approx(table["x"].to_list()) and back["y"].to_list() == pytest.approx([30.0] * 4)
    assert set(back["status"]) == {"measured"} and back["confidence"].to_list() == [1.0] * 4
    assert back["t_ns"].null_count() == 4 and back["X"].null_count() == 4 and back["tracker"][0] == "res"


@pytest.mark.parametrize("line, message", [
    ("0,1,1,1,5,5,1", r"res\.txt:2: frame '0' is not a 1-based frame number"),
    ("2,1.5,1,1,5,5,1", r"res\.txt:2: id '1\.5' is not an integer"),
    ("2,1,1,1,0,5,1", r"res\.txt:2: box 1,1,0,5 is not a finite box of positive size"),
    ("2,1,x,1,5,5,1", r"res\.txt:2: bb_left 'x' is not a number"),
    ("1,1,2,2,5,5,1", r"res\.txt:2: id 1 appears a second time in frame 1 \(first on line 1\)"),
    ("2,1,1,1", r"res\.txt:2: expected frame,id,bb_left,bb_top,bb_width,bb_height"),
])
def test_a_bad_result_line_is_named(tmp_path: Path, line: str, message: str) -> None:
    path = tmp_path / "res.txt"
    path.write_text("1,1,1,1,5,5,1\n" + line + "\n")
    with pytest.raises(TrackreplayError, match=message):
        read_mot_result(path)


def test_a_sequence_folder_every_frame_annotated_and_zero_marked_rows_left_out(tmp_path: Path) -> None:
    seq = read_mot_sequence(sequence(tmp_path / "S", ["1,1,11,21,10,20,1,-1,-1,-1", "2,1,12,21,10,20,1,-1,-1,-1",
                                                      "2,2,50,50,10,10,0,-1,-1,-1"]))
    assert seq.length == 5 and seq.frames.to_list() == [0, 1, 2, 3, 4] and seq.name == "MOT17-02"
    assert seq.gt["id"].to_list() == [1, 1] and seq.gt["x"].to_list() == [15.0, 16.0] and seq.gt["y"].to_list() == [30.0, 30.0]
    # the gt.txt alone finds its seqinfo.ini two folders up
    assert read_mot_sequence(tmp_path / "S" / "gt" / "gt.txt").length == 5
    with pytest.raises(TrackreplayError, match=r"gt\.txt:1: frame 9 is beyond the sequence's 5 frames"):
        read_mot_sequence(sequence(tmp_path / "T", ["9,1,1,1,5,5,1,-1,-1,-1"]))
    with pytest.raises(TrackreplayError, match=r"neither a log nor a MOTChallenge sequence folder"):
        read_mot_sequence(tmp_path)


def test_mot17_truth_scores_pedestrians_and_clears_boxes_on_distractors(tmp_path: Path) -> None:
    """As TrackEval: class 1 is scored; a tracker box matched to a static person (class 7) is neither
    a hit nor a false positive; one on a car (class 3, not a distractor) stays a false positive."""
    seq = read_mot_sequence(sequence(tmp_path / "S", [
        "1,1,11,11,10,10,1,1,1.0",    # pedestrian
        "1,2,101,101,10,10,0,7,1.0",  # static person: a distractor
        "1,3,201,201,10,10,0,3,1.0",  # car: not scored, not a distractor
    ], length=1))
    assert seq.gt["id"].to_list() == [1]
    rows = [state_row("t", 0, 0, TrackState(k, x=x, y=x, w=10.0, h=10.0, status="measured"))
            for k, x in ((1, 15.0), (2, 105.0), (3, 205.0))]
    traj = trajectory_table(rows)
    cleared, removed = drop_distractor_matches(traj, seq)
    assert removed == 1 and cleared["track_id"].to_list() == [1, 3]
    m = mot_metrics(cleared, seq.gt, frames=seq.frames)
    assert (m.matches, m.false_positives, m.misses) == (1, 1, 0)


def test_a_result_scores_like_the_table_it_was_exported_from(tmp_path: Path) -> None:
    gt_lines = [f"{f + 1},1,{11 + f},21,10,20,1,-1,-1,-1" for f in range(5)]
    seq = read_mot_sequence(sequence(tmp_path / "S", gt_lines))
    rows = [state_row("flow", f, f, TrackState(1, x=16.0 + f, y=30.0, w=10.0, h=20.0)) for f in range(5)]
    path = tmp_path / "r.txt"
    write_mot(trajectory_table(rows), path)
    a, _ = evaluate(trajectory_table(rows), seq.gt)
    b, _ = evaluate(read_mot_result(path), seq.gt)
    assert a.centre_error_mean == pytest.approx(b.centre_error_mean) == pytest.approx(1.0)
    assert b.measured_within_5px == 1.0 and b.measured_iou_50 == 1.0
    assert pl.Series(seq.frames).to_list() == list(range(5))


TOY = Path(__file__).resolve().parent / "mot17_toy"
# TrackEval 1.3.0 (MotChallenge2DBox, BENCHMARK MOT17, its default preprocessing) on mot17_toy:
# `regenerate.py --score` run with trackeval installed (numbers measured with it)
TRACKEVAL = {"hota": 0.3855916729327296, "deta": 0.3308203306303302, "assa": 0.4498711922679337,
             "mota": 0.07547169811320754, "fp": 70, "fn": 27, "tp": 79, "idsw": 1, "idf1": 0.5176470588235295}


def test_a_mot17_folder_scores_as_trackeval_does(tmp_path: Path, capsys) -> None:
    """Class-1 truth only, zero-marked rows out, tracker boxes on distractors cleared: TrackEval's numbers."""
    import json

    from trackreplay.replay.cli.main import main

    metrics = tmp_path / "m.json"
    assert main(["eval", str(TOY / "result.txt"), str(TOY), "--json", str(metrics)]) == 0
    data = json.loads(metrics.read_text())
    printed = capsys.readouterr().out
    assert "tracked box(es) on distractors (static people, reflections, ...) left out, as TrackEval does" in printed
    image, hota = data["image"], data["hota"]["image"]
    assert (image["false_positives"], image["misses"], image["matches"], image["id_switches"]) == (
        TRACKEVAL["fp"], TRACKEVAL["fn"], TRACKEVAL["tp"], TRACKEVAL["idsw"])
    assert image["mota"] == pytest.approx(TRACKEVAL["mota"], abs=1e-9)
    assert image["idf1"] == pytest.approx(TRACKEVAL["idf1"], abs=1e-9)
    for key in ("hota", "deta", "assa"):
        assert hota[key] == pytest.approx(TRACKEVAL[key], abs=1e-9)
