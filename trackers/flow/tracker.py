"""The gradient-flow tracker (seed 004, §4.3 and Fig. 6) stepped frame by frame.

Step k (frame k arrives; the FOV centre c was set after frame k−1):
crop frames k−1 and k at c (eq. 26) → flow (on-line: one refinement warm-started from the
previous flow, eq. 25; offline: eq. 7–10) → velocity and centroid (eq. 11) → Kalman filter
(eq. 23–24) → the FOV moves to the rounded filtered position. "measured" on a frame with moving
pixels, "predicted" without, "lost" on the ``lost_after``-th such frame in a row or once the FOV has left
the picture (the track's life: :mod:`trackreplay.trackers.lifecycle`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from trackreplay.trackers.base import TrackerBase, TrackState
from trackreplay.trackers.flow.config import FlowConfig
from trackreplay.trackers.flow.fov import crop, fov_origin, inside, next_centre, shift_field
from trackreplay.trackers.flow.kalman import AxisFilters
from trackreplay.trackers.flow.local_flow import FlowField
from trackreplay.trackers.flow.refine import online_step, refine_flow
from trackreplay.trackers.flow.velocity import VelocityEstimate, histogram_edges, object_velocity
from trackreplay.trackers.frame import Frame
from trackreplay.trackers.lifecycle import TrackLife


@dataclass(frozen=True, eq=False)
class FlowIntermediates:
    """One step's inner results, plain numpy (the Rerun view and the digest rely on these names)."""

    fov_box: np.ndarray  # (4,) [x0, y0, w, h]: first column/row of the window and its size, image px
    flow_u: np.ndarray  # (fov, fov) float32 px/frame, NaN where rejected; lives half-way between the frames
    flow_v: np.ndarray
    valid: np.ndarray  # (fov, fov) bool
    cond: np.ndarray  # (fov, fov) float32, cond₂(G) (eq. 8)
    moving: np.ndarray  # (fov, fov) bool, the set S of eq. 11
    hist_edges: np.ndarray  # float64
    hist_u: np.ndarray  # int64 counts over valid pixels
    hist_v: np.ndarray
    raw_velocity: np.ndarray  # (2,) eq. 11, NaN when nothing moved
    filtered_velocity: np.ndarray  # (2,)
    kalman_x: np.ndarray  # (2, 3) per axis (x, ẋ, ẍ)
    kalman_P: np.ndarray  # (2, 3, 3)
    centroid: np.ndarray  # (2,) the position observation: S's centroid carried to frame k, image px; NaN when empty
    residual: float  # RMS brightness residual after the flow step (eq. 10)
    moving_pixels: int


