"""One camera over a ground plane as the group tracker's depth source (trackers/groups/ground_depth.py):
a known camera's homography gives back the camera, and a region standing on the ground gets the
depth of a vertical person at its foot point."""

import numpy as np
import pytest

from trackreplay.trackers.geometry.ground_plane import GroundPlane
from trackreplay.trackers.groups.config import GroundConfig
from trackreplay.trackers.groups.ground_depth import GroundDepth, focal_from_homography, ground_rig, region_feet

W, H_IMG, F, HEIGHT, TILT = 160, 120, 150.0, 4.0, np.radians(30.0)
CENTRE = np.array([1.0, -2.0, HEIGHT])  # the camera, metres (ground frame, Z up), looking along +Y


def _camera() -> tuple[np.ndarray, np.ndarray]:
    """K and the world → camera rotation of a camera tilted down by TILT."""
    z = np.array([0.0, np.cos(TILT), -np.sin(TILT)])
    x = np.array([1.0, 0.0, 0.0])
    R_cw = np.stack([x, np.cross(z, x), z], axis=1)
    K = np.array([[F, 0.0, (W - 1) / 2], [0.0, F, (H_IMG - 1) / 2], [0.0, 0.0, 1.0]])
    return K, R_cw.T


def _project(points: np.ndarray) -> np.ndarray:
    K, R_wc = _camera()
    p = (points - CENTRE) @ R_wc.T @ K.T
    return p[:, :2] / p[:, 2:]


def _plane() -> GroundPlane:
    K, R_wc = _camera()
    G = K @ np.stack([R_wc[:, 0], R_wc[:, 1], -R_wc @ CENTRE], axis=1)
    return GroundPlane(np.linalg.inv(G), camera_ground=(1.0, -2.0), camera_height=HEIGHT)


def test_the_homography_gives_back_the_camera() -> None:
    plane = _plane()
    assert focal_from_homography(plane.ground_to_image, ((W - 1) / 2, (H_IMG - 1) / 2)) == pytest.approx(F, rel=1e-6)
    rig = ground_rig(plane, (H_IMG, W))
    assert rig.f == pytest.approx(F, rel=1e-6) and rig.baseline == pytest.approx(HEIGHT, rel=1e-5)
    np.testing.assert_allclose(rig.pose.t, CENTRE, atol=1e-4)
    _, R_wc = _camera()
    np.testing.assert_allclose(rig.pose.R, R_wc.T, atol=1e-5)


def test_a_left_handed_ground_frame_is_refused() -> None:
    mirrored = GroundPlane(np.diag([1.0, -1.0, 1.0]) @ _plane().image_to_ground)
    with pytest.raises(ValueError, match="left-handed"):
        ground_rig(mirrored, (H_IMG, W))


def test_a_standing_region_gets_a_vertical_person_at_its_foot() -> None:
    """A person 1.8 m tall standing at a known ground point: the region drawn from its projection gets,
    through the virtual disparity, 3-D points on the ground under it and up to about its height."""
    foot = np.array([1.5, 6.0, 0.0])
    corners = _project(np.array([foot + [-0.25, 0, 0], foot + [0.25, 0, 0], foot + [-0.25, 0, 1.8], foot + [0.25, 0, 1.8]]))
    x0, y0 = np.floor(corners.min(axis=0)).astype(int)
    x1, y1 = np.floor(corners.max(axis=0)).astype(int)
    background = np.full((H_IMG, W, 3), 90, np.uint8)
    depth = GroundDepth(GroundConfig(open_px=0, close_px=0, min_area_px=10), frames=10)
    for _ in range(10):  # (MOG2 calls a change after 3 frames a shadow: its weights are not settled)
        depth.add(background)
    depth.start(10.0)
    person = background.copy()
    person[y0:y1 + 1, x0:x1 + 1] = 220
    view = depth.observe(person, _plane())
    assert view.fg_left[y0:y1 + 1, x0:x1 + 1].all() and view.fg_left.sum() == (y1 - y0 + 1) * (x1 - x0 + 1)
    assert view.crops.tolist() == [[x0, y0, x1 + 1, y1 + 1]] and not view.fg_right.any()
    rig = depth.rig
    v, u = np.nonzero(view.fg_left)
    world = rig.pose.to_world(rig.to_points(np.stack([u, v, view.disparity[v, u]], axis=1)))
    (foot_px,) = region_feet(np.array([[x0, y0, x1 - x0 + 1, y1 - y0 + 1]]))
    np.testing.assert_allclose(_plane().to_ground(foot_px[None])[0], foot[:2], atol=0.1)  # the box's bottom edge
    np.testing.assert_allclose(world[:, 1], foot[1], atol=0.1)  # every pixel on the person's vertical plane
    assert world[:, 2].min() == pytest.approx(0.0, abs=0.1) and world[:, 2].max() == pytest.approx(1.8, abs=0.1)
    assert np.isnan(view.disparity[~view.fg_left]).all()


