"""A broadcast camera operator following the ball, and the encoders that log what the head did.

Pan and tilt each follow a second-order (spring–damper) law with velocity feed-forward,

    θ'' = ωn² (θ* − θ) + 2 ζ ωn (θ*' − θ'),

toward the ball's direction as the operator *perceives* it: seen ``reaction_s`` late and
extrapolated ``lead_s`` ahead. The lag and the under-damping (ζ < 1) give the overshoot of a
human operator at launch, at the apex and at the bounce. The zoom (in log-magnification, first
order and rate-limited) aims at an apparent ball diameter that is large while the ball sits on the
tee, small at launch (the operator widens to keep the fast ball in the frame, then tightens during
the climb), and grows as the ball comes down. Focus follows the ball's range with a lag.

The path is simulated on a fine grid (1 ms) and is the camera's truth: the renderer and the
ground truth use ``CameraPath.at``; the encoders sample the same path at their own rate, then add
Gaussian noise and quantise (only in the logged readings).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from trackreplay.recorder.synth.golf.lens import COUNTS, BroadcastLens
from trackreplay.schemas.records import PtzReading


@dataclass(frozen=True)
class OperatorConfig:
    reaction_s: float = 0.12  # perception delay
    lead_s: float = 0.12  # aims this far ahead along the perceived motion
    natural_hz: float = 1.3  # ωn / 2π of the pan/tilt response
    damping: float = 0.55  # ζ < 1: slight overshoot
    max_rate_deg_s: float = 120.0  # head slew limit
    zoom_tau_s: float = 0.35
    zoom_rate: float = 1.5  # max |d ln(magnification) / dt|, 1/s
    focus_tau_s: float = 0.25
    # Apparent ball diameter the operator aims for, px at 720 lines (scaled with the height).
    size_tee_px: float = 10.0
    size_launch_px: float = 4.5
    launch_wide: float = 0.6  # right after launch the operator goes wider still (this fraction of the size)
    launch_wide_s: float = 0.7  # ... for this long, then back to ``size_launch_px`` over as long again
    size_landing_px: float = 7.0
    size_ground_px: float = 8.0
    # A camera cut / fast zoom: zoom out by this factor at once and leave the ball off-centre.
    cut_zoom_factor: float = 3.0
    cut_offset: tuple[float, float] = (0.25, 0.2)  # ball offset after the cut, fraction of width/height


@dataclass(frozen=True)
class EncoderModel:
    """The head and lens encoders: their rate, noise (1 sigma) and quantisation steps."""

    rate_hz: float = 100.0
    noisy: bool = True  # False: exact readings of the true path (no noise, no quantisation)
    angle_sigma_deg: float = 0.0005
    angle_step_deg: float = 0.001
    zoom_sigma: float = 0.5
    focus_sigma: float = 2.0
    count_step: float = 1.0


@dataclass(frozen=True)
class ShotTimes:
    """When things happen, seconds on the log clock (t = 0 at the first frame)."""

    launch: float
    apex: float
    landing: float


@dataclass(frozen=True)
class CameraPath:
    """The camera's true pan/tilt (deg) and zoom/focus (counts) on a fine time grid (s)."""

    t: np.ndarray
    pan: np.ndarray
    tilt: np.ndarray
    zoom: np.ndarray
    focus: np.ndarray
    cut_time: float | None = None

    def at(self, times: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Linear interpolation on the grid; a cut is a jump between two grid points."""
        t = np.atleast_1d(np.asarray(times, dtype=np.float64))
        return tuple(np.interp(t, self.t, a) for a in (self.pan, self.tilt, self.zoom, self.focus))  # type: ignore[return-value]


def _direction_angles(camera: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    d = points - camera
    horiz = np.hypot(d[:, 0], d[:, 1])
    pan = np.unwrap(np.arctan2(d[:, 1], d[:, 0]))
    tilt = np.arctan2(d[:, 2], horiz)
    return np.rad2deg(pan), np.rad2deg(tilt), np.linalg.norm(d, axis=1)


def target_diameter(cfg: OperatorConfig, times: np.ndarray, shot: ShotTimes, height: int) -> np.ndarray:
    """The apparent ball diameter (px) the operator wants at each time."""
    scale = height / 720.0
    frac = np.clip((times - shot.apex) / max(shot.landing - shot.apex, 1e-6), 0.0, 1.0)
    since = np.clip((times - shot.launch - cfg.launch_wide_s) / cfg.launch_wide_s, 0.0, 1.0)
    climb = cfg.size_launch_px * (cfg.launch_wide + (1.0 - cfg.launch_wide) * since)
    size = np.where(times < shot.launch, cfg.size_tee_px,
                    np.where(times < shot.apex, climb,
                             np.where(times < shot.landing, cfg.size_launch_px + frac * (cfg.size_landing_px - cfg.size_launch_px),
                                      cfg.size_ground_px)))
    return size * scale


def follow_ball(cfg: OperatorConfig, lens: BroadcastLens, camera: np.ndarray, t: np.ndarray, ball: np.ndarray,
                shot: ShotTimes, ball_diameter: float, cut_time: float | None = None) -> CameraPath:
    """Simulate the operator on the uniform grid ``t`` given the ball centre ``ball`` (N, 3) there."""
    dt = float(t[1] - t[0])
    n = len(t)
    pan_b, tilt_b, rng_b = _direction_angles(camera, ball)
    rate_pan = np.gradient(pan_b, dt)
    rate_tilt = np.gradient(tilt_b, dt)
    lag = int(round(cfg.reaction_s / dt))
    seen = np.clip(np.arange(n) - lag, 0, n - 1)
    tgt_pan = pan_b[seen] + cfg.lead_s * rate_pan[seen]
    tgt_tilt = tilt_b[seen] + cfg.lead_s * rate_tilt[seen]
    tgt_rpan, tgt_rtilt = rate_pan[seen], rate_tilt[seen]
    seen_range = rng_b[seen]
    want_fx = target_diameter(cfg, t[seen], shot, lens.height) * seen_range / ball_diameter
    log_ratio = math.log(lens.ratio)
    tgt_m = np.clip(np.log(want_fx / lens.fx_wide), 0.0, log_ratio)
    tgt_focus = lens.focus_for_distance(seen_range)

    wn = 2.0 * math.pi * cfg.natural_hz
    k_p, k_d = wn * wn, 2.0 * cfg.damping * wn
    vmax = cfg.max_rate_deg_s
    pan = np.empty(n)
    tilt = np.empty(n)
    m = np.empty(n)
    focus = np.empty(n)
    p, q, vp, vq = pan_b[0], tilt_b[0], 0.0, 0.0
    mm, ff = tgt_m[0], tgt_focus[0]
    cut_index = None if cut_time is None else int(round(cut_time / dt))
    a_f = dt / cfg.focus_tau_s
    for i in range(n):
        if i == cut_index:
            mm = max(0.0, mm - math.log(cfg.cut_zoom_factor))
            fx = lens.fx_wide * math.exp(mm)
            p += math.degrees(math.atan(cfg.cut_offset[0] * lens.width / fx))
            q += math.degrees(math.atan(cfg.cut_offset[1] * lens.height / fx))
            vp = vq = 0.0
        pan[i], tilt[i], m[i], focus[i] = p, q, mm, ff
        ap = k_p * (tgt_pan[i] - p) + k_d * (tgt_rpan[i] - vp)
        aq = k_p * (tgt_tilt[i] - q) + k_d * (tgt_rtilt[i] - vq)
        vp = min(max(vp + ap * dt, -vmax), vmax)
        vq = min(max(vq + aq * dt, -vmax), vmax)
        p += vp * dt
        q += vq * dt
        dm = (tgt_m[i] - mm) / cfg.zoom_tau_s
        mm += min(max(dm, -cfg.zoom_rate), cfg.zoom_rate) * dt
        ff += (tgt_focus[i] - ff) * a_f
    zoom = COUNTS * m / log_ratio
    return CameraPath(t.copy(), pan, tilt, zoom, focus, cut_time)


def encoder_times(duration: float, rate_hz: float, dropout: tuple[float, float] | None = None) -> np.ndarray:
    """Reading times (s): ``j / rate`` from 0 through ``duration``, minus a dropout window [start, end)."""
    j = np.arange(int(math.floor(duration * rate_hz + 1e-9)) + 1)
    t = j / rate_hz
    if dropout is not None:
        t = t[(t < dropout[0]) | (t >= dropout[1])]
    return t


def encoder_readings(path: CameraPath, enc: EncoderModel, rng: np.random.Generator, duration: float,
                     dropout: tuple[float, float] | None = None) -> list[PtzReading]:
    """What the encoders log: the true path at their own rate, with noise and quantisation."""
    times = encoder_times(duration, enc.rate_hz)
    pan, tilt, zoom, focus = path.at(times)
    if enc.noisy:
        # Noise is drawn for every tick, dropped or not, so a dropout changes nothing else.
        n = len(times)
        pan = _quantise(pan + rng.normal(0.0, enc.angle_sigma_deg, n), enc.angle_step_deg)
        tilt = _quantise(tilt + rng.normal(0.0, enc.angle_sigma_deg, n), enc.angle_step_deg)
        zoom = np.clip(_quantise(zoom + rng.normal(0.0, enc.zoom_sigma, n), enc.count_step), 0, COUNTS)
        focus = np.clip(_quantise(focus + rng.normal(0.0, enc.focus_sigma, n), enc.count_step), 0, COUNTS)
    if dropout is not None:
        keep = (times < dropout[0]) | (times >= dropout[1])
        times, pan, tilt, zoom, focus = (a[keep] for a in (times, pan, tilt, zoom, focus))
    t_ns = np.round(times * 1e9).astype(np.int64)
    return [PtzReading(int(t_ns[i]), float(pan[i]), float(tilt[i]), float(zoom[i]), float(focus[i])) for i in range(len(times))]


def _quantise(x: np.ndarray, step: float) -> np.ndarray:
    return np.round(x / step) * step if step > 0 else x
