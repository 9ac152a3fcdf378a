"""HOTA of replay/analysis/mot.py: parity with TrackEval 1.3.0 and hand-computed cases.

TrackEval is the reference HOTA implementation (Luiten et al. 2020). Its PyPI release ``trackeval``
1.3.0 is published from the kovalp/TrackEval fork of JonathonLuiten/TrackEval; its
``metrics/hota.py`` ``eval_sequence`` is upstream's with ``np.float`` replaced by ``float`` (compared
line by line, 2026-11-25). The numbers below were computed ONCE with trackeval 1.3.0 (numpy 2.4.6,
its own venv: ``python -m venv tevenv && tevenv/bin/pip install trackeval==1.3.0``) by
``trackeval.metrics.HOTA().eval_sequence`` on the six sequences of ``mot_parity_sequences.json``
(those of the motmetrics parity test), ids relabelled 0..n-1 in sorted order as TrackEval's datasets
do, each reported figure the mean of its 19 α values. The sequences hold thresholded distances, so
the similarity fed to both sides is ``max(0, 1 − d / 1)`` with NaN (no match) = 0: the IoU for the
image sequences (for ``golden_groups_image``, stored at IoU ≥ 0.3, pairs below 0.3 are 0) and
``1 − d/1 m`` for ``golden_groups_3d`` (exact: the stored 3-D distances were cut at 1 m). When a venv
with trackeval is at hand (``TRACKREPLAY_TRACKEVAL_PYTHON``, default /tmp/tevenv/bin/python) the
live test reruns it.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from trackreplay.replay.analysis.mot import ALPHAS, distance_similarity, hota, iou_similarity

HERE = Path(__file__).parent
SEQUENCES = HERE / "mot_parity_sequences.json"

TRACKEVAL_1_3_0 = {
    "motmetrics_readme": {"hota": 0.4136448547665181, "deta": 0.5774436090225564, "assa": 0.29807017543859654, "loca": 0.8315789473684211, "detre": 0.7017543859649124, "detpr": 0.7017543859649124, "assre": 0.3999999999999999, "asspr": 0.5491228070175439},
    "random_1": {"hota": 0.3116890365432351, "deta": 0.4096965093276355, "assa": 0.23744680408697252, "loca": 0.7489492685083335, "detre": 0.5568381921346116, "detpr": 0.5060455192034139, "assre": 0.30770669105460097, "asspr": 0.443180403722732},
    "random_2": {"hota": 0.28092159345227563, "deta": 0.41953663263478874, "assa": 0.18920008335733218, "loca": 0.7462344808185742, "detre": 0.5523486134691568, "detpr": 0.5206258890469417, "assre": 0.25507531714251236, "asspr": 0.3832014241597974},
    "random_3": {"hota": 0.2796278937937039, "deta": 0.4033042012082978, "assa": 0.19543079690193532, "loca": 0.7504546243636906, "detre": 0.5495989043240072, "detpr": 0.5045805640380816, "assre": 0.2883253930215323, "asspr": 0.29814705570814415},
    "golden_groups_image": {"hota": 0.6516602953244008, "deta": 0.6444912606190801, "assa": 0.6589391193022976, "loca": 0.9364430080365144, "detre": 0.6557017543859649, "detpr": 0.9537480063795853, "assre": 0.6713588797806399, "asspr": 0.9549474102630657},
    "golden_groups_3d": {"hota": 0.2683596013435765, "deta": 0.17253601189402779, "assa": 0.41858337444637755, "loca": 0.7188848221446432, "detre": 0.22478070175438594, "detpr": 0.32695374800637955, "assre": 0.4340311004784689, "asspr": 0.5487039968341908},}


def _similarity(f: dict) -> np.ndarray:
    d = np.array([[np.nan if x is None else x for x in row] for row in f["d"]], np.float64).reshape(len(f["o"]), len(f["h"]))
    return np.clip(1.0 - np.nan_to_num(d, nan=1.0), 0.0, None)


def _check(name: str, ref: dict) -> None:
    frames = json.loads(SEQUENCES.read_text())[name]
    ours = hota([(f["o"], f["h"], _similarity(f)) for f in frames]).as_dict()
    for key, value in ref.items():
        assert ours[key] == pytest.approx(value, abs=1e-6), f"{name}: {key} ours {ours[key]} trackeval {value}"


@pytest.mark.parametrize("name", sorted(TRACKEVAL_1_3_0))
def test_hota_matches_trackeval(name: str) -> None:
    _check(name, TRACKEVAL_1_3_0[name])


_SIDE = """
import json, sys
import numpy as np
from trackeval.metrics import HOTA
out = {}
for name, frames in json.load(open(sys.argv[1])).items():
    gts = sorted({o for f in frames for o in f["o"]}); hyps = sorted({h for f in frames for h in f["h"]})
    gi = {o: k for k, o in enumerate(gts)}; hi = {h: k for k, h in enumerate(hyps)}
    sims = [np.clip(1.0 - np.nan_to_num(np.array([[np.nan if x is None else x for x in r] for r in f["d"]], float)
                                         .reshape(len(f["o"]), len(f["h"])), nan=1.0), 0.0, None) for f in frames]
    data = {"num_gt_ids": len(gts), "num_tracker_ids": len(hyps),
            "num_gt_dets": sum(len(f["o"]) for f in frames), "num_tracker_dets": sum(len(f["h"]) for f in frames),
            "gt_ids": [np.array([gi[o] for o in f["o"]], int) for f in frames],
            "tracker_ids": [np.array([hi[h] for h in f["h"]], int) for f in frames], "similarity_scores": sims}
    r = HOTA().eval_sequence(data)
    out[name] = {k.lower(): float(np.mean(r[k])) for k in ["HOTA", "DetA", "AssA", "LocA", "DetRe", "DetPr", "AssRe", "AssPr"]}
