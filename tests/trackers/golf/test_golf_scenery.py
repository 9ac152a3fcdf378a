"""Still scenery (trackers/golf/scenery.py): a white thing that stayed put while the ball was
measured elsewhere is refused by the gate; the ball itself never becomes scenery."""

import dataclasses

import numpy as np

from trackreplay.schemas.records import InitRegion
from trackreplay.trackers.foreground.blobs import Blobs
from trackreplay.trackers.frame import Frame
from trackreplay.trackers.golf import GolfConfig, GolfTracker
from trackreplay.trackers.golf.blobs import REASONS
from trackreplay.trackers.golf.scenery import Scenery

NS = 33_333_333


def at(*points, side=3):
    """Blobs of ``side`` x ``side`` px centred at ``points``."""
    c = np.array(points, float).reshape(-1, 2)
    x0 = np.round(c - (side - 1) / 2).astype(np.int64)
    bbox = np.column_stack([x0, np.full((len(c), 2), side, np.int64)])
    return Blobs(c, np.full(len(c), side * side, float), np.full(len(c), np.nan), bbox, np.full((len(c), 3), np.nan))


def test_points_from_still_blobs_away_from_the_measured_ball():
    s = Scenery(still_px=1.5)
    s.update(0, at((100.0, 100.0), (200.0, 50.0)), True, (100.0, 100.0), 6.0, 1.0)
    assert len(s.points) == 0  # one frame: nothing is known to be still
    s.update(1, at((100.2, 100.1), (200.3, 50.2)), True, (100.2, 100.1), 6.0, 1.0)
    assert s.points.tolist() == [[200.3, 50.2]]  # the still ball is not scenery, the still thing away from it is
    assert s.on_scenery(at((200.0, 50.0), (205.0, 50.0), (201.0, 48.0)), 1.0).tolist() == [True, False, True]
    # (the third: its centroid moved 2 px, as a blob cut by the search region's edge; its pixels still hold the point)
    s.update(2, at((120.0, 90.0)), True, None, 6.0, 1.0)
    assert len(s.points) == 0  # nothing there any more: forgotten


def test_nothing_added_while_the_ball_is_not_measured_or_across_a_gap():
    s = Scenery(still_px=1.5)
    s.update(0, at((200.0, 50.0)), True, (100.0, 100.0), 6.0, 1.0)
    s.update(1, at((200.0, 50.0)), True, None, 6.0, 1.0)  # the ball not seen: where is it?
    assert len(s.points) == 0
    s.update(3, at((200.0, 50.0)), True, (100.0, 100.0), 6.0, 1.0)  # frame 2 missing
    assert len(s.points) == 0


def test_only_look_alikes_become_scenery():
    s = Scenery(still_px=1.5)
    blobs = at((200.0, 50.0), (300.0, 80.0))
    s.update(0, blobs, np.array([True, False]), (100.0, 100.0), 6.0, 1.0)
    s.update(1, blobs, np.array([True, False]), (100.0, 100.0), 6.0, 1.0)
    assert s.points.tolist() == [[200.0, 50.0]]  # a still speck the gate refuses anyway is no scenery


def test_points_follow_the_pose_change():
    s = Scenery(still_px=1.5)
    s.update(0, at((200.0, 50.0)), True, (100.0, 100.0), 6.0, 1.0)
    s.follow_camera(np.array([[1.0, 0.0, -7.0], [0.0, 1.0, 3.0], [0.0, 0.0, 1.0]]))
    s.update(1, at((193.0, 53.0)), True, (100.0, 100.0), 6.0, 1.0)  # the camera panned; the thing stayed
    assert np.allclose(s.points, [[193.0, 53.0]])


def _frames(backdrop, draw_ball, path, still_at):
    base = draw_ball(backdrop(), still_at, 5.0)  # a white disc as large as the ball, still all along
    mark = InitRegion(0, 0, path[0][0], path[0][1], 14, 14, "ball")
    return [Frame(k, k * NS, base if p is None else draw_ball(base, p, 5.0), hints=(mark,) if k == 0 else (),
                  all_hints=(mark,)) for k, p in enumerate(path)]


def test_a_still_look_alike_beside_the_path_is_not_taken_for_a_missed_ball(backdrop, draw_ball):
    # The ball flies right 8 px a frame past a still white disc 24 px below its path, and is not
    # drawn from frame 16 on (gone behind something): the disc, in the gate, is not the ball.
    path = [(300.0 + 8 * k, 250.0) for k in range(16)] + [None] * 10
    frames = _frames(backdrop, draw_ball, path, (424.0, 274.0))

    def run(config):
        tracker = GolfTracker(config, np.random.default_rng(0))
        return [(tracker.step(f), tracker.intermediates) for f in frames]

    on = run(GolfConfig())
    assert [s[0].status for s, _ in on[:16]].count("measured") >= 14
    assert all(s[0].status != "measured" for s, _ in on[16:])
    refused = [i for _, i in on[16:] if (i.blobs.reason == REASONS.index("still")).any()]
    assert refused  # refused as still scenery, visibly in the intermediates
    # without it (and without the world behind the ball, trackers/golf/world_behind.py, which refuses the disc too)
    off = run(GolfConfig(validate=dataclasses.replace(GolfConfig().validate, still_px=0.0),
                         world_behind=dataclasses.replace(GolfConfig().world_behind, frames=0)))
    wrong = [s[0] for s, _ in off[16:] if s[0].status == "measured"]
    assert wrong and all(abs(s.y - 274.0) < 2 for s in wrong)  # without it: the disc, measured
