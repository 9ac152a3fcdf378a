"""Group tracker with subtraction stereo (seed 003): ``GroupTracker``, name "groups".

Per stereo pair, the paper's pipeline (Fig. 2), one module per stage:

1. §2 background subtraction in both views (median of the first frames) and subtraction stereo:
   SGBM on foreground crops only (:mod:`.stereo_depth`). A log with one camera and a ground plane
   (``/camera/ground_plane``) and no stereo pair takes its depth from :mod:`.ground_depth` instead:
   MOG2 foreground, each region a standing person at its foot point's distance, read as the
   disparity of a virtual rig (baseline = the camera's height); every later stage is the same.
2. §3.1 KLT on the left foreground, 3-D from the disparity; observation points = features tracked
   over the whole time window (:mod:`.features`).
3. §3.2 each group's EKF predicts (:mod:`.ekf`).
4. §3.3 eq. (8) gate, eqs. (9)–(11) arg max of m_p·m_v (:mod:`.association`); a group with at
   least ``min_points`` points is updated with their mean ``[u v d]`` and its extent by eq. (7),
   else it only predicts.
5. Groups without an update for more than ``tracks.max_empty_frames`` frames are deleted (ours:
   the paper states no rule; the groups' life is :mod:`trackreplay.trackers.lifecycle`'s); with one
   camera, once the EKF no longer places them within ``tracks.ground_coast_sigma_m`` on the ground.
   With one camera a group keeps only the connected set of the points its gate took
   (``grouping.connected``, eq. 12's relation).
6. §3.4 initial grouping of the unassigned points (:mod:`.grouping`).
7. §3.5 merging of groups whose position and velocity regions overlap (:mod:`.merging`; eqs. 14–15
   by :func:`trackreplay.trackers.filters.gaussians.merge_gaussians`) and, ours, whose member points'
   own velocities agree across the line of sight (``merge.measured_velocity``); the merged group gets a new id.

Outputs per live group: X Y Z the EKF position (metres) in the world frame (Z up) when the log
carries the rig's pose (``/stereo/pose``, ``position_frame == "world"``) or a ground plane (the
ground's frame: X Y on the ground as the plane gives them, Z up), else in the left camera's
frame (x right, y down, z forward; ``"camera"``) — the EKF itself runs in the camera frame, as in
the paper; the image box of the foreground pixels whose 3-D points fall in the group's gate
(else the projected extent), vx vy the projected EKF velocity (px/frame); "measured" when updated
this frame, "predicted" otherwise; one "lost" row (no position) on the frame a group is deleted or
merged into another. ``intermediates.extra_rows()`` gives the member count, 3-D velocity and
extent covariance (the second table, docs/groups.md).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from trackreplay.trackers.appearance.color import to_grey
from trackreplay.trackers.base import TrackerBase, TrackState
from trackreplay.trackers.filters.gaussians import merge_gaussians
from trackreplay.trackers.filters.gating import mahalanobis_sq
from trackreplay.trackers.frame import Frame
from trackreplay.trackers.geometry.stereo import StereoRig
from trackreplay.trackers.groups.association import associate
from trackreplay.trackers.groups.config import EkfConfig, GroupsConfig
from trackreplay.trackers.groups.ekf import POS, VEL, GroupEkf, state_from
from trackreplay.trackers.groups.features import KltFeatures, ObservationPoints
from trackreplay.trackers.groups.ground_depth import DepthView, GroundDepth
from trackreplay.trackers.groups.grouping import initial_groups
from trackreplay.trackers.groups.intermediates import GroupsIntermediates, GroupSnapshot
from trackreplay.trackers.groups.merging import measured_velocities, merge_overlap, merge_sets
from trackreplay.trackers.groups.stereo_depth import StereoDepth
from trackreplay.trackers.lifecycle import TrackLife

GROUND_NOTICE = ("one camera: depth from the ground plane (each foreground region's people stand at their feet's "
                 "distance; heights and people one behind the other are not seen, docs/groups_pets.md)")
NO_STEREO = ("the log has no stereo pair with calibration (/stereo/{left,right}/image and calibration) and no ground "
             "plane (/camera/ground_plane): groups tracker idle")


@dataclass
class Group:
    gid: int
    ekf: GroupEkf
    extent: np.ndarray  # Σ, 3×3 position extent (eq. 7)
    velocity_spread: np.ndarray  # the same on the points' velocities
    members: int
    life: TrackLife  # its frames without an update (trackers.lifecycle): deleted once lost
    status: str = "measured"
    merged_from: str = ""
    hits: int = 0  # frames it was measured on (confirmed from merge.frames on: grouping.near_gate)
    coasted: int = 0  # frames in a row without an update
    box: np.ndarray = field(default_factory=lambda: np.full(4, np.nan))

    @property
    def position(self) -> np.ndarray:
        return self.ekf.x[POS]

    @property
    def velocity(self) -> np.ndarray:
        return self.ekf.x[VEL]


def _cov(values: np.ndarray) -> np.ndarray:
    if len(values) < 2:
        return np.zeros((3, 3))
    d = values - values.mean(axis=0)
    return d.T @ d / (len(values) - 1)


class GroupTracker(TrackerBase):
    """Seed 003 (docs/papers.md §4). ``step(frame)`` returns one state per live or just-ended group."""

    name = "groups"  # what the replay needs of it (a stereo pair) is declared in trackers/groups/__init__.py

    def __init__(self, config: GroupsConfig, rng: np.random.Generator) -> None:
        self.user_config = config
        self.config = config  # rescaled to the log's frame rate when the background is learnt (config.at_rate)
        self.fps = float("nan")
        # "world" when the log carries the rig's pose (/stereo/pose: X Y Z, the second table's
        # velocities and extents in the world frame, Z up), else "camera" (the left camera's frame)
        self.position_frame = "camera"
        self.pose = None
        self.learn_t: list[int] = []
        self.rng = rng  # handed in by the engine; nothing here is random
        self.stereo = StereoDepth(config)
        self.ground = GroundDepth(config.ground, config.background.frames)
        self.source = ""  # "stereo" or "ground": the depth source, chosen on the first frame with one
        self.learnt = False
        self.klt = KltFeatures(config.klt, config.stereo.disparity_window)
        self.groups: list[Group] = []
        self.next_id = 1
        self.pair_frames: dict[tuple[int, int], int] = {}
        self.contested = np.zeros(0, bool)  # this frame's points gated by two or more groups (§3.3)
        self.held_out = np.zeros(0, bool)  # this frame's points that may not start a group (grouping.near_gate)
        self.prev_t: int | None = None
        self.intermediates = GroupsIntermediates.idle("idle", (1, 1))

    # --- the pipeline -------------------------------------------------------------------------

    def step(self, frame: Frame) -> list[TrackState]:
        """Per stereo pair (Fig. 2): §2 the background is learnt first; then foreground, subtraction
        stereo and observation points (§2-§3.1), predict (§3.2), associate and update (§3.3), delete the
        lost, start groups (§3.4), merge (§3.5), the groups' image boxes and the rows."""
        shape = frame.image.shape[:2]
        rig = self._rig(frame)
        if rig is None:
            return []
        self.position_frame = "world" if rig.pose is not None else "camera"
        self.pose = rig.pose
        dt_s = (frame.t_ns - self.prev_t) / 1e9 if self.prev_t is not None else float("nan")
        self.prev_t = frame.t_ns
        if not self.learnt:  # §2: learn the background (of both views)
            window = self.config.klt.window  # (the window before the rate is known, on the last such frame too)
            self._learn(frame)
            self.intermediates = GroupsIntermediates.idle("learning", shape, "", window)
            return []
        view = self._observe(frame)
        points = self.klt.observation_points(rig)
        for g in self.groups:  # §3.2
            g.ekf.predict()
        labels = self._associate_and_update(points, rig)  # §3.3
        labels, ended, events = self._delete(labels)
        labels = self._start_groups(points, labels, rig, events)  # §3.4
        labels, merged = self._merge(labels, events, points)  # §3.5
        ended = np.array(sorted(ended + merged), np.int64)
        self._boxes(view.disparity, rig)
        point_ids = np.array([self.groups[j].gid if j >= 0 else -1 for j in labels.tolist()], np.int64)
        snapshot = self._snapshot()
        self.intermediates = GroupsIntermediates(
            "tracking", view.fg_left, view.fg_right, view.disparity, view.crops, self.klt.uv.copy(), points, point_ids,
            snapshot, ended, tuple(events), dt_s, notice=GROUND_NOTICE if self.source == "ground" else "", world=rig.pose,
            rig=rig)
        states = [self._state(g, rig) for g in self.groups]
        states += [TrackState(int(gid), status="lost") for gid in ended.tolist()]
        return sorted(states, key=lambda s: s.track_id)

    def _rig(self, frame: Frame) -> StereoRig | None:
        """The frame's stereo rig, else the virtual rig of one camera over the log's ground plane
        (:mod:`.ground_depth`); None (the tracker idles, and says why) when the log has neither."""
        shape = frame.image.shape[:2]
        if not self.source:
            self.source = ("stereo" if frame.right is not None and frame.stereo is not None
                           else "ground" if frame.ground_plane is not None else "")
        if self.source == "stereo" and frame.right is not None and frame.stereo is not None:
            return frame.stereo
        if self.source == "ground" and frame.ground_plane is not None:
            try:
                return self.ground.camera(frame.ground_plane, shape)
            except ValueError as err:
                notice = f"the log's ground plane gives no camera ({err}): groups tracker idle"
                self.intermediates = GroupsIntermediates.idle("idle", shape, notice, self.config.klt.window)
                return None
        self.intermediates = GroupsIntermediates.idle("idle", shape, NO_STEREO, self.config.klt.window)
        return None

    def _learn(self, frame: Frame) -> None:
        """§2: the frames into the background model(s); once there are enough, the log's rate."""
        self.learn_t.append(frame.t_ns)
        if self.source == "stereo":
            assert frame.right is not None
            self.stereo.add(frame.image, frame.right)
            if self.stereo.models is not None:
                self._set_rate()
                self.learnt = True
            return
        self.ground.add(frame.image)
        if self.ground.full:
            self._set_rate()
            self.ground.start(self.fps)
            self.learnt = True

    def _observe(self, frame: Frame) -> DepthView:
        """§2 the foreground and its depth (subtraction stereo, or standing people on the ground);
        §3.1 KLT on the (left) foreground."""
        if self.source == "stereo":
            assert frame.right is not None
            view = self.stereo.observe(frame.image, frame.right, self.config)
        else:
            assert frame.ground_plane is not None
            view = self.ground.observe(frame.image, frame.ground_plane)
        self.klt.step(to_grey(frame.image), view.fg_left, view.disparity)
        return view

    def _ekf_config(self) -> EkfConfig:
        """The EKF's noises; with the ground's depth, σ_d is the foot row's jitter (``ground.sigma_foot_px``)."""
        ekf = self.config.ekf
        return ekf if self.source == "stereo" else replace(ekf, sigma_d=self.config.ground.sigma_foot_px)

    def _set_rate(self) -> None:
        """The log's frame rate from the background frames' times; the per-frame parameters rescaled to it."""
        steps = np.diff(np.asarray(self.learn_t, np.int64))
        steps = steps[steps > 0]
        self.fps = float(1e9 / np.median(steps)) if len(steps) else float("nan")
        self.config = self.user_config.at_rate(self.fps)
        self.klt = KltFeatures(self.config.klt, self.config.stereo.disparity_window)

    def _associate_and_update(self, points: ObservationPoints, rig: StereoRig) -> np.ndarray:
        acfg = self.config.association
        floor = np.eye(3) * acfg.min_extent_m**2
        self.contested = np.zeros(len(points), bool)
        self.held_out = np.zeros(len(points), bool)
        if not self.groups:
            return np.full(len(points), -1, np.int64)
        centres = np.array([g.position for g in self.groups])
        gate = np.array([g.extent + floor + g.ekf.P[np.ix_(POS, POS)] for g in self.groups])
        vmeans = np.array([g.velocity for g in self.groups])
        vcovs = np.array([g.velocity_spread + g.ekf.P[np.ix_(VEL, VEL)] + np.eye(3) * 1e-6 for g in self.groups])
        assoc = associate(points.xyz, points.velocity, centres, gate, vmeans, vcovs, acfg.gamma, acfg.k_p, acfg.k_v)
        self.contested = assoc.contested
        labels = self._near_gate(points, assoc.labels, centres, gate)
        labels = self._connected(points, labels, centres)
        a = acfg.alpha_s
        for j, g in enumerate(self.groups):
            idx = np.flatnonzero(labels == j)
            g.members = len(idx)
            g.merged_from = ""
            if len(idx) >= acfg.min_points:
                g.ekf.update(points.uvd[idx].mean(axis=0))
                g.extent = a * g.extent + (1.0 - a) * _cov(points.xyz[idx])  # eq. (7)
                g.velocity_spread = a * g.velocity_spread + (1.0 - a) * _cov(points.velocity[idx])
                g.status = g.life.supported()
                g.hits += 1
                g.coasted = 0
            else:
                g.status = self._coast(g)
        return labels

    def _coast(self, g: Group) -> str:
        """A frame without an update: with stereo, "lost" from ``tracks.max_empty_frames`` + 1 such frames in a
        row on (deleted next). With one camera (``tracks.ground_coast_sigma_m``, ours) the group coasts on its
        prediction while the EKF still places it on the ground to within that standard deviation (its
        largest axis), and is lost once it does not: people who stand still fade into MOG2's background
        and those passing behind others are hidden for longer than the stereo scenes' 0.25 s."""
        g.coasted += 1
        limit = self.config.tracks.ground_coast_sigma_m
        if self.source != "ground" or limit <= 0 or self.pose is None:
            return g.life.missed()
        P = self.pose.rotate_cov(g.ekf.P[np.ix_(POS, POS)][None])[0][:2, :2]
        return g.life.held() if float(np.sqrt(np.linalg.eigvalsh(P)[-1])) <= limit else g.life.lose()

    def _connected(self, points: ObservationPoints, labels: np.ndarray, centres: np.ndarray) -> np.ndarray:
        """A group's points this frame are one connected set under §3.4's relation (eq. 12: points within
        ``grouping.radius_m`` are related), as the points that started it were (``grouping.connected``,
        ours): of the points its gate took, it keeps the connected set with the most points (the one
        nearest its predicted position on a tie); the others are unassigned (and may start a group, §3.4).
        A gate is the extent eq. (7) learnt from the points; without this, a group that took a passer-by's
        points grew its extent over them and its gate then took the next person's."""
        mode = self.config.grouping.connected
        if mode == "off" or (mode == "ground" and self.source != "ground"):
            return labels
        labels = labels.copy()
        for j in np.unique(labels[labels >= 0]).tolist():
            idx = np.flatnonzero(labels == j)
            sets = initial_groups(points.xyz[idx], self.config.grouping.radius_m, 1)
            if len(sets) < 2:
                continue
            sizes = np.array([len(m) for m in sets])
            near = np.array([np.linalg.norm(points.xyz[idx[m]].mean(axis=0) - centres[j]) for m in sets])
            keep = min(range(len(sets)), key=lambda k: (-sizes[k], near[k], k))
            drop = np.concatenate([m for k, m in enumerate(sets) if k != keep])
            labels[idx[drop]] = -1
        return labels

    def _start_sets(self, points: ObservationPoints, labels: np.ndarray) -> list[np.ndarray]:
        """§3.4: the sets of unassigned points (indices into ``points``) that would start a group."""
        free = np.flatnonzero(labels == -1)
        start_points = self.config.grouping.min_points if self.source == "stereo" else self.config.ground.min_points
        return [free[m] for m in initial_groups(points.xyz[free], self.config.grouping.radius_m, start_points)]

    def _near_gate(self, points: ObservationPoints, labels: np.ndarray, centres: np.ndarray,
                   gate: np.ndarray) -> np.ndarray:
        """Splinters (``grouping.near_gate``, ours): a set of the gate's leftover points that would
        start a group (§3.4) while its region overlaps a confirmed group's gate — its centroid within
        eq. (8)'s γ under the gate's covariance plus the set's own position spread — joins the nearest
        such group (``"join"``: the labels returned give it those points before its update) or may not
        start one (``"leave"``: ``self.held_out``). With ``grouping.inside_box`` a set whose image
        points' centre lies in a confirmed group's image box (the foreground pixels its gate held on the last
        frame) may not start one either, whatever its depth: a part of the group at a wrong disparity
        (heads matched half as far, in the synthetic stairs), or someone the group hides, who starts
        once out of the box. Stereo only: the ground's depth is each column's own foot, never a
        mismatch, and on PETS09 the test held real people out (person coverage 0.86 -> 0.66).
        ``grouping.near_gate_ground`` (stereo with the rig's pose): the gate test on the ground, world
        X Y (a group's legs under its torsos); ``grouping.box_overlap``: the set's image box overlapping
        the group's box, not only its centre inside. Unchanged with ``"start"`` (the paper)."""
        self.held_out = np.zeros(len(points), bool)
        mode = self.config.grouping.near_gate
        confirmed = np.array([g.hits >= self.config.merge.frames for g in self.groups], bool)
        if mode == "start" or not confirmed.any():
            return labels
        labels = labels.copy()
        gamma = self.config.association.gamma
        box_test = self.config.grouping.inside_box and self.source == "stereo"
        # with a stereo rig's pose: on the ground (world X Y) — people stand upright, a person's legs are
        # under their torso whatever the height between them — at the same probability as eq. (8)'s 3 dof
        on_ground = self.config.grouping.near_gate_ground and self.pose is not None and self.source == "stereo"
        R = self.pose.R[:2] if on_ground else np.eye(3)
        if on_ground:
            gamma = self.config.grouping.gamma_ground
        for idx in self._start_sets(points, labels):
            xyz = points.xyz[idx]
            c, spread = xyz.mean(axis=0), _cov(xyz)
            d2 = np.array([mahalanobis_sq((R @ c)[None], R @ centres[j], R @ (gate[j] + spread) @ R.T)[0]
                           if confirmed[j] else np.inf for j in range(len(self.groups))])
            j = int(np.argmin(d2))
            if d2[j] >= gamma:
                if box_test and self._inside_a_box(points.uvd[idx, :2], confirmed):
                    self.held_out[idx] = True
                continue
            if mode == "join":
                labels[idx] = j
            else:
                self.held_out[idx] = True
        return labels

    def _inside_a_box(self, uv: np.ndarray, confirmed: np.ndarray) -> bool:
        """Whether the centre of the points ``uv`` (px) lies in the image box of a confirmed group, or with
        ``grouping.box_overlap`` whether their own box overlaps it."""
        u, v = uv.mean(axis=0)
        lo, hi = (uv.min(axis=0), uv.max(axis=0)) if self.config.grouping.box_overlap else (np.array([u, v]),) * 2
        for g, ok in zip(self.groups, confirmed):
            x0, y0, x1, y1 = g.box
            if ok and lo[0] <= x1 and hi[0] >= x0 and lo[1] <= y1 and hi[1] >= y0:  # (NaN box: False)
                return True
        return False

    def _delete(self, labels: np.ndarray) -> tuple[np.ndarray, list[int], list[str]]:
        alive = np.array([not g.life.lost for g in self.groups], bool)
        ended = [g.gid for g, a in zip(self.groups, alive) if not a]
        old = self.groups
        self.groups = [g for g, a in zip(self.groups, alive) if a]
        index_map = np.where(alive, np.cumsum(alive) - 1, -1) if len(alive) else np.zeros(0, np.int64)
        labels = np.where(labels >= 0, index_map[np.maximum(labels, 0)] if len(alive) else -1, -1)
        frames = {g.gid: self.config.tracks.lifecycle.lost_after if self.source == "stereo" else g.coasted
                  for g, a in zip(old, alive) if not a}
        return labels.astype(np.int64), ended, [f"group {gid} deleted: no update for {frames[gid]} frames" for gid in ended]

    def _start_groups(self, points: ObservationPoints, labels: np.ndarray, rig: StereoRig, events: list[str]) -> np.ndarray:
        ecfg = self.config.ekf
        held_out = self.held_out if len(self.held_out) == len(labels) else np.zeros(len(labels), bool)
        labels = labels.copy()
        for idx in self._start_sets(points, np.where(held_out, -2, labels)):
            pos, vel = points.xyz[idx].mean(axis=0), points.velocity[idx].mean(axis=0)
            extent = _cov(points.xyz[idx])
            P0 = np.zeros((6, 6))
            P0[np.ix_(POS, POS)] = extent / len(idx) + np.eye(3) * 0.05**2
            P0[np.ix_(VEL, VEL)] = np.eye(3) * ecfg.init_velocity_sigma**2
            g = Group(self.next_id, GroupEkf(self._ekf_config(), rig, state_from(pos, vel), P0), extent, _cov(points.velocity[idx]), len(idx),
                      TrackLife(self.config.tracks.lifecycle))
            self.next_id += 1
            labels[idx] = len(self.groups)
            self.groups.append(g)
            events.append(f"group {g.gid} started with {len(idx)} points")
        return labels

    def _merge(self, labels: np.ndarray, events: list[str], points: ObservationPoints) -> tuple[np.ndarray, list[int]]:
        """§3.5: the groups whose regions have overlapped on ``merge.frames`` frames in a row become one
        (:meth:`_merged`); the points' labels follow the new order; the ids merged away are returned."""
        sets = merge_sets(self._ready_to_merge(labels, points))
        if not sets:
            return labels, []
        merged_ids: list[int] = []
        new_groups: list[Group] = []
        index_map = np.arange(len(self.groups))
        gone = set()
        for s in sets:
            parts = [self.groups[k] for k in s.tolist()]
            g, absorbed = self._merged(parts)
            merged_ids += [p.gid for p in parts if p.gid != g.gid]
            verb = "absorbed by" if absorbed else "merged into"
            events.append(f"groups {g.merged_from} {verb} group {g.gid}")
            gone.update(s.tolist())
            new_groups.append(g)
        keep = [k for k in range(len(self.groups)) if k not in gone]
        for t, s in enumerate(sets):
            index_map[s] = len(keep) + t
        for rank, k in enumerate(keep):
            index_map[k] = rank
        self.groups = [self.groups[k] for k in keep] + new_groups
        labels = np.where(labels >= 0, index_map[np.maximum(labels, 0)], -1)
        return labels, merged_ids

    def _ready_to_merge(self, labels: np.ndarray, points: ObservationPoints) -> np.ndarray:
        """The pairs of groups whose position and velocity regions overlap (:func:`.merging.merge_overlap`)
        on this frame and on ``merge.frames`` frames in a row so far (a symmetric boolean matrix)."""
        mcfg, floor = self.config.merge, np.eye(3) * self.config.association.min_extent_m**2
        if len(self.groups) < 2:
            self.pair_frames = {}
            return np.zeros((len(self.groups), len(self.groups)), bool)
        centres = np.array([g.position for g in self.groups])
        extents = np.array([g.extent + floor for g in self.groups])
        vel = np.array([g.velocity for g in self.groups])
        spread = 1.0 if mcfg.velocity_spread_in_gate else 0.0
        vcov = np.array([g.ekf.P[np.ix_(VEL, VEL)] + spread * g.velocity_spread / max(g.members, 1) + np.eye(3) * 1e-8
                         for g in self.groups])
        measured = measured_velocities(points.velocity, labels, len(self.groups), self.config.association.min_points,
                                       self.contested)
        both = merge_overlap(centres, extents, vel, vcov, measured, mcfg, self.pose).overlap
        ids = [g.gid for g in self.groups]
        counts: dict[tuple[int, int], int] = {}
        ready = np.zeros_like(both)
        for i, j in zip(*np.nonzero(np.triu(both))):
            key = (ids[i], ids[j])
            counts[key] = self.pair_frames.get(key, 0) + 1
            ready[i, j] = ready[j, i] = counts[key] >= mcfg.frames
        self.pair_frames = counts
        return ready

    def _merged(self, parts: list[Group]) -> tuple[Group, bool]:
        """Eqs. 14-15: one group from ``parts`` (member-weighted Gaussians of state, extent and velocity
        spread); it keeps the largest part's id when that part holds ``merge.keep_id_share`` of the members
        (True: absorbed), else it takes a new one."""
        n = np.array([max(p.members, 1) for p in parts], np.float64)
        x, P = merge_gaussians(n, np.array([p.ekf.x for p in parts]), np.array([p.ekf.P for p in parts]))  # eqs. 14-15
        _, extent = merge_gaussians(n, np.array([p.position for p in parts]), np.array([p.extent for p in parts]))
        _, vspread = merge_gaussians(n, np.array([p.velocity for p in parts]), np.array([p.velocity_spread for p in parts]))
        big = int(np.argmax(n))
        absorbed = n[big] >= self.config.merge.keep_id_share * n.sum()
        gid = parts[big].gid if absorbed else self.next_id
        g = Group(gid, parts[big].ekf, extent, vspread, int(sum(p.members for p in parts)),
                  TrackLife.merged(p.life for p in parts),
                  status="measured" if any(p.status == "measured" for p in parts) else "predicted",
                  merged_from=",".join(str(p.gid) for p in parts), hits=max(p.hits for p in parts),
                  coasted=min(p.coasted for p in parts))
        g.ekf.set(x, P)
        if not absorbed:
            self.next_id += 1
        return g, bool(absorbed)

    def _boxes(self, disparity: np.ndarray, rig: StereoRig) -> None:
        """Each group's image box: the foreground pixels whose 3-D point it gates best (every 2nd pixel)."""
        if not self.groups:
            return
        sub = disparity[::2, ::2]
        v, u = np.nonzero(np.isfinite(sub) & (sub > 0))
        uvd = np.stack([u * 2.0, v * 2.0, sub[v, u].astype(np.float64)], axis=1)
        gamma = self.config.association.gamma
        floor = np.eye(3) * self.config.association.min_extent_m**2
        if len(uvd):
            xyz = rig.to_points(uvd)
            d2 = np.stack([mahalanobis_sq(xyz, g.position, g.extent + floor + g.ekf.P[np.ix_(POS, POS)])
                           for g in self.groups], axis=1)
            best = np.argmin(d2, axis=1)
            ok = d2[np.arange(len(d2)), best] < gamma
        for j, g in enumerate(self.groups):
            sel = uvd[(best == j) & ok] if len(uvd) else uvd
            if len(sel) >= 20:
                g.box = np.array([sel[:, 0].min(), sel[:, 1].min(), sel[:, 0].max() + 2.0, sel[:, 1].max() + 2.0])
            else:  # the extent projected: ±√3 σ (a uniform spread's half-width)
                z = max(float(g.position[2]), 0.1)
                c = rig.to_uvd(g.position[None])[0]
                half = rig.f * np.sqrt(3.0 * np.maximum(np.diag(g.extent + floor)[:2], 0.0)) / z
                g.box = np.array([c[0] - half[0], c[1] - half[1], c[0] + half[0], c[1] + half[1]])

    def _snapshot(self) -> GroupSnapshot:
        gs = self.groups
        if not gs:
            return GroupSnapshot.empty()
        order = np.argsort([g.gid for g in gs], kind="stable")
        gs = [gs[k] for k in order]
        self.groups = gs
        return GroupSnapshot(np.array([g.gid for g in gs], np.int64), np.array([g.ekf.x for g in gs]),
                             np.array([g.ekf.P for g in gs]), np.array([g.extent for g in gs]),
                             np.array([g.velocity_spread for g in gs]), np.array([g.members for g in gs], np.int64),
                             tuple(g.status for g in gs), np.array([g.box for g in gs]), tuple(g.merged_from for g in gs))

    @staticmethod
    def _state(g: Group, rig: StereoRig) -> TrackState:
        X, Y, Z = (float(c) for c in (g.position if rig.pose is None else rig.pose.to_world(g.position)[0]))
        J = rig.jacobian(g.position)
        du, dv, _ = J @ g.velocity
        x0, y0, x1, y1 = (float(c) for c in g.box)
        return TrackState(g.gid, x=(x0 + x1) / 2, y=(y0 + y1) / 2, w=x1 - x0, h=y1 - y0, X=X, Y=Y, Z=Z,
                          vx=float(du), vy=float(dv), status=g.status)
