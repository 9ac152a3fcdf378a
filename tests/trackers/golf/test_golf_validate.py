"""The validation stage's tentative tracks under a moving camera, and the search region that reaches them."""

import cv2
import numpy as np
import pytest

from trackreplay.trackers.foreground.blobs import measure_blobs
from trackreplay.trackers.golf.blobs import AREA_LARGE, CIRCULARITY, ELONGATED, OK, GatedBlobs
from trackreplay.trackers.golf.config import BlobConfig, SearchConfig, ValidateConfig
from trackreplay.trackers.golf.search_region import reaching, search_region
from trackreplay.trackers.golf.validate import Validator

SIZE = (1280, 720)


def disc_at(x: float, y: float, radius: int = 4) -> GatedBlobs:
    mask = np.zeros(SIZE[::-1], np.uint8)
    cv2.circle(mask, (int(round(x)), int(round(y))), radius, 1, -1)
    blobs = measure_blobs(mask)
    return GatedBlobs(blobs, np.zeros(len(blobs.area), np.int64), -1, np.array([float(blobs.area[0]), 0.9]), 1.0)


def shift(dx: float) -> np.ndarray:
    return np.array([[1.0, 0.0, dx], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])


def verdicts(pans: list[float], follow: bool) -> list[str]:
    """A ball still against the world while the camera sweeps ``pans[k]`` px right before frame k
    (slowing down: the ball's image steps shrink 60, 30, 10 px). The track is lost (every sighting
    is tentative evidence); ``follow``: the validator is told each pose change."""
    validator = Validator(ValidateConfig(), BlobConfig())
    x, out = 700.0, []
    for k, pan in enumerate(pans):
        x -= pan
        if follow and k:
            validator.follow_camera(shift(-pan))
        check = validator.validate(index=k, gated=disc_at(x, 300.0), predicted=np.array([640.0, 360.0]),
                                   spread=np.full(2, 50.0), diameter=9.0, size=SIZE, scale=1.0, lost=True)
        out.append(check.verdict)
    return out


def test_tentative_tracks_follow_the_camera_sweep():
    pans = [0.0, 60.0, 30.0, 10.0]
    assert verdicts(pans, follow=True)[2] == "confirmed"  # still against the world: three sightings agree
    # Extrapolated in raw image pixels the slowing sweep bends the track 30 px off (> 12 px + D):
    assert "confirmed" not in verdicts(pans, follow=False)[:3]


def test_follow_camera_carries_the_points_not_the_rows_as_seen():
    validator = Validator(ValidateConfig(), BlobConfig())
    for k, x in enumerate((500.0, 520.0)):
        validator.validate(index=k, gated=disc_at(x, 200.0), predicted=np.array([640.0, 360.0]), spread=np.full(2, 50.0),
                           diameter=9.0, size=SIZE, scale=1.0, lost=True)
    validator.follow_camera(shift(-15.0))
    track = validator.best
    assert [r[1] for r in track.rows] == [500.0, 520.0]  # as each frame saw them (shown, velocity)
    assert np.allclose([p[0] for p in track.in_view], [485.0, 505.0])
    point, reach = validator.next_point(9.0, 1.0)
    assert np.allclose(point, [525.0, 200.0]) and reach == ValidateConfig().confirm_px + 9.0


def test_search_region_reaches_the_next_tentative_point():
    cfg = SearchConfig()
    region = search_region(np.array([640.0, 400.0]), np.array([10.0, 10.0]), 8.0, *SIZE, 1.0, cfg)
    x0, y0, w, h = region.box
    grown = reaching(region, np.array([640.0, 200.0]), 20.0, *SIZE)
    gx0, gy0, gw, gh = grown.box
    assert gy0 == 180.0 and gy0 + gh == y0 + h and gx0 == x0 and gw == w  # grown up to hold 200 +- 20, nothing else
    assert grown.centre is region.centre and grown.spread is region.spread  # the gate is still the samples'
    assert reaching(region, np.array([640.0, 400.0]), 5.0, *SIZE) is region  # already inside: unchanged
    edge = reaching(region, np.array([5.0, 5.0]), 40.0, *SIZE)
    assert edge.box[0] == 0.0 and edge.box[1] == 0.0  # clipped to the frame



