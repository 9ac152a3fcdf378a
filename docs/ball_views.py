"""How far the pictures of each ball clip change over six frames: the numbers behind the golf
tracker's ``world_behind.max_change`` (docs/ball_corpus.md, "the world behind the ball").

For each clip, over its first 120 frames from the corpus case's start, the median absolute change
of the pixels between a frame and the one 6 frames before, on the copies the tracker compares
(long side 256 px, ``trackers/golf/world_behind.py``), as 10th/50th/90th percentiles over frames.

    python docs/ball_views.py [DATA_ROOT]    # default: ../shared/data/real next to the repository
"""

from __future__ import annotations

import sys
from pathlib import Path

import cv2
import numpy as np

from trackreplay.trackers.appearance.color import to_grey
from trackreplay.trackers.golf.world_behind import _small, _step

CLIPS = (  # (name, source under the data root, first frame): the ball corpus's image-only cases
    ("badminton_chis_rally", "ball_clips/badminton_chis_rally_cam1/video.mp4", 283),
    ("badminton_alz_00001", "ball_clips/badminton_alz_rawdata_00001/video.mp4", 31),
    ("badminton_alz_00004", "ball_clips/badminton_alz_rawdata_00004/video.mp4", 46),
    ("badminton_alz_00025", "ball_clips/badminton_alz_rawdata_00025/video.mp4", 44),
    ("golf_iron_shot_sky", "golf_iron_shot_sky/vid1.mp4", 458),
    ("vot2014_ball", "ball_clips/vot2014_ball/frames", 0),
)
SPAN, FRAMES = 6, 120


def pictures(source: Path, first: int):
    """BGR frames from ``first`` on (a video file or a folder of JPEGs)."""
    if source.is_dir():
        for path in sorted(source.glob("*.jpg"))[first:first + FRAMES]:
            yield cv2.imread(str(path))
        return
    capture = cv2.VideoCapture(str(source))
    capture.set(cv2.CAP_PROP_POS_FRAMES, first)
    for _ in range(FRAMES):
        ok, image = capture.read()
        if not ok:
            return
        yield image


def changes(source: Path, first: int) -> np.ndarray:
    """The median pixel change over SPAN frames, one value per frame."""
    small = []
    out = []
    for image in pictures(source, first):
        grey = to_grey(image)
        small.append(_small(grey, _step(grey)))
        if len(small) > SPAN:
            out.append(float(np.median(np.abs(small[-1] - small[-1 - SPAN]))))
    return np.array(out)


def main() -> None:
    root = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parents[2] / "shared" / "data" / "real"
    print("| clip | frames | median change p10 / p50 / p90 (grey levels) |")
    print("|---|---|---|")
    for name, relative, first in CLIPS:
        values = changes(root / relative, first)
        p10, p50, p90 = np.percentile(values, [10, 50, 90]) if len(values) else (np.nan,) * 3
        print(f"| {name} | {len(values)} | {p10:.1f} / {p50:.1f} / {p90:.1f} |")


if __name__ == "__main__":
    main()
