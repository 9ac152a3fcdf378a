"""Re-detection of a lost target ([colorpf.redetect], colorpf.redetect; issue 31): while lost, a scan of the
whole picture re-seeds the cloud on the one box that matches; a look-alike that matches as well leaves it."""

import numpy as np

from trackreplay.replay.core.config import config_from_dict
from trackreplay.schemas.records import InitRegion
from trackreplay.trackers.colorpf.config import PAPER, ColorPfConfig, RedetectConfig
from trackreplay.trackers.colorpf.redetect import grid, unique_best
from trackreplay.trackers.colorpf.tracker import ColorPfTracker
from trackreplay.trackers.frame import Frame

SIDE, GONE, BACK, FRAMES = 16, 12, 32, 60  # the square is hidden on frames GONE..BACK-1
# where it comes back (its centre): ~150 px from where it was lost (59, 68); and ``twins``: a second,
# identical square, apart from it
AWAY, TWIN = np.array([200.0, 130.0]), np.array([60.0, 150.0])


def _frames(twins: bool) -> list[np.ndarray]:
    """A red 16x16 square on a grey, noisy floor moving right 1 px a frame, hidden for 20 frames (the track
    turns lost), then back far from there; ``twins``: a second, identical square comes back too, apart."""
    rng = np.random.default_rng(0)
    floor = np.clip(rng.normal(120, 6, (200, 300, 3)), 0, 255).astype(np.uint8)
    images = []
    for i in range(FRAMES):
        image = floor.copy()
        if i < GONE:
            image[60:60 + SIDE, 40 + i:40 + i + SIDE] = (30, 30, 160)
        elif i >= BACK:
            for centre in (AWAY, TWIN) if twins else (AWAY,):
                x, y = (centre - SIDE / 2).astype(int)
                image[y:y + SIDE, x:x + SIDE] = (30, 30, 160)
        images.append(image)
    return images


def _rows(config: ColorPfConfig, twins: bool = False, seed: int = 0) -> list:
    mark = InitRegion(0, 0, 40 + SIDE / 2 - 0.5, 60 + SIDE / 2 - 0.5, SIDE, SIDE, "target")
    tracker = ColorPfTracker(config, np.random.default_rng(seed))
    rows = []
    for i, image in enumerate(_frames(twins)):
        states = tracker.step(Frame(index=i, t_ns=i * 33_333_333, image=image, all_hints=(mark,),
                                    hints=(mark,) if i == 0 else ()))
        rows.append(states[0])
    return rows


def test_the_grid_covers_its_bounds_within_its_size():
    wh = np.array([20.0, 40.0])
    boxes = grid(wh, np.array([10.0, 20.0]), np.array([290.0, 180.0]), 0.5, 4096)
    assert np.all(boxes[:, 2:4] == wh)
    assert boxes[:, 0].min() >= 10 and boxes[:, 0].max() <= 290 and boxes[:, 1].min() >= 20 and boxes[:, 1].max() <= 180
    steps = np.diff(np.unique(boxes[:, 0])), np.diff(np.unique(boxes[:, 1]))
    assert steps[0].max() <= 10 + 1e-9 and steps[1].max() <= 20 + 1e-9  # half a box per axis
    assert 0 < len(grid(wh, np.array([10.0, 20.0]), np.array([290.0, 180.0]), 0.5, 50)) <= 50  # the stride widens
    assert len(grid(wh, np.array([150.0, 100.0]), np.array([140.0, 90.0]), 0.5, 10)) == 1  # empty bounds: the middle


def test_only_a_single_match_is_taken():
    boxes = np.array([[10.0, 10, 10, 10], [14, 10, 10, 10], [60, 60, 10, 10]])
    assert unique_best(boxes, np.array([0.9, 0.7, 0.2]), 0.5) == 0  # its overlapping neighbour does not count
    assert unique_best(boxes, np.array([0.9, 0.7, 0.6]), 0.5) is None  # a look-alike apart matches as well
    assert unique_best(boxes, np.array([0.4, 0.3, 0.2]), 0.5) is None  # nothing matches


def test_a_lost_target_is_found_again_far_from_where_it_was_lost():
    rows = _rows(ColorPfConfig())
    assert all(r.status == "lost" for r in rows[GONE + 12:BACK])  # lost while hidden
    found = [i for i, r in enumerate(rows) if i >= BACK and r.status == "measured"]
    assert found and found[0] <= BACK + 6, [r.status for r in rows[BACK:]]
    assert all(abs(rows[i].x - AWAY[0]) <= 4 and abs(rows[i].y - AWAY[1]) <= 4 for i in found)
    assert all(r.status == "measured" for r in rows[found[0]:])
    without = _rows(ColorPfConfig(redetect=RedetectConfig(enabled=False)))
    assert all(r.status == "lost" for r in without[BACK:])  # the lost cloud's random walk does not get there


def test_a_look_alike_that_matches_as_well_is_not_taken():
    rows = _rows(ColorPfConfig(), twins=True)
    without = _rows(ColorPfConfig(redetect=RedetectConfig(enabled=False)), twins=True)
    # two matches: the scan cannot tell which, and leaves the cloud as it is
    assert [(r.status, r.x, r.y) for r in rows] == [(r.status, r.x, r.y) for r in without]


def test_re_detection_is_deterministic_and_off_in_paper():
    a, b = _rows(ColorPfConfig(), seed=3), _rows(ColorPfConfig(), seed=3)
    assert [(r.status, r.x, r.y, r.confidence) for r in a] == [(r.status, r.x, r.y, r.confidence) for r in b]
    assert config_from_dict(ColorPfConfig, PAPER).redetect.enabled is False


class _Scans(ColorPfTracker):
    """The tracker, noting the frames on which the lost track's scan runs."""

    def __init__(self, config: ColorPfConfig, rng: np.random.Generator) -> None:
        super().__init__(config, rng)
        self.frame, self.scanned = -1, []

    def step(self, frame: Frame) -> list:
        self.frame = frame.index
        return super().step(frame)

    def _redetect(self, image, view, prev) -> None:
        self.scanned.append(self.frame)
        super()._redetect(image, view, prev)


def _scans(config: ColorPfConfig, interval_ns: int) -> tuple[list[int], list[int]]:
    """The lost frames (the track lost before the frame's step) and the frames scanned."""
    mark = InitRegion(0, 0, 40 + SIDE / 2 - 0.5, 60 + SIDE / 2 - 0.5, SIDE, SIDE, "target")
    tracker = _Scans(config, np.random.default_rng(0))
    lost = []
    for i, image in enumerate(_frames(False)[:BACK]):  # hidden from GONE on: lost, and never found
        if tracker.life.lost:
            lost.append(i)
        tracker.step(Frame(index=i, t_ns=i * interval_ns, image=image, all_hints=(mark,),
                           hints=(mark,) if i == 0 else ()))
    return lost, tracker.scanned


def test_the_lost_track_is_scanned_ten_times_a_second():
    lost, scanned = _scans(ColorPfConfig(), 33_333_333)  # 30 fps: the first lost frame, then every 3rd
    assert len(lost) >= 6 and scanned == lost[::3]
    lost, scanned = _scans(ColorPfConfig(), 100_000_000)  # 10 fps: every lost frame (a tenth of a second apart)
    assert len(lost) >= 3 and scanned == lost
    lost, scanned = _scans(ColorPfConfig(redetect=RedetectConfig(every=1)), 33_333_333)
    assert scanned == lost