class FlowTracker(TrackerBase):
    """Tracks one moving object with the gradient method (seed 004); ``name = "flow"``."""

    name: ClassVar[str] = "flow"
    # Mark labels this tracker reads (trackers without the attribute read any); replay refuses
    # marks with other labels instead of silently starting from the image centre.
    mark_labels: ClassVar[tuple[str, ...]] = ("target",)

    def __init__(self, config: FlowConfig, rng: np.random.Generator) -> None:
        self.config = config
        self.rng = rng  # part of the tracker contract; this tracker draws nothing
        self.edges = histogram_edges(config.hist_range, config.hist_bin)
        self.intermediates: FlowIntermediates | None = None
        self._prev: np.ndarray | None = None
        self._centre: tuple[int, int] = (0, 0)
        self._kf: AxisFilters | None = None
        self._warm: FlowField | None = None
        self._steps = 0
        # the track's life (trackers.lifecycle): "lost" after lost_after frames in a row without moving pixels
        self.life = TrackLife(config.lifecycle)
        self._extent: tuple[float | None, float | None] = (None, None)
        # how far S reaches beyond a moving edge: the derivative and neighbourhood radii, of which
        # about three quarters carry flow above ε (measured on the flow-sim scenes)
        self._spread = 0.75 * ((config.derivative - 1) / 2 + (config.neighbourhood - 1) / 2)

    def step(self, frame: Frame) -> list[TrackState]:
        """Step k: the flow in the window (eq. 26; eqs. 7-10 or 25), the object's velocity and centroid
        (eq. 11), the Kalman filter (eqs. 23-24) and the track's life, the window moved, the row."""
        grey = frame.grey
        if self._prev is None:
            return self._start(frame, grey)
        centre = self._centre
        flow, est = self._measure(grey, centre)
        origin = fov_origin(centre, self.config.fov)
        status, observed = self._filter(est, origin)
        assert self._kf is not None
        kalman_x = self._kf.state
        filtered, velocity = kalman_x[:, 0].copy(), kalman_x[:, 1].copy()
        self._move_window(grey, flow, est, velocity, filtered, centre)
        self.intermediates = self._intermediates(flow, est, origin, observed, kalman_x, velocity)
        if status == "lost" or not inside(filtered, grey.shape):
            # no position: nothing has moved for lost_after frames, or the FOV has left the picture
            return [TrackState(1, status="lost")]
        return [TrackState(1, x=float(filtered[0]), y=float(filtered[1]), w=self._extent[0], h=self._extent[1],
                           vx=float(velocity[0]), vy=float(velocity[1]), status=status)]

    def _measure(self, grey: np.ndarray, centre: tuple[int, int]) -> tuple[FlowField, VelocityEstimate]:
        """Eq. 26: both frames seen through the same window, so the background stands still; their flow
        (on-line: one refinement warm-started from the previous flow, eq. 25; offline: eqs. 7-10) and the
        object's velocity and moving set (eq. 11)."""
        cfg = self.config
        e0, e1 = crop(self._prev, centre, cfg.fov), crop(grey, centre, cfg.fov)
        flow = online_step(e0, e1, self._warm, cfg, step=self._steps) if cfg.online else refine_flow(e0, e1, cfg)
        return flow, object_velocity(flow, cfg.epsilon, self.edges, self._spread)

    def _filter(self, est: VelocityEstimate, origin: tuple[int, int]) -> tuple[str, np.ndarray]:
        """Eqs. 23-24: predict, and update on the moving pixels' centroid and velocity when any moved (a
        frame that supports the track, :mod:`trackreplay.trackers.lifecycle`); the status and the observation."""
        assert self._kf is not None
        self._kf.predict()
        observed = np.full(2, np.nan)
        if est.count == 0:
            return self.life.missed(), observed
        # S's centroid sits half-way between the frames (so does the flow): half the velocity
        # carries it to frame k
        observed = est.centroid + 0.5 * est.velocity + np.array(origin, dtype=np.float64)
        self._kf.update(observed, est.velocity)
        self._extent = (float(est.extent[0]), float(est.extent[1]))
        return self.life.supported(), observed

    def _move_window(self, grey: np.ndarray, flow: FlowField, est: VelocityEstimate, velocity: np.ndarray,
                     filtered: np.ndarray, centre: tuple[int, int]) -> None:
        """§4.2: the FOV moves to the rounded filtered position; the next step starts from this flow."""
        self._centre = next_centre(filtered, grey.shape)
        self._warm = self._warm_start(flow, est.moving, est.velocity if est.count else velocity, centre, self._centre)
        self._prev = grey
        self._steps += 1

    def _intermediates(self, flow: FlowField, est: VelocityEstimate, origin: tuple[int, int], observed: np.ndarray,
                       kalman_x: np.ndarray, velocity: np.ndarray) -> FlowIntermediates:
        assert self._kf is not None
        cfg = self.config
        return FlowIntermediates(
            fov_box=np.array([origin[0], origin[1], cfg.fov, cfg.fov], dtype=np.float64),
            # this step's own arrays (nothing else writes to them): no copies
            flow_u=flow.u.astype(np.float32, copy=False),
            flow_v=flow.v.astype(np.float32, copy=False),
            valid=flow.valid,
            cond=flow.cond.astype(np.float32, copy=False),
            moving=est.moving,
            hist_edges=est.hist_edges.astype(np.float64),  # the tracker's edges: a copy
            hist_u=est.hist_u,
            hist_v=est.hist_v,
            raw_velocity=est.velocity.astype(np.float64),
            filtered_velocity=velocity,
            kalman_x=kalman_x,
            kalman_P=self._kf.covariance,
            centroid=observed,
            residual=float(flow.residual),
            moving_pixels=est.count,
        )

    @staticmethod
    def _warm_start(flow: FlowField, moving: np.ndarray, motion: np.ndarray, old: tuple[int, int], new: tuple[int, int]) -> FlowField:
        """The next step's starting flow (§4.1): this step's flow on the moving pixels, moved as the
        target moves relative to the window, i.e. by its motion less the window's shift.

        The background starts at zero, its flow once compensated (eq. 26). Shifting by the window's
        shift alone would keep the background aligned but leave the target's flow behind by its motion.
        """
        dx = int(np.floor(motion[0] + 0.5)) - (new[0] - old[0])
        dy = int(np.floor(motion[1] + 0.5)) - (new[1] - old[1])
        zero = np.float32(0.0)
        # moving pixels are valid, so the field itself (NaN only where not valid) serves
        return FlowField(
            shift_field(np.where(moving, flow.u, zero), dx, dy),
            shift_field(np.where(moving, flow.v, zero), dx, dy),
            shift_field(moving, dx, dy, False),
            shift_field(flow.cond, dx, dy, np.inf),
        )

    def _start(self, frame: Frame, grey: np.ndarray) -> list[TrackState]:
        """Frame 0: the window starts on the marked target (or the configured or image centre)."""
        cfg = self.config
        hint = next((h for h in frame.hints if h.label in self.mark_labels), None)
        if hint is not None:
            start = (float(hint.x), float(hint.y))
            self._extent = (float(hint.w), float(hint.h))
        elif cfg.init_center is not None:
            start = (float(cfg.init_center[0]), float(cfg.init_center[1]))
        else:
            start = ((grey.shape[1] - 1) / 2.0, (grey.shape[0] - 1) / 2.0)
        self._kf = AxisFilters(start, cfg.alpha, cfg.q, cfg.r_pos, cfg.r_vel, cfg.p0)
        self.life.start()
        self._centre = next_centre(np.array(start), grey.shape)
        self._prev = grey
        x0, y0 = fov_origin(self._centre, cfg.fov)
        n = cfg.fov
        nan_img = np.full((n, n), np.nan, np.float32)
        zeros_hist = np.zeros(len(self.edges) - 1, np.int64)
        self.intermediates = FlowIntermediates(
            fov_box=np.array([x0, y0, n, n], dtype=np.float64),
            flow_u=nan_img, flow_v=nan_img.copy(), valid=np.zeros((n, n), bool), cond=nan_img.copy(),
            moving=np.zeros((n, n), bool), hist_edges=self.edges.copy(), hist_u=zeros_hist, hist_v=zeros_hist.copy(),
            raw_velocity=np.full(2, np.nan), filtered_velocity=self._kf.velocity, kalman_x=self._kf.state,
            kalman_P=self._kf.covariance, centroid=np.full(2, np.nan), residual=float("nan"), moving_pixels=0,
        )
        # Only a mark is a sighting; a configured point or the image centre is where the search starts
        status = "measured" if hint is not None else "predicted"
        return [TrackState(1, x=start[0], y=start[1], w=self._extent[0], h=self._extent[1], status=status)]