def test_the_virtual_disparity_is_the_foot_rows_below_the_horizon_for_a_level_camera() -> None:
    """Why ground.sigma_foot_px is in pixels: baseline = height, so d = f h / z = v_foot - v_horizon."""
    rig = ground_rig(_plane(), (H_IMG, W))
    z = 8.0
    assert rig.f * rig.baseline / z == pytest.approx(F * HEIGHT / z)  # level camera: v - cy = f h / z


@pytest.mark.parametrize("foot", ["box", "column"])
def test_two_people_side_by_side_in_one_region(foot) -> None:
    """A near and a farther person the foreground joins into one region: with ``foot = "box"`` both
    stand at the region's box foot (the nearer one's row); with ``"column"`` each at their own."""
    near, far = np.array([0.6, 6.0, 0.0]), np.array([1.9, 7.5, 0.0])
    background = np.full((H_IMG, W, 3), 90, np.uint8)
    image = background.copy()
    boxes = []
    for p in (near, far):
        c = _project(np.array([p + [-0.25, 0, 1.8], p + [0.25, 0, 0.0]]))
        x0, y0 = np.floor(c[0]).astype(int)
        x1, y1 = np.floor(c[1]).astype(int)
        image[y0:y1 + 1, x0:x1 + 1] = 220
        boxes.append((x0, y0, x1, y1))
    (_, _, nx1, ny1), (fx0, fy0, _, fy1) = boxes
    assert fx0 > nx1 + 2  # apart in the picture: joined by a thin bridge at waist height
    image[fy0 + 12, nx1:fx0 + 1] = 220
    depth = GroundDepth(GroundConfig(open_px=0, close_px=0, min_area_px=10, foot=foot), frames=10)
    for _ in range(10):
        depth.add(background)
    depth.start(10.0)
    view = depth.observe(image, _plane())
    rig = depth.rig
    depths = {}
    for name, (x0, y0, x1, y1) in zip(("near", "far"), boxes):
        sub = view.disparity[y0:y1 + 1, x0:x1 + 1]
        v, u = np.nonzero(np.isfinite(sub))
        pts = rig.pose.to_world(rig.to_points(np.stack([u + x0, v + y0, sub[v, u]], axis=1)))
        depths[name] = float(np.median(pts[:, 1]))
    assert depths["near"] == pytest.approx(near[1], abs=0.15)
    assert depths["far"] == pytest.approx(far[1] if foot == "column" else near[1], abs=0.15)


def _learnt(cfg: GroundConfig, background: np.ndarray) -> GroundDepth:
    depth = GroundDepth(cfg, frames=10)
    for _ in range(10):  # (MOG2 calls a change after 3 frames a shadow: its weights are not settled)
        depth.add(background)
    depth.start(10.0)
    return depth


def _rows(foot: np.ndarray, low: float, high: float) -> tuple[int, int, int, int]:
    """The pixel box x0 y0 x1 y1 of a 0.5 m wide person at ``foot`` from ``low`` to ``high`` metres up."""
    c = _project(np.array([foot + [-0.25, 0, high], foot + [0.25, 0, low]]))
    x0, y0 = np.floor(c[0]).astype(int)
    x1, y1 = np.floor(c[1]).astype(int)
    return x0, y0, x1, y1


def _ground_y(depth: GroundDepth, view, box: tuple[int, int, int, int]) -> np.ndarray:
    """World Y (m, along the view) of every foreground pixel in ``box`` (x0 y0 x1 y1, inclusive)."""
    x0, y0, x1, y1 = box
    sub = view.disparity[y0:y1 + 1, x0:x1 + 1]
    v, u = np.nonzero(np.isfinite(sub))
    rig = depth.rig
    return rig.pose.to_world(rig.to_points(np.stack([u + x0, v + y0, sub[v, u]], axis=1)))[:, 1]


CLEAN = {"open_px": 0, "close_px": 0, "min_area_px": 10}