def _ball_over_a_liner(refused_as: int) -> tuple[GatedBlobs, int]:
    """The ball (r 9) on the prediction merged with a flat oval (the cup's white liner) into one blob
    refused (``refused_as``), and a piece of the liner 30 px off it that the gate accepts."""
    mask = np.zeros(SIZE[::-1], np.uint8)
    cv2.circle(mask, (400, 300), 9, 1, -1)
    cv2.ellipse(mask, (406, 294), (20, 4), 0, 0, 360, 1, -1)
    cv2.ellipse(mask, (372, 287), (7, 5), 0, 0, 360, 1, -1)  # the liner's piece beside it
    blobs = measure_blobs(mask)
    piece = int(np.argmin(blobs.area))
    reason = np.full(len(blobs.area), refused_as, np.int64)
    reason[piece] = OK
    return GatedBlobs(blobs, reason, -1, np.array([254.0, 0.9]), 1.0), piece


def test_a_piece_beside_a_ball_merged_with_scenery_is_not_measured():
    """(The approach clip's frame 208: the ball rolling over the cup's liner is one oval with it, refused
    as elongated; the liner's left part, smaller and a little farther from the prediction, passed the gate.)"""
    verdict = {}
    for refused_as in (ELONGATED, CIRCULARITY, AREA_LARGE):
        gated, piece = _ball_over_a_liner(refused_as)
        found, _, _ = Validator(ValidateConfig(), BlobConfig()).seen_in_gate(
            gated=gated, predicted=np.array([401.0, 298.0]), spread=np.full(2, 8.0), diameter=18.0, size=SIZE,
            scale=1.0, lost=False)
        assert found.candidate == piece and found.fit >= ValidateConfig().min_fit
        verdict[refused_as] = found.verdict
    assert verdict[ELONGATED] == verdict[CIRCULARITY] == "merged_nearer"  # shown in the Rerun view as the reason
    assert verdict[AREA_LARGE] == "measured"  # a blob refused for its size is no merged ball: the piece stands


def test_a_repeated_picture_is_no_new_sighting_for_a_confirmation():
    """A review: the approach clip retimed to 50 fps (30 fps pictures, some shown twice) confirmed ball
    and cup liner from three frames that were two pictures, then measured liner pieces after the ball
    dropped. A row taken on a frame that repeats the picture before it is no new sighting; a ball
    that merely moves less than a pixel (a far ball at 240 fps) is one."""
    from trackreplay.trackers.golf.config import BlobConfig, ValidateConfig
    from trackreplay.trackers.golf.validate import Tentative, Validator

    validator = Validator(ValidateConfig(), BlobConfig())
    shape = (20.0, 0.9)
    track = Tentative([(0, 10.0, 10.0)], [shape])
    track.add(1, (10.0, 10.0), shape, repeat=True)  # the same picture again
    track.add(2, (14.0, 10.5), shape)
    assert validator._fit(track, 1.0) == 0.0  # three frames, two pictures
    track.add(3, (18.0, 11.0), shape)
    assert validator._fit(track, 1.0) > 0.0  # the third distinct picture
    slow = Tentative([(0, 10.0, 10.0)], [shape])
    slow.add(1, (10.0, 10.0), shape)  # the same place, but a new picture (noise, other things moved)
    slow.add(2, (10.0, 10.0), shape)
    assert validator._fit(slow, 1.0) > 0.0


