"""Runs inside the separate CSRT venv (opencv-contrib-python-headless only, never beside trackreplay's
opencv-python-headless; see replay/runs/csrt.py; benchmarks/bench_colorpf.py runs it too): CSRT over a folder of images from a first box,
per-frame boxes (top-left, size; null where CSRT reports a failure) and step times.

    python csrt_side.py FOLDER x0,y0,w,h OUT.json
"""

import json
import sys
import time
from pathlib import Path

import cv2


def main() -> None:
    folder, out = Path(sys.argv[1]), Path(sys.argv[3])
    box = tuple(float(v) for v in sys.argv[2].split(","))
    cv2.setNumThreads(1)
    files = sorted(folder.glob("*.png")) + sorted(folder.glob("*.jpg"))
    tracker = cv2.TrackerCSRT_create()
    boxes, times = [list(box)], []
    tracker.init(cv2.imread(str(files[0])), tuple(int(round(v)) for v in box))
    for f in files[1:]:
        img = cv2.imread(str(f))
        t = time.perf_counter()
        ok, b = tracker.update(img)
        times.append(time.perf_counter() - t)
        boxes.append([float(v) for v in b] if ok else None)
    out.write_text(json.dumps({"opencv": cv2.__version__, "boxes": boxes, "times": times}))


if __name__ == "__main__":
    main()
