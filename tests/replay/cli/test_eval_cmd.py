"""`eval`: MOTChallenge results and sequence folders, the track it scores said (never silently the
longest), the measured figures first."""

import json
from pathlib import Path

import pytest

from trackreplay.replay.cli.main import main
from trackreplay.replay.core.export import write_mot
from trackreplay.replay.core.trajectory import state_row, trajectory_table
from trackreplay.trackers.base import TrackState


def _sequence(root: Path, n: int = 6) -> Path:
    (root / "gt").mkdir(parents=True)
    lines = [f"{f + 1},{k},{11 + 40 * k + f},21,10,20,1,-1,-1,-1" for f in range(n) for k in (1, 2)]
    (root / "gt" / "gt.txt").write_text("\n".join(lines) + "\n")
    (root / "seqinfo.ini").write_text(f"[Sequence]\nname=TOY\nseqLength={n}\nframeRate=30\nimWidth=200\nimHeight=100\n")
    return root


def _result(path: Path, tracks=(1, 2), n: int = 6, status: str = "measured") -> Path:
    rows = [state_row("t", f, f, TrackState(k, x=15.0 + 40 * k + f, y=30.0, w=10.0, h=20.0, status=status))
            for f in range(n) for k in tracks]
    table = trajectory_table(rows)
    if path.suffix == ".txt":
        write_mot(table, path)
    else:
        table.write_parquet(path)
    return path


def test_several_tracks_are_all_scored_and_it_says_so(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    seq = _sequence(tmp_path / "TOY")
    assert main(["eval", str(_result(tmp_path / "r.txt")), str(seq), "--json", str(tmp_path / "out" / "m.json")]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[0].startswith("scoring all 2 tracks against all 2 truth object(s) with the multi-object metrics")
    assert "MOTA 1.000" in out and "IDSW 0" in out
    assert json.loads((tmp_path / "out" / "m.json").read_text())["image"]["mota"] == 1.0  # its folder created


def test_track_scores_one_against_the_object_it_follows(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    seq = _sequence(tmp_path / "TOY")
    assert main(["eval", str(_result(tmp_path / "r.txt")), str(seq / "gt" / "gt.txt"), "--track", "2"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == "scoring track 2 (--track) against truth object 2, the one of 2 it lies on most often (--gt-id ID chooses)"
    assert "t / 2 vs ground-truth object 2" in lines[1] or "r / 2 vs ground-truth object 2" in lines[1]
    # the headline: measured figures before "frames tracked"
    assert lines[2].startswith("measured within 5 px") and "6 of 6 visible (100.0%)" in lines[2]
    assert [i for i, l in enumerate(lines) if l.startswith("measured ")] < [i for i, l in enumerate(lines) if l.startswith("frames tracked")]


def test_predicted_rows_are_tracked_but_not_measured(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    seq = _sequence(tmp_path / "TOY")
    traj = _result(tmp_path / "r.parquet", tracks=(1,), status="predicted")
    assert main(["eval", str(traj), str(seq), "--gt-id", "1"]) == 0
    out = capsys.readouterr().out
    assert "scoring track 1 (the trajectory's only one) against truth object 1 (--gt-id)" in out
    assert "measured within 5 px                                  0 of 6 visible (0.0%)" in out
    assert "frames tracked (measured, predicted or interpolated)  6 of 6 visible (100.0%)" in out


@pytest.mark.parametrize("argv, message", [
    (["--track", "9"], r"r\.txt has no track 9 \(its tracks: 1, 2\)"),
    (["--gt-id", "1"], r"r\.txt holds 2 tracks: --gt-id scores one of them, so name it with --track ID"),
    (["--gt-topic", "/x"], r"--gt-topic and --image-topic choose topics of a log; .*TOY is a MOTChallenge sequence"),
])
def test_bad_choices_are_one_sentence_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture, argv, message) -> None:
    import re

    seq = _sequence(tmp_path / "TOY")
    assert main(["eval", str(_result(tmp_path / "r.txt")), str(seq), *argv]) == 2
    err = capsys.readouterr().err
    assert re.search(message, err) and err.count("\n") == 1


def test_a_result_of_another_sequence_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    seq = _sequence(tmp_path / "TOY", n=3)
    assert main(["eval", str(_result(tmp_path / "r.txt", n=6)), str(seq)]) == 2
    assert "r.txt: frame 4 (1-based) is beyond the 3 frames of TOY" in capsys.readouterr().err


def test_a_result_txt_against_a_log(short_sim: Path, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """A MOTChallenge result of a replay scores against the log it came from as its table does."""
    traj, txt = tmp_path / "t.parquet", tmp_path / "t.txt"
    assert main(["replay", str(short_sim), "--tracker", "flow", "--export", str(traj), "--quiet"]) == 0
    assert main(["export", str(traj), str(txt)]) == 0
    capsys.readouterr()
    assert main(["eval", str(traj), str(short_sim)]) == 0
    a = capsys.readouterr().out.splitlines()
    assert main(["eval", str(txt), str(short_sim)]) == 0
    b = capsys.readouterr().out.splitlines()
    assert a[0] == b[0] == "scoring track 1 (the trajectory's only one) against truth object 1 (the truth's only one)"
    assert a[2:5] == b[2:5]  # the measured figures (the .txt's rows are all measured, as flow's are here)


def test_a_result_of_another_log_is_refused(short_sim: Path, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    txt = _result(tmp_path / "r.txt", tracks=(1,), n=20)  # the log has 12 frames
    assert main(["eval", str(txt), str(short_sim)]) == 2
    err = capsys.readouterr().err
    assert "r.txt: frame 13 (1-based) is not one of the 12 frames of" in err and err.count("\n") == 1