def test_a_ball_predicted_beyond_the_edge_is_only_what_the_edge_cuts():
    """A review: an iron shot climbed slowly out through the top (its samples' mean 1.4 px above the
    picture, less than a diameter), and the corner of a broadcast's white logo box 11 px below the edge,
    14 px from the prediction and inside the gate, was measured for the 44 frames after it left."""
    from trackreplay.trackers.golf.validate import cut_by_edge

    validator = Validator(ValidateConfig(), BlobConfig())
    predicted = np.array([622.5, -1.4])
    ask = dict(predicted=predicted, spread=np.full(2, 8.0), diameter=4.0, size=SIZE, scale=1.0, lost=False)
    corner = disc_at(631.0, 12.0, radius=2)
    found, in_gate, outside = validator.seen_in_gate(gated=corner, **ask)
    assert found is None and not in_gate.any() and outside  # the ball left: nothing inside is it
    assert validator.validate(index=0, gated=corner, **ask).verdict == "outside_image"
    leaving = disc_at(622.0, 1.0, radius=2)  # what is left of the ball at the edge
    found, _, outside = validator.seen_in_gate(gated=leaving, **ask)
    assert found is not None and found.verdict == "measured" and not outside
    inside = dict(ask, predicted=np.array([622.5, 3.0]))  # the prediction still in the picture: unchanged
    found, _, _ = validator.seen_in_gate(gated=corner, **inside)
    assert found is not None and found.candidate == 0
    boxes = np.array([[0, 100, 5, 5], [100, 0, 5, 5], [1275, 100, 5, 5], [100, 715, 5, 5], [100, 100, 5, 5]], float)
    for k, point in enumerate(([-3.0, 100.0], [100.0, -3.0], [1282.0, 100.0], [100.0, 722.0])):
        assert cut_by_edge(boxes, np.array(point), SIZE, 1.0).tolist() == [j == k for j in range(5)]


def test_a_confirmed_velocity_counts_steps_between_distinct_pictures():
    """A review: a track confirmed on a clip retimed by repeating frames had a zero step on the repeated
    picture, and the last step plus its change doubled the velocity. A ball moving 4 px a picture,
    pictures shown 1, 2, 1, ... frames: about 4 px a frame over the distinct pictures, never 8."""
    from trackreplay.trackers.golf.config import BlobConfig, ValidateConfig
    from trackreplay.trackers.golf.validate import Tentative, Validator

    validator = Validator(ValidateConfig(), BlobConfig())
    shape = (20.0, 0.9)
    track = Tentative([(0, 10.0, 10.0)], [shape])
    track.add(1, (14.0, 10.0), shape)
    track.add(2, (14.0, 10.0), shape, repeat=True)  # the same picture again
    track.add(3, (18.0, 10.0), shape)
    validator.best = track
    velocity, unsure = validator.confirmed_velocity()
    assert velocity.tolist() == [8.0 / 3.0, 0.0]  # 8 px over 3 frames (was 8: 4 + (4 - 0))
    assert abs(unsure - 4.0 / 3.0) < 1e-12  # steps of 4 and 2 px a frame between the distinct pictures


def test_a_repeated_picture_long_ago_leaves_the_last_steps_alone():
    """A review: one repeated picture at a track's start switched a slowing ball's velocity to the mean
    over the whole track (11.2 px a frame against a next step of 4)."""
    from trackreplay.trackers.golf.config import BlobConfig, ValidateConfig
    from trackreplay.trackers.golf.validate import Tentative, Validator

    validator = Validator(ValidateConfig(), BlobConfig())
    shape = (20.0, 0.9)
    track = Tentative([(0, 0.0, 0.0)], [shape])
    track.add(1, (0.0, 0.0), shape, repeat=True)
    x = 0.0
    for k, step in enumerate((20.0, 16.0, 12.0, 8.0), start=2):
        x += step
        track.add(k, (x, 0.0), shape)
    validator.best = track
    velocity, unsure = validator.confirmed_velocity()
    assert velocity.tolist() == [4.0, 0.0] and unsure == 4.0


def discs_at(*points: tuple[float, ...], radius: int = 4) -> GatedBlobs:
    """Discs at ``points`` (x, y, or x, y, radius); the targets are the first disc's."""
    mask = np.zeros(SIZE[::-1], np.uint8)
    for point in points:
        x, y, r = (*point, radius) if len(point) == 2 else point
        cv2.circle(mask, (int(round(x)), int(round(y))), int(r), 1, -1)
    blobs = measure_blobs(mask)
    return GatedBlobs(blobs, np.zeros(len(blobs.area), np.int64), -1, np.array([float(blobs.area[0]), 0.9]), 1.0)