@pytest.mark.parametrize("check", [True, False])
def test_legs_taken_for_shadow_stand_the_person_where_their_head_is(check) -> None:
    """A person 1.7 m tall (the standing stature) whose legs are as dark as a shadow on the ground (MOG2
    leaves them out): the region ends at the knees. Checked against a standing person it is too short,
    the rows under it are shadow, so it stands where its head puts it; unchecked, at its knees' ground
    point (metres too far)."""
    foot = np.array([1.0, 7.0, 0.0])
    background = np.full((H_IMG, W, 3), 90, np.uint8)
    image = background.copy()
    x0, y0, x1, y1 = _rows(foot, 0.0, 1.7)
    _, yk, _, _ = _rows(foot, 0.0, 0.8)
    image[y0:yk, x0:x1 + 1] = 220
    image[yk:y1 + 1, x0:x1 + 1] = 63  # 0.7 x the background, same colour: MOG2's shadow
    depth = _learnt(GroundConfig(**CLEAN, stature_check=check), background)
    view = depth.observe(image, _plane())
    assert depth.shadow[yk:y1 + 1, x0:x1 + 1].mean() > 0.9 and not view.fg_left[yk + 1:y1 + 1].any()
    y = _ground_y(depth, view, (x0, y0, x1, y1))
    if check:
        assert np.median(y) == pytest.approx(foot[1], abs=0.25)
    else:
        assert np.median(y) > foot[1] + 1.5


def test_a_person_whose_head_and_torso_faded_keeps_their_feet() -> None:
    """Only the legs are foreground (a person who stands still fades into MOG2's background from the top):
    as short, but nothing under the feet says they are missing, so the foot stays where it is."""
    foot = np.array([1.0, 7.0, 0.0])
    background = np.full((H_IMG, W, 3), 90, np.uint8)
    image = background.copy()
    x0, y0, x1, y1 = _rows(foot, 0.0, 0.8)
    image[y0:y1 + 1, x0:x1 + 1] = 220
    depth = _learnt(GroundConfig(**CLEAN), background)
    view = depth.observe(image, _plane())
    assert np.median(_ground_y(depth, view, (x0, y0, x1, y1))) == pytest.approx(foot[1], abs=0.15)


def test_a_person_cut_by_the_picture_s_bottom_edge_stands_where_their_head_is() -> None:
    """Feet below the picture: the lowest visible row would put the person metres too far; the region
    ends at the bottom edge, so the head rule places them."""
    background = np.full((H_IMG, W, 3), 90, np.uint8)
    bottom = _plane().to_ground(np.array([[W / 2, H_IMG - 0.5]]))[0]
    foot = np.array([bottom[0], bottom[1] - 0.6, 0.0])  # 0.6 m nearer than the picture's bottom edge
    x0, y0, x1, y1 = _rows(foot, 0.0, 1.7)
    assert y1 > H_IMG and y0 > 0
    image = background.copy()
    image[y0:, x0:x1 + 1] = 220
    depth = _learnt(GroundConfig(**CLEAN), background)
    view = depth.observe(image, _plane())
    assert np.median(_ground_y(depth, view, (x0, y0, x1, H_IMG - 1))) == pytest.approx(foot[1], abs=0.25)
    off = _learnt(GroundConfig(**CLEAN, stature_check=False), background)
    assert np.median(_ground_y(off, off.observe(image, _plane()), (x0, y0, x1, H_IMG - 1))) > foot[1] + 0.5


@pytest.mark.parametrize("check", [True, False])
def test_someone_behind_a_person_in_one_region_stands_behind(check) -> None:
    """Two people of the standing stature, one 4 m behind the other, joined into one region: the column is
    taller than anyone standing at the near foot, so its pixels above the near person's head stand where
    the column's top (the far one's head) puts them; unchecked, everyone stands at the near foot."""
    near, far = np.array([1.0, 6.0, 0.0]), np.array([1.0, 10.0, 0.0])
    background = np.full((H_IMG, W, 3), 90, np.uint8)
    image = background.copy()
    nx0, ny0, nx1, ny1 = _rows(near, 0.0, 1.7)
    fx0, fy0, fx1, fy1 = _rows(far, 0.0, 1.7)
    assert fy1 >= ny0 and fy0 < ny0 - 3  # the far one's feet meet the near one's head in the picture
    image[ny0:ny1 + 1, nx0:nx1 + 1] = 220
    image[fy0:fy1 + 1, fx0:fx1 + 1] = 220
    depth = _learnt(GroundConfig(**CLEAN, stature_check=check), background)
    view = depth.observe(image, _plane())
    above = _ground_y(depth, view, (fx0, fy0, fx1, ny0 - 2))  # the far person above the near one's head
    assert np.median(_ground_y(depth, view, (nx0, ny0 + 2, nx1, ny1))) == pytest.approx(near[1], abs=0.15)
    # (the head's row is whole pixels: at 10 m one row of this 160 x 120 camera is 0.3 m along the ground)
    assert np.median(above) == pytest.approx(far[1] if check else near[1], abs=0.45)
