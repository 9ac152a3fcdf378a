"""What a row without support may say ([colorpf.support], colorpf.support; issue 31): the box does not
grow, the track turns lost after lost_unsupported frames, the confidence of "predicted" rows falls."""

import dataclasses

import numpy as np
import pytest

from trackreplay.replay.core.config import config_from_dict
from trackreplay.schemas.records import InitRegion
from trackreplay.trackers.colorpf.config import PAPER, ColorPfConfig, SupportConfig
from trackreplay.trackers.colorpf.support import Support
from trackreplay.trackers.colorpf.tracker import ColorPfTracker
from trackreplay.trackers.frame import Frame

FRAMES, SIDE = 70, 7  # a 7x7 mark: under min_box_pixels, so the colour never vouches ("predicted" at best)


def _small_target() -> list[np.ndarray]:
    """A red 7x7 square moving right at 1 px per frame over a grey, noisy floor."""
    rng = np.random.default_rng(0)
    floor = np.clip(rng.normal(120, 6, (120, 200, 3)), 0, 255).astype(np.uint8)
    images = []
    for i in range(FRAMES):
        image = floor.copy()
        image[56:56 + SIDE, 40 + i:40 + i + SIDE] = (30, 30, 160)
        images.append(image)
    return images


def _rows(support: SupportConfig, inflate_at: int | None = None) -> list:
    """The track's row per frame; ``inflate_at``: before that frame's step, the cloud and S' are made 3x
    larger per side (as a measured camera zoom or the aspect stage would change them, with nothing seeing
    the target)."""
    mark = InitRegion(0, 0, 40 + SIDE / 2 - 0.5, 56 + SIDE / 2 - 0.5, SIDE, SIDE, "target")
    # the colour's confidence and how it falls (calibrate would report a probability instead)
    tracker = ColorPfTracker(ColorPfConfig(support=support, calibrate=False), np.random.default_rng(0))
    rows = []
    for i, image in enumerate(_small_target()):
        if i == inflate_at:
            tracker.pf.particles[:, 2:4] *= 3.0
            tracker.size.area0 *= 9.0
        states = tracker.step(Frame(index=i, t_ns=i * 33_333_333, image=image, all_hints=(mark,),
                                    hints=(mark,) if i == 0 else ()))
        rows.append(states[0])
    return rows


def test_the_support_unit():
    s = Support(np.array([10.0, 20.0]))
    assert s.shrink(np.array([5.0, 10.0])) == 1.0 and s.shrink(np.array([20.0, 20.0])) == 0.5
    assert s.shrink(np.array([10.0, 40.0])) == 0.5  # the aspect kept, both sides within
    s.note(False, np.array([99.0, 99.0]))
    assert s.unsupported == 1 and list(s.wh) == [10.0, 20.0]  # an unsupported box is not remembered
    assert s.confidence(0.9, 4) == pytest.approx(0.9 * 0.75) and s.confidence(0.9, None) == 0.9
    assert not s.expired(2) and not s.expired(None)
    s.note(False, np.zeros(2))
    assert s.expired(2)
    s.note(True, np.array([12.0, 24.0]))
    assert s.unsupported == 0 and list(s.wh) == [12.0, 24.0] and s.confidence(0.9, 4) == 0.9


def test_a_track_without_support_turns_lost_after_the_stated_frames():
    rows = _rows(SupportConfig(lost_unsupported=20))
    assert all(r.status == "predicted" for r in rows[1:20]), [r.status for r in rows[:25]]
    assert all(r.status == "lost" and r.x is None for r in rows[20:])  # from the 20th unsupported frame on
    before = _rows(SupportConfig(size_holds=False, lost_unsupported=0, confidence_falls=False))
    assert all(r.status == "predicted" for r in before[1:])  # before: "predicted" to the end, never lost


def test_the_confidence_of_predicted_rows_falls_without_support():
    rows = _rows(SupportConfig(lost_unsupported=20))
    before = _rows(SupportConfig(lost_unsupported=20, confidence_falls=False))
    falls = [r.confidence for r in rows[1:20]]
    assert all(c == pytest.approx(b.confidence * (1 - n / 20)) for n, (c, b) in enumerate(zip(falls, before[1:20]), 1))
    assert max(falls[-4:]) <= 0.2 * max(b.confidence for b in before[1:20])  # near 0 as the track turns lost
    assert min(b.confidence for b in before[1:20]) > 0.5  # the colour's own stays high (what it was before)


def test_a_held_box_does_not_grow_without_evidence():
    rows = _rows(SupportConfig(lost_unsupported=0), inflate_at=10)
    shown = [r for r in rows[1:] if r.x is not None]
    assert len(shown) > 15 and rows[10].status == "predicted"  # rows with a box after the inflation too
    assert all(r.w <= SIDE + 1e-9 and r.h <= SIDE + 1e-9 for r in shown), [(r.w, r.h) for r in rows[8:14]]
    grown = _rows(SupportConfig(size_holds=False, lost_unsupported=0), inflate_at=10)
    assert grown[10].w > 2 * SIDE and grown[10].h > 2 * SIDE  # without it the inflated box is reported


def test_paper_has_no_support_rules():
    paper = config_from_dict(ColorPfConfig, PAPER)
    assert paper.support == SupportConfig(size_holds=False, lost_unsupported=0, confidence_falls=False)
    assert dataclasses.replace(paper, support=ColorPfConfig().support).support == SupportConfig()
    with pytest.raises(ValueError):
        SupportConfig(lost_unsupported=-1)