print(json.dumps(out))
"""


def test_hota_matches_trackeval_run_live(reference_side) -> None:
    live = reference_side("TRACKREPLAY_TRACKEVAL_PYTHON", "/tmp/tevenv/bin/python", _SIDE, SEQUENCES)
    assert sorted(live) == sorted(TRACKEVAL_1_3_0)
    for name, ref in live.items():
        _check(name, ref)


# hand-computed cases


def _one(ids_gt, ids_hyp, sim):
    return (np.array(ids_gt), np.array(ids_hyp), np.array(sim, float).reshape(len(ids_gt), len(ids_hyp)))


def test_perfect_tracker_is_one() -> None:
    frames = [_one([1, 2], [7, 8], [[1.0, 0.0], [0.0, 1.0]]) for _ in range(10)]
    s = hota(frames)
    assert (s.hota, s.deta, s.assa, s.loca) == pytest.approx((1.0, 1.0, 1.0, 1.0))


def test_one_id_switch_halfway() -> None:
    # one object, 10 frames, hypothesis 5 then 6: every frame a TP; each TP's pair has TPA 5, FNA 5, FPA 0
    frames = [_one([1], [5 if t < 5 else 6], [[1.0]]) for t in range(10)]
    s = hota(frames)
    assert s.deta == pytest.approx(1.0)
    assert s.assa == pytest.approx(0.5)
    assert s.hota == pytest.approx(math.sqrt(0.5))
    assert s.assre == pytest.approx(0.5) and s.asspr == pytest.approx(1.0)


def test_false_positive_track() -> None:
    # truth tracked perfectly for 4 frames, plus a hypothesis overlapping nothing: DetA 4/8, AssA 1
    frames = [_one([1], [5, 9], [[1.0, 0.0]]) for _ in range(4)]
    s = hota(frames)
    assert s.deta == pytest.approx(0.5) and s.assa == pytest.approx(1.0)
    assert s.hota == pytest.approx(math.sqrt(0.5))
    assert s.detre == pytest.approx(1.0) and s.detpr == pytest.approx(0.5)


def test_localisation_sweeps_alpha() -> None:
    # similarity 0.5 everywhere: a TP for the 10 α <= 0.5, a FN + FP for the 9 above
    frames = [_one([1], [5], [[0.5]]) for _ in range(6)]
    s = hota(frames)
    assert len(ALPHAS) == 19
    assert s.deta == pytest.approx(10 / 19 * 1.0 + 9 / 19 * 0.0)
    assert s.hota == pytest.approx(10 / 19)
    assert s.hota_alpha[9] == pytest.approx(1.0) and s.hota_alpha[10] == 0.0


def test_empty_tracker() -> None:
    s = hota([_one([1, 2], [], []) for _ in range(3)])
    assert s.hota == 0.0 and s.deta == 0.0


def test_similarities() -> None:
    iou = iou_similarity(np.array([[0, 0, 2, 2]]), np.array([[1, 0, 2, 2], [10, 10, 1, 1]]))
    assert iou == pytest.approx(np.array([[2 / 6, 0.0]]))
    d = distance_similarity(np.array([[0, 0, 0]]), np.array([[0.25, 0, 0], [0, 3, 0]]), 1.0)
    assert d == pytest.approx(np.array([[0.75, 0.0]]))


def test_eval_mot_prints_and_writes_hota(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    from trackreplay.replay.cli.main import main

    golden = HERE.parents[1] / "golden"
    out = tmp_path / "mot.json"
    assert main(["eval", str(golden / "groups.trajectory.parquet"), str(golden / "groups-crossing-320x240.mcap"),
                 "--mot", "--gt-topic", "/groundtruth/groups", "--json", str(out)]) == 0
    text = capsys.readouterr().out
    assert "HOTA" in text and "AssA" in text
    data = json.loads(out.read_text())
    for space in ("image", "3d"):
        h = data["hota"][space]
        assert 0.0 < h["hota"] <= 1.0 and len(h["hota_alpha"]) == 19
        assert h["hota"] == pytest.approx(float(np.mean(h["hota_alpha"])))
