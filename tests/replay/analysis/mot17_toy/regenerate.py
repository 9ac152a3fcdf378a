"""Writes this folder's toy MOT17 sequence (seed 0: 3 pedestrians, one zero-marked, a static person,
a distractor, a car, a person on a vehicle, a reflection; a tracker with noise, an id switch, false
positives and boxes on the distractors) and, run with a Python that has ``trackeval`` 1.3.0, prints
TrackEval's scores of it, which ``test_mot_files.py`` holds as its expected values:

    python regenerate.py            # the sequence (gt/gt.txt, seqinfo.ini, result.txt)
    /path/to/trackeval-venv/bin/python regenerate.py --score
"""

import json
import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
SEQ, N = "MOT17-02-TOY", 40


def write() -> None:
    rng = np.random.default_rng(0)
    gt, tr = [], []
    objs = {k: (rng.uniform(20, 500), rng.uniform(20, 350), rng.uniform(20, 60), rng.uniform(40, 120), cls, flag)
            for k, cls, flag in [(1, 1, 1), (2, 1, 1), (3, 1, 1), (4, 1, 0), (5, 7, 0), (6, 8, 0), (7, 3, 0), (8, 2, 0), (9, 12, 1)]}
    for f in range(1, N + 1):
        for k, (x, y, w, h, cls, flag) in objs.items():
            if rng.random() < 0.1:
                continue
            x += f * rng.normal(1, 0.3)
            y += f * rng.normal(0.5, 0.2)
            gt.append(f"{f},{k},{x:.2f},{y:.2f},{w:.2f},{h:.2f},{flag},{cls},1.0")
            if rng.random() < 0.8:
                tid = k + (100 if (k == 2 and f > N // 2) else 0)
                tr.append(f"{f},{tid},{x + rng.normal(0, 4):.2f},{y + rng.normal(0, 4):.2f},{w * rng.uniform(0.8, 1.2):.2f},"
                          f"{h * rng.uniform(0.8, 1.2):.2f},1,-1,-1,-1")
        if rng.random() < 0.3:
            tr.append(f"{f},50,{rng.uniform(0, 600):.2f},{rng.uniform(0, 400):.2f},30,60,1,-1,-1,-1")
    (HERE / "gt").mkdir(exist_ok=True)
    (HERE / "gt" / "gt.txt").write_text("\n".join(gt) + "\n")
    (HERE / "seqinfo.ini").write_text(f"[Sequence]\nname={SEQ}\nimDir=img1\nframeRate=30\nseqLength={N}\nimWidth=640\n"
                                      "imHeight=480\nimExt=.jpg\n")
    (HERE / "result.txt").write_text("\n".join(tr) + "\n")


def score() -> dict:
    import trackeval

    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        seq = root / "gt" / "MOT17-train" / SEQ
        shutil.copytree(HERE / "gt", seq / "gt")
        shutil.copy(HERE / "seqinfo.ini", seq)
        (root / "gt" / "seqmaps").mkdir(parents=True)
        (root / "gt" / "seqmaps" / "MOT17-train.txt").write_text(f"name\n{SEQ}\n")
        (root / "trackers" / "MOT17-train" / "T" / "data").mkdir(parents=True)
        shutil.copy(HERE / "result.txt", root / "trackers" / "MOT17-train" / "T" / "data" / f"{SEQ}.txt")
        ec = trackeval.Evaluator.get_default_eval_config()
        ec.update(USE_PARALLEL=False, PRINT_RESULTS=False, PRINT_CONFIG=False, OUTPUT_SUMMARY=False, OUTPUT_DETAILED=False,
                  PLOT_CURVES=False, TIME_PROGRESS=False)
        dc = trackeval.datasets.MotChallenge2DBox.get_default_dataset_config()
        dc.update(GT_FOLDER=str(root / "gt"), TRACKERS_FOLDER=str(root / "trackers"), BENCHMARK="MOT17",
                  SPLIT_TO_EVAL="train", TRACKERS_TO_EVAL=["T"], PRINT_CONFIG=False)
        metrics = [trackeval.metrics.HOTA(), trackeval.metrics.CLEAR(), trackeval.metrics.Identity()]
        res, _ = trackeval.Evaluator(ec).evaluate([trackeval.datasets.MotChallenge2DBox(dc)], metrics)
    r = res["MotChallenge2DBox"]["T"][SEQ]["pedestrian"]
    return {"hota": float(r["HOTA"]["HOTA"].mean()), "deta": float(r["HOTA"]["DetA"].mean()),
            "assa": float(r["HOTA"]["AssA"].mean()), "mota": float(r["CLEAR"]["MOTA"]), "fp": int(r["CLEAR"]["CLR_FP"]),
            "fn": int(r["CLEAR"]["CLR_FN"]), "tp": int(r["CLEAR"]["CLR_TP"]), "idsw": int(r["CLEAR"]["IDSW"]),
            "idf1": float(r["Identity"]["IDF1"])}


if __name__ == "__main__":
    print(json.dumps(score())) if "--score" in sys.argv else write()