def after_a_mark(frames: list[tuple[tuple[float, float], ...]], mark: tuple[float, float] = (400.0, 300.0)) -> list[str]:
    """Marked at ``mark`` on frame 0 (measured there), then the blobs of each later frame, the
    prediction staying at the mark (a single mark gives no velocity)."""
    validator = Validator(ValidateConfig(), BlobConfig())
    validator.seed_at(0, mark)
    out = []
    for k, points in enumerate([(mark,)] + frames):
        check = validator.validate(index=k, gated=discs_at(*points), predicted=np.array(mark), spread=np.full(2, 20.0),
                                   diameter=9.0, size=SIZE, scale=1.0, lost=False)
        out.append(check.verdict)
    return out


def test_a_blob_away_from_the_mark_is_no_measurement_until_a_track_from_the_mark_confirms():
    # The shuttle leaves the mark at 40 px a frame, unseen on frame 1; a player's shoe 30 px from the
    # mark, nearer the prediction than the shuttle, is seen on frames 1-2 and then hidden.
    shoe = (390.0, 330.0)
    verdicts = after_a_mark([(shoe,), (shoe, (480.0, 300.0)), ((520.0, 300.0),), ((560.0, 300.0),)])
    assert verdicts[0] == "measured"  # the mark's own frame
    assert verdicts[1] == "unconfirmed"  # the shoe, nearest the prediction, is not measured on a guess
    assert "measured" not in verdicts[1:3]
    assert verdicts[3] == "confirmed"  # mark -> 480 (two frames) -> 520, and no other path from the mark alive


def test_a_path_from_the_mark_waits_while_another_one_lives():
    # as above, but the shoe stays in view: two paths leave the mark, neither is taken; nor is a
    # look-alike far from the mark moving steadily (out of the paths' reach: no path from the mark),
    # though its own tentative track is long enough to confirm once the ball's speed is known
    shoe = (390.0, 330.0)
    far = [(1100.0 + 10 * k, 600.0) for k in range(5)]
    verdicts = after_a_mark([(shoe, far[1]), (shoe, (480.0, 300.0), far[2]), (shoe, (520.0, 300.0), far[3]),
                             (shoe, (560.0, 300.0), far[4])])
    assert "confirmed" not in verdicts and "measured" not in verdicts[1:]


def test_a_ball_seen_at_its_mark_is_measured_at_once():
    assert after_a_mark([((401.0, 300.0),), ((400.0, 301.0),)]) == ["measured", "measured", "measured"]


def test_two_paths_from_the_mark_confirm_neither():
    # two look-alikes leave the mark in opposite directions at the same speed
    frames = [((400.0 + 40 * k, 300.0), (400.0 - 40 * k, 300.0)) for k in range(1, 4)]
    verdicts = after_a_mark(frames)
    assert "confirmed" not in verdicts and "measured" not in verdicts[1:]


def test_while_the_speed_is_unknown_no_track_elsewhere_is_confirmed():
    # The ball is unseen for two frames after its mark, then seen 120 px away (a path from the mark
    # starts, not yet ready); a look-alike far from the mark has moved steadily for three frames.
    far = [(1100.0 + 10 * k, 600.0, 10) for k in range(4)]  # (five times the ball's area: no look-alike)
    verdicts = after_a_mark([(far[1],), (far[2],), ((520.0, 300.0), far[3])])
    assert verdicts[3] != "confirmed"  # a track elsewhere does not win because the ball's own path is young


def test_after_a_loss_a_ball_sized_blob_in_view_keeps_a_bigger_track_from_confirmation():
    # The rally is over: the shuttle lies on the floor of a fixed view (the ball's size, still: never
    # confirmed itself), and a player's white shoe, five times its area, walks steadily across the
    # picture. The shoe's track agrees with itself, but a blob that looks like the ball as last seen
    # is in view: which is the ball is not known.
    def run(with_shuttle: bool) -> list[str]:
        validator = Validator(ValidateConfig(), BlobConfig())
        out = []
        for k in range(5):
            shoe = (600.0 + 6 * k, 500.0, 9)
            points = ((900.0, 600.0), shoe) if with_shuttle else (shoe,)
            gated = discs_at(*points)
            gated = GatedBlobs(gated.blobs, gated.reason, -1, np.array([50.0, 0.9]), 1.0)  # the ball as last seen
            check = validator.validate(index=k, gated=gated, predicted=np.array([640.0, 360.0]), spread=np.full(2, 50.0),
                                       diameter=8.0, size=SIZE, scale=1.0, lost=True, entry_only=True)
            out.append(check.verdict)
        return out

    assert "confirmed" in run(with_shuttle=False)  # alone in view, a steady track is taken after a loss
    verdicts = run(with_shuttle=True)
    assert "confirmed" not in verdicts and "ambiguous" in verdicts


def test_the_gate_is_never_wider_than_a_quarter_of_the_picture():
    # A ball 32 px across on a 320x240 hand-held clip: its size scales the gate's spread (scale 2), and
    # a white cabinet 100 px from the prediction was inside it. The gate stops at 240 / 4 = 60 px.
    size = (320, 240)
    validator = Validator(ValidateConfig(), BlobConfig())
    s, radius = validator.gate(np.full(2, 50.0), 32.0, 2.0, size)
    assert radius == pytest.approx(60.0) and s == pytest.approx(60.0 / ValidateConfig().gate_sigmas)
    assert validator.gate(np.full(2, 50.0), 32.0, 2.0)[1] > 200.0  # without the picture: the spread's own gate
    mask = np.zeros(size[::-1], np.uint8)
    cv2.circle(mask, (250, 60), 14, 1, -1)  # the cabinet, 100 px from the prediction (190, 140)
    blobs = measure_blobs(mask)
    gated = GatedBlobs(blobs, np.zeros(1, np.int64), -1, np.array([float(blobs.area[0]), 0.9]), 1.0)
    found, in_gate, _ = validator.seen_in_gate(gated=gated, predicted=np.array([190.0, 140.0]), spread=np.full(2, 50.0),
                                               diameter=32.0, size=size, scale=2.0, lost=False)
    assert found is None and not in_gate.any()
    wide = validator.seen_in_gate(gated=gated, predicted=np.array([190.0, 140.0]), spread=np.full(2, 50.0),
                                  diameter=32.0, size=(1280, 960), scale=2.0, lost=False)[0]
    assert wide is not None and wide.verdict == "measured"  # the same blob in a picture four times as large


def _discs(*discs: tuple[float, float, int]) -> GatedBlobs:
    """Shape-accepted discs ``(x, y, radius)``; the targets are the first disc's area."""
    mask = np.zeros(SIZE[::-1], np.uint8)
    for x, y, r in discs:
        cv2.circle(mask, (int(x), int(y)), r, 1, -1)
    blobs = measure_blobs(mask)
    first = int(np.argmin(np.hypot(blobs.centroid[:, 0] - discs[0][0], blobs.centroid[:, 1] - discs[0][1])))
    return GatedBlobs(blobs, np.zeros(len(blobs.area), np.int64), -1, np.array([float(blobs.area[first]), 0.9]), 1.0)


def _seen(gated: GatedBlobs, spread: float = 8.0):
    found, _, _ = Validator(ValidateConfig(), BlobConfig()).seen_in_gate(
        gated=gated, predicted=np.array([600.0, 300.0]), spread=np.full(2, spread), diameter=9.0, size=SIZE, scale=1.0,
        lost=False)
    return found


def test_two_pieces_of_one_ball_are_not_look_alikes():
    # A ball split in two by a seam's shadow (the approach clip turned upside down): the pieces lie
    # within a diameter of each other, so the nearest keeps the confidence it has alone.
    alone = _seen(_discs((606.0, 300.0, 3)))
    pieces = _seen(_discs((606.0, 300.0, 3), (614.0, 300.0, 2)))
    assert pieces.verdict == "measured" and pieces.confidence == pytest.approx(alone.confidence)


def test_a_look_alike_in_the_gate_shares_the_confidence():
    """The confidence is the chosen blob's fit times motion times its share of the in-gate blobs' (the
    association probability among them): with a twin as near the prediction the track cannot tell which
    one is its ball, and each holds half (a shuttle among a player's white socks and shoes)."""
    alone = _seen(_discs((620.0, 300.0, 4)))
    twins = _seen(_discs((620.0, 300.0, 4), (580.0, 300.0, 4)))
    assert alone.verdict == "measured"
    assert twins.confidence == pytest.approx(alone.confidence / 2.0, rel=0.05)
    assert twins.verdict == "low_confidence"  # below min_confidence: "predicted", nothing learns from either
