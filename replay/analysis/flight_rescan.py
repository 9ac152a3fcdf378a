"""Look again along the fitted flight: the frames the golf tracker could not measure, searched
where the whole shot says the ball is (offline, after :func:`~trackreplay.replay.analysis.flight.fit_flight`).

The causal tracker looks at one frame with only the past to go on: a 2 px speck among cloud puffs
as bright as it, or a launch smeared over 100 px at a few grey levels, cannot be told from the
sky there (docs/golf_synthetic.md counts them: most missed frames show nothing that stands out
within 30 px). After the event the fitted flight — every line of sight of the shot, bounce and
roll included, through the physics — says where the ball was in each of those frames, how large,
and which way and how fast it moved across the picture. With that prior the question is no
longer "where is a ball?" but "is the ball here?", and a matched filter answers it:

- the expected image of the ball: a disc of the fitted apparent diameter swept along the fitted
  path across the sensor during the exposure (the camera's own panning included; a bounce bends
  it; the exposure is not in the log: a few fractions of the frame interval are tried, the best kept);
- that template correlated with the luminance's white top-hat (a disc ``kernel_diameters`` ball
  diameters wide: the sky's and the turf's slow shading gone, the ball's contrast kept) over a
  window round the fitted position: the response averages the ball's contrast over all its
  pixels, so a streak a few levels above the sky over many pixels stands above noise of ±1.5 per pixel;
- the ball is there when the response has a local maximum within ``gate_px`` of the fitted
  position (not the flank of something brighter just outside), ``min_snr`` robust sigmas of the
  window's response above its median, **and** the same template over what also stands above the
  world behind the ball — the median of the frames up to ``world_frames`` either side in which
  the ball is elsewhere, each brought into this pose — is ``min_new_snr`` sigmas up there too.
  Cloud puffs, turf, tee markers and spare balls stay where they were; the ball does not. With
  the top-hat alone a place 15-40 px beside the ball "found a ball" on 15 % of the searches over
  the synthetic shots (puffs of the ball's size); with both tests on 0.8 % (docs/golf_rescan.md).
  Only a place that at least ``min_world`` such frames saw is searched, and the response must rise
  ``min_contrast`` grey levels, its sigma no less than rounding to grey levels leaves (a flat,
  clipped sky has no spread to measure against);
- and only where the fit is sure enough of the place: within ``reach`` frames of frames already
  measured and with ``sigma_factor`` times its 1-σ in the picture inside the gate (the launch: a
  ball leaving the tee at 200 px a frame, with a launch time known to a few milliseconds, is not).

Found frames become observations and the flight is fitted again; the next round looks again
with the better fit (a launch missed for 25 frames is closed from the frames nearest the ones
already measured outwards). After the last round every frame found is checked against the final
fit; one further than the gate from it is dropped and the flight fitted once more without it.

A frame found this way is ``measured`` (the ball was seen in that frame's picture) with ``fill``
``rescan``; its size ``w, h`` is left empty (the template's is the model's, not a measurement),
its ``X, Y, Z`` are the fitted flight's. Frames the tracker measured are never changed.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import polars as pl

from trackreplay.replay.analysis.flight import FlightConfig, FlightFit, fit_flight, observations
from trackreplay.replay.core.trajectory import COLUMNS, canonical_order
from trackreplay.schemas.errors import TrackreplayError
from trackreplay.trackers.appearance.color import to_ycrcb
from trackreplay.trackers.foreground.morphology import disc_top_hat
from trackreplay.trackers.geometry.ptz import PtzCamera, pose_homography
from trackreplay.trackers.golf.silhouette import previous_in_pose


@dataclass(frozen=True)
class RescanConfig:
    """``flight --rescan``: where and how hard the frames the tracker missed are searched."""

    gate_px: float = 5.0  # the ball is looked for within this of the fitted position (at reference_height) ...
    gate_diameters: float = 1.0  # ... or this many fitted diameters, whichever is larger
    min_snr: float = 6.0  # robust sigmas of the window's matched-filter response
    exposures: tuple[float, ...] = (0.0, 0.25, 0.5, 0.75, 1.0)  # fractions of the frame interval tried
    kernel_diameters: float = 3.0  # the top-hat's disc, in ball diameters (at least 5 px)
    world_frames: int = 3  # the world behind the ball: the median of the frames up to this many either side that
    # show it (the ball elsewhere by its diameter and twice registration_px), each in this pose
    registration_px: float = 1.0  # the poses' error: each of those frames' brightest within this
    min_new_snr: float = 4.0  # robust sigmas of the response over what is new in the world (static clutter is not)
    min_world: int = 2  # frames that must have seen the world behind the ball, over the gate and the template
    min_contrast: float = 1.0  # grey levels: the least mean contrast over the ball's image that counts at all
    window_px: float = 40.0  # half-width of the window the noise is measured over, beyond the template
    reach: int = 3  # a frame is searched once a measured (or found) frame is at most this many frames away:
    # the fit is trusted next to its data, and grows into a gap a round at a time
    rounds: int = 40  # look, refit, look again ... at most this many times
    # ... and only where the fit knows the ball's place well enough: this many of its 1-σ (the
    # fit's covariance, carried into the picture) within the gate. The covariance leaves model error
    # out: in the default tee shot's launch gap the fit was off by 4-6 of its σ.
    sigma_factor: float = 5.0
    reference_height: int = 720

    def __post_init__(self) -> None:
        if self.gate_px <= 0 or self.min_snr <= 0 or not self.exposures or self.rounds < 1 or self.reach < 1:
            raise ValueError("rescan: need gate_px > 0, min_snr > 0, at least one exposure, one round and a reach of 1")
        if self.world_frames < 1 or self.min_world < 1 or self.registration_px < 0 or self.min_contrast < 0 or self.sigma_factor < 0:
            raise ValueError("rescan: need world_frames >= 1, min_world >= 1, and registration_px, min_contrast, sigma_factor >= 0")
        if any(not 0.0 <= e <= 1.0 for e in self.exposures):
            raise ValueError("rescan: exposures are fractions of the frame interval in [0, 1]")


@dataclass(frozen=True)
class ExpectedBall:
    """Where the fitted flight puts the ball in one frame's picture."""

    frame: int
    centre: np.ndarray  # (2,) px, at the frame's time
    path: np.ndarray  # (m, 2) px from centre, over one frame interval round the frame's time (odd m; the middle 0)
    diameter: float  # px
    sigma: float = 0.0  # px, 1-σ of centre along its most uncertain direction
    away: tuple[tuple[int, float], ...] = ()  # (frame offset, px): the ball's place that many frames off, in this pose


@dataclass(frozen=True)
class Sighting:
    """The ball found in one frame by :func:`look`."""

    frame: int
    point: np.ndarray  # (2,) px
    snr: float  # the response's peak over the window's robust sigma
    exposure: float  # the exposure fraction whose template answered best
    offset: float  # px from the fitted position
    new_snr: float = math.nan  # the same response over what stands above the world behind the ball, at that place


@dataclass(frozen=True, eq=False)
class RescanResult:
    trajectory: pl.DataFrame  # the tracker's rows, with the frames found measured (fill "rescan")
    fit: FlightFit  # the flight fitted to every measured frame, the found ones included
    sightings: tuple[Sighting, ...]  # the frames kept, in frame order
    rounds: tuple[int, ...]  # frames found per round
    dropped: tuple[int, ...]  # frames found, then further than the gate from the final fit
    warnings: tuple[str, ...] = ()  # frames that could not be read (damaged), not searched


def expected_balls(fit: FlightFit, frames: list[int], times: dict[int, int], cameras: dict[int, PtzCamera],
                   samples: int = 33, world_frames: int = 2) -> list[ExpectedBall]:
    """The fitted ball in each of ``frames`` that has a pose and sees it: position at the frame's
    time and its 1-σ in the picture (the fit's covariance carried through the flight and the
    projection), its path across the sensor over the frame interval round that time (the flight
    sampled ``samples`` times, each point moved as the camera's own panning and zooming moves a
    fixed point there: central differences of the neighbouring frames' poses), apparent diameter ``f D / r``,
    and how far it is, in this frame's pose, from where it was ``1 .. world_frames`` frames before and after."""
    known = sorted(i for i in times if i in cameras)
    wanted = []
    for i in frames:
        if i in cameras and i in times:
            p = cameras[i].project_points(fit.shot.at(np.array([times[i] * 1e-9]))[0])[0]
            if np.isfinite(p).all() and cameras[i].in_image(p.reshape(1, 2))[0]:
                wanted.append(i)
    if not wanted:
        return []
    t = np.array([times[i] for i in wanted], dtype=np.float64) * 1e-9
    pos, dpos, _ = fit.sensitivity(t)  # (m, 3), (m, 3, p)
    ordinal = {i: k for k, i in enumerate(known)}
    out = []
    for j, i in enumerate(wanted):
        k, cam = ordinal[i], cameras[i]
        uv = cam.project_points(pos[j:j + 1])[0]
        before = cameras[known[k - 1]] if k > 0 and known[k - 1] == i - 1 else None
        after = cameras[known[k + 1]] if k + 1 < len(known) and known[k + 1] == i + 1 else None
        dt = _frame_interval(times, i)
        s = np.linspace(-0.5, 0.5, samples)
        path_pos, _ = fit.shot.at(t[j] + s * dt)
        path = cam.project_points(path_pos)
        shift = _camera_shift(cam, before, after, path_pos)  # px per frame interval, of a fixed point at each
        path = path + s[:, None] * shift - uv[None, :]
        f = math.sqrt(cam.intrinsics.fx * cam.intrinsics.fy)
        r = float(np.linalg.norm(pos[j] - np.asarray(cam.position, float)))
        jac = _projection_jacobian(cam, pos[j], uv, r) @ dpos[j]  # (2, p)
        sigma = float(np.sqrt(max(float(np.linalg.eigvalsh(jac @ fit.cov @ jac.T)[-1]), 0.0)))
        others = [i + o for o in range(-world_frames, world_frames + 1) if o and i + o in times]
        then = cam.project_points(fit.shot.at(np.array([times[n] * 1e-9 for n in others]))[0]) if others else np.zeros((0, 2))
        away = np.hypot(*(then - uv).T) if others else np.zeros(0)
        out.append(ExpectedBall(i, uv.copy(), np.where(np.isfinite(path), path, 0.0), f * fit.config.ball.diameter / max(r, 1e-6),
                                sigma, tuple((n - i, float(a) if np.isfinite(a) else 0.0) for n, a in zip(others, away))))
    return out


def _frame_interval(times: dict[int, int], index: int) -> float:
    """Seconds between this frame and its neighbours (the mean of the gaps either side present)."""
    gaps = [abs(times[index] - times[j]) * 1e-9 for j in (index - 1, index + 1) if j in times]
    return float(np.mean(gaps)) if gaps else 0.0


def _camera_shift(cam: PtzCamera, before: PtzCamera | None, after: PtzCamera | None, points: np.ndarray) -> np.ndarray:
    """How far (px per frame interval) the camera's own motion moves fixed ``points`` (world) across
    this frame: half the difference of the next and previous frames' projections (one side alone
    at the ends of the log); zero without a neighbour."""
    if before is not None and after is not None:
        return (after.project_points(points) - before.project_points(points)) / 2.0
    if after is not None:
        return after.project_points(points) - cam.project_points(points)
    if before is not None:
        return cam.project_points(points) - before.project_points(points)
    return np.zeros((len(points), 2))


def _projection_jacobian(cam: PtzCamera, point: np.ndarray, uv: np.ndarray, distance: float) -> np.ndarray:
    """``d(u, v) / d(X, Y, Z)`` (2, 3) at ``point``, by finite differences of a millimetre per metre of distance."""
    h = 1e-3 * max(distance, 1.0)
    moved = cam.project_points(point[None, :] + h * np.eye(3))
    return ((moved - uv[None, :]) / h).T


SUPERSAMPLE = 4  # the template is drawn this many times finer, then averaged down


def ball_template(diameter: float, path: np.ndarray) -> np.ndarray:
    """The image of a disc ``diameter`` px wide swept along ``path`` (points in px from the
    template's centre, in time order) during the exposure, as float32 weights that sum to 1: drawn
    as a thick round-capped polyline ``SUPERSAMPLE`` times finer and averaged down (a ball bouncing
    mid-exposure leaves a bent streak; a sub-pixel ball still weighs its pixel)."""
    path = np.asarray(path, float).reshape(-1, 2)
    half = int(math.ceil(max(diameter, 1.0) / 2.0 + float(np.max(np.abs(path))) + 1.0))
    side = 2 * half + 1
    fine = np.zeros((side * SUPERSAMPLE, side * SUPERSAMPLE), np.uint8)
    points = np.round(((path + half + 0.5) * SUPERSAMPLE - 0.5) * 16).astype(np.int32)  # 4 fractional bits
    thickness = max(1, int(round(diameter * SUPERSAMPLE)))
    if len(points) > 1:  # (a thick polyline has round caps)
        cv2.polylines(fine, [points.reshape(-1, 1, 2)], False, 255, thickness, cv2.LINE_8, shift=4)
    else:
        cv2.circle(fine, tuple(int(v) for v in points[0]), max(thickness // 2, 1) * 16, 255, -1, cv2.LINE_8, shift=4)  # (radius in the same fractional bits)
    weights = cv2.resize(fine.astype(np.float32), (side, side), interpolation=cv2.INTER_AREA)
    return weights / float(weights.sum())


def exposed(path: np.ndarray, exposure: float) -> np.ndarray:
    """The part of a frame interval's ``path`` (odd length, centred) an exposure of this fraction sees."""
    m = len(path)
    half = int(round(exposure * (m - 1) / 2.0))
    return path[(m - 1) // 2 - half:(m - 1) // 2 + half + 1]


def look(luminance: np.ndarray, ball: ExpectedBall, cfg: RescanConfig, scale: float,
         neighbours: list[tuple[np.ndarray, np.ndarray]]) -> Sighting | None:
    """Is the ball where ``ball`` expects it in this frame's ``luminance`` (uint8)? The matched
    filter of the module docstring: the response over the top-hat must peak in the gate, and the
    response over what also stands above the world behind the ball (``neighbours``: frames in which
    the ball is elsewhere, as ``(luminance, homography to this frame)``) must be there too. None
    when it is not, or when the question cannot be asked (the place not seen by ``min_world``
    neighbours, a fit unsure of the place)."""
    height, width = luminance.shape
    d = max(ball.diameter, 1.0)
    gate = _gate(cfg, d, scale)
    registration = cfg.registration_px * scale
    if len(neighbours) < cfg.min_world or cfg.sigma_factor * ball.sigma > gate:
        return None
    extent = float(np.max(np.abs(ball.path))) + d
    side = max(5, int(round(cfg.kernel_diameters * d)) | 1)
    half = int(math.ceil(gate + extent + cfg.window_px * scale + side))
    cx, cy = (float(v) for v in ball.centre)
    x0, y0 = max(int(math.floor(cx)) - half, 0), max(int(math.floor(cy)) - half, 0)
    x1, y1 = min(int(math.floor(cx)) + half + 1, width), min(int(math.floor(cy)) + half + 1, height)
    if x1 - x0 < 2 * side or y1 - y0 < 2 * side:
        return None
    crop = np.ascontiguousarray(luminance[y0:y1, x0:x1])
    hat = disc_top_hat(crop, side)
    rise, seen_by = rise_over_world(crop, hat, neighbours, (x0, y0), registration)
    rows, cols = np.mgrid[y0:y1, x0:x1]
    r2 = (cols - cx) ** 2 + (rows - cy) ** 2
    in_gate = r2 <= gate ** 2
    if int(seen_by[r2 <= (gate + extent) ** 2].min()) < cfg.min_world:
        return None  # the world behind the ball there is not seen by enough frames (the picture's edge)
    hat = hat.astype(np.float32)
    best = None
    for exposure in cfg.exposures:
        template = ball_template(d, exposed(ball.path, exposure))
        response, snr = _matched(hat, template, cfg.min_contrast)
        # the highest local maximum in the gate (the rim of the gate on the flank of something brighter outside is none)
        peaks = in_gate & (response >= cv2.dilate(response, np.ones((3, 3), np.uint8)))
        if not peaks.any():
            continue
        k = int(np.argmax(np.where(peaks, response, -np.inf)))
        py, px = divmod(k, response.shape[1])
        if best is None or snr[py, px] > best[0]:
            best = (float(snr[py, px]), exposure, px, py, response, template)
    if best is None or best[0] < cfg.min_snr:
        return None
    snr, exposure, px, py, response, template = best
    valid = seen_by > 0
    _, new = _matched(np.where(valid, rise, np.float32(np.median(rise[valid]))), template, cfg.min_contrast, valid)
    new_snr = float(np.max(new[max(py - 1, 0):py + 2, max(px - 1, 0):px + 2]))
    if new_snr < cfg.min_new_snr:
        return None
    point = np.array([x0 + px + _vertex(response, py, px, 1), y0 + py + _vertex(response, py, px, 0)])
    return Sighting(ball.frame, point, snr, float(exposure), float(np.hypot(*(point - ball.centre))), new_snr)


QUANTUM_SIGMA = 1.0 / math.sqrt(12.0)  # grey levels: the rounding of a picture to integers, the least noise it has


def _matched(signal: np.ndarray, template: np.ndarray, min_contrast: float,
             valid: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The template's response over ``signal`` and the same in robust sigmas above its median (over
    the ``valid`` pixels). The sigma is at least what rounding to grey levels leaves in a weighted mean
    over the template, and the response must rise ``min_contrast`` levels above the median to count at
    all: on a flat or clipped sky most of the response is one value, its spread 0, and a single level
    of difference would be any number of sigmas."""
    response = cv2.filter2D(signal, cv2.CV_32F, template, borderType=cv2.BORDER_REFLECT)
    values = response if valid is None else response[valid]
    median = float(np.median(values))
    sigma = max(1.4826 * float(np.median(np.abs(values - median))), QUANTUM_SIGMA * float(np.linalg.norm(template)))
    above = response - median
    return response, np.where(above >= min_contrast, above / sigma, np.minimum(above / sigma, 0.0))


def rise_over_world(crop: np.ndarray, hat: np.ndarray, neighbours: list[tuple[np.ndarray, np.ndarray]],
                    offset: tuple[int, int], registration: float) -> tuple[np.ndarray, np.ndarray]:
    """How far each pixel of ``crop`` stands above both its local background (``hat``, the top-hat)
    and the same place of the world in the ``neighbours`` (each brought into this pose, the
    brightest within ``registration`` px of it for the poses' error; the median of those that saw
    the place, so a neighbour that shows the ball there does not count): float32, negative where
    the world there is brighter, NaN where no neighbour saw it; and how many neighbours saw each
    pixel. Clouds, turf, tee markers and spare balls are where they were; the ball is not."""
    k = 2 * max(int(round(registration)), 0) + 1
    square = np.ones((k, k), np.uint8)
    shape = crop.shape[:2]
    stack = np.full((len(neighbours),) + shape, np.nan, np.float32)
    for n, (image, homography) in enumerate(neighbours):
        there = previous_in_pose(image, homography, offset, shape)
        unseen = previous_in_pose(np.zeros(image.shape[:2], np.uint8), homography, offset, shape) > 0  # (255 off its picture)
        if k > 1:
            there, unseen = cv2.dilate(there, square), cv2.dilate(unseen.astype(np.uint8), square) > 0
        stack[n] = np.where(unseen, np.nan, there.astype(np.float32))
    seen_by = np.sum(~np.isnan(stack), axis=0)
    ordered = np.sort(stack, axis=0)  # NaN last
    low = np.take_along_axis(ordered, np.maximum(seen_by - 1, 0)[None] // 2, axis=0)[0]
    high = np.take_along_axis(ordered, (seen_by // 2)[None], axis=0)[0] if len(neighbours) > 1 else low
    world = np.where(seen_by > 0, (low + np.where(seen_by > 1, high, low)) / 2.0, np.nan)
    return np.minimum(hat.astype(np.float32), crop.astype(np.float32) - world.astype(np.float32)), seen_by


def _vertex(response: np.ndarray, py: int, px: int, axis: int) -> float:
    """Sub-pixel offset of the peak along ``axis`` (0: rows, 1: columns): the vertex of the parabola
    through it and its two neighbours (0 at the window's edge)."""
    n = response.shape[axis]
    at = py if axis == 0 else px
    if at == 0 or at == n - 1:
        return 0.0
    a, b, c = ((response[at - 1, px], response[at, px], response[at + 1, px]) if axis == 0
               else (response[py, at - 1], response[py, at], response[py, at + 1]))
    denom = float(a) - 2.0 * float(b) + float(c)
    return float(np.clip(0.5 * (float(a) - float(c)) / denom, -0.5, 0.5)) if denom < 0 else 0.0


def _luminances(log: Path, wanted: set[int], unreadable: dict[int, str]):
    """``(frame index, uint8 luminance)`` of the ``wanted`` frames, in log order; only those are decoded
    (straight to their chunks when the log's message indexes allow). A frame lost with a damaged
    chunk, or whose image does not decode, is left out and named in ``unreadable``."""
    from trackreplay.replay.log.decode import decode_image
    from trackreplay.replay.log.frames import FrameTopics
    from trackreplay.replay.log.reader import LogReader
    from trackreplay.schemas.errors import LogError

    if not wanted:
        return
    reader = LogReader(log)
    topic = FrameTopics.detect(reader).image
    items = reader.messages_at(topic, wanted)
    last = max(wanted)
    for item in reader.messages([topic]) if items is None else items:
        if item.index in wanted:
            where = f"{reader.path}: topic {item.topic} message {item.index}"
            if item.lost is not None:
                unreadable[item.index] = f"{where}: lost with a damaged chunk"
            else:
                try:
                    image = decode_image(item.decode(), item.schema, where)[0]
                except LogError as err:
                    unreadable[item.index] = str(err)
                else:
                    yield item.index, (cv2.extractChannel(to_ycrcb(image), 0) if image.ndim == 3 else image)
        if item.index >= last:
            break


def _with_sightings(traj: pl.DataFrame, sightings: list[Sighting], fit: FlightFit, times: dict[int, int],
                    cameras: dict[int, PtzCamera], track: tuple[str, int]) -> pl.DataFrame:
    """The trajectory with a ``measured`` row (``fill`` ``rescan``) in place of each sighting's frame
    of ``track`` (tracker, track id); every other row as it was."""
    base = traj if "fill" in traj.columns else traj.with_columns(pl.lit(None, pl.String).alias("fill"))
    if not sightings:
        return base
    tracker, track_id = track
    frames = [s.frame for s in sightings]
    t_ns = np.array([times[f] for f in frames], dtype=np.int64)
    pos, _ = fit.shot.at(t_ns * 1e-9)
    los = np.stack([cameras[f].line_of_sight(s.point.reshape(1, 2))[0] for f, s in zip(frames, sightings)])
    n = len(frames)
    nan = [None] * n
    rows = pl.DataFrame({
        "tracker": [tracker] * n, "track_id": [track_id] * n, "frame": frames, "t_ns": t_ns,
        "x": [float(s.point[0]) for s in sightings], "y": [float(s.point[1]) for s in sightings], "w": nan, "h": nan,
        "X": pos[:, 0], "Y": pos[:, 1], "Z": pos[:, 2], "dx": los[:, 0], "dy": los[:, 1], "dz": los[:, 2],
        "vx": nan, "vy": nan, "status": ["measured"] * n,
        "confidence": [float(min(1.0, s.snr / 20.0)) for s in sightings], "fill": ["rescan"] * n,
    })
    rows = rows.select([pl.col(c).cast(base.schema[c]) if c in rows.columns else pl.lit(None, base.schema[c]).alias(c)
                        for c in base.columns])
    mine = (pl.col("tracker") == tracker) & (pl.col("track_id") == track_id)
    keep = base.filter(~(mine & pl.col("frame").is_in(frames)))
    return canonical_order(pl.concat([keep, rows]), extra=tuple(c for c in base.columns if c not in COLUMNS))


def rescan(traj: pl.DataFrame, log: Path, times: dict[int, int], cameras: dict[int, PtzCamera], *,
           track_id: int, config: RescanConfig = RescanConfig(), flight: FlightConfig = FlightConfig(),
           fps: float = 30.0, what: str = "the trajectory", tracker: str = "golf") -> RescanResult:
    """Look for the ball along the fitted flight in the frames of ``log`` track ``track_id`` of
    ``tracker`` did not measure (module docstring), from those next to measured frames outwards,
    fitting again after each round; deterministic. Rows of other tracks are kept as they are."""
    quick = dataclasses.replace(flight, jackknife_blocks=0)  # the rounds need the flight, not its uncertainty
    track = (tracker, int(track_id))
    own = traj.filter((pl.col("tracker") == tracker) & (pl.col("track_id") == track_id))
    if own.is_empty():
        raise TrackreplayError(f"{what} has no {tracker} track {track_id}")
    measured = set(own.filter(pl.col("status") == "measured")["frame"].to_list())
    frames = sorted(times)
    found: dict[int, Sighting] = {}
    unreadable: dict[int, str] = {}
    per_round: list[int] = []

    def refit(sightings: dict[int, Sighting], cfg: FlightConfig) -> FlightFit:
        rows = _with_sightings(own, sorted(sightings.values(), key=lambda s: s.frame), fit, times, cameras, track) if sightings else own
        return fit_flight(observations(rows, cameras, track_id=track_id, what=what), cfg, fps)

    fit = fit_flight(observations(own, cameras, track_id=track_id, what=what), quick, fps)
    for _ in range(config.rounds):
        seen = np.array(sorted(measured | set(found)))
        todo = [i for i in frames if i not in measured and i not in found and i not in unreadable and _within(seen, i, config.reach)]
        balls = {b.frame: b for b in expected_balls(fit, todo, times, cameras, world_frames=config.world_frames)}
        new = _look_all(log, balls, cameras, config, unreadable)
        per_round.append(len(new))
        if not new:
            break
        found.update({s.frame: s for s in new})
        fit = refit(found, quick)
    # every frame found, against the final fit: one the flight no longer passes through is dropped, and
    # the flight fitted again without it, until all that are left agree with it
    dropped: list[int] = []
    while found:
        balls = {b.frame: b for b in expected_balls(fit, sorted(found), times, cameras)}
        off = [i for i, s in sorted(found.items())
               if (b := balls.get(i)) is None or float(np.hypot(*(s.point - b.centre))) > _gate(
                   config, b.diameter, float(cameras[i].intrinsics.height) / config.reference_height)]
        if not off:
            break
        dropped += off
        for index in off:
            del found[index]
        fit = refit(found, quick)
    sightings = tuple(sorted(found.values(), key=lambda s: s.frame))
    fit = refit(found, flight)
    out = _with_sightings(traj, list(sightings), fit, times, cameras, track)  # X, Y, Z from the final fit
    warnings = tuple(f"frame {i} not searched: {unreadable[i]}" for i in sorted(unreadable))
    return RescanResult(out, fit, sightings, tuple(per_round), tuple(sorted(dropped)), warnings)


def _look_all(log: Path, balls: dict[int, ExpectedBall], cameras: dict[int, PtzCamera], config: RescanConfig,
              unreadable: dict[int, str] | None = None) -> list[Sighting]:
    """:func:`look` in each frame of ``balls``, with the frames either side that show the world
    behind the ball there (:func:`_clear_px`). Frames that cannot be read go into ``unreadable``."""
    clear = {i: [i + o for o, px in ball.away if i + o in cameras and px >= _clear_px(config, ball, cameras[i])]
             for i, ball in balls.items()}
    images = dict(_luminances(log, set(balls).union(*clear.values()), {} if unreadable is None else unreadable))
    found = []
    for index in sorted(balls):
        if index not in images:
            continue
        neighbours = [(images[n], pose_homography(cameras[n], cameras[index])) for n in clear[index] if n in images]
        lum = images[index]
        sighting = look(lum, balls[index], config, lum.shape[0] / config.reference_height, neighbours)
        if sighting is not None:
            found.append(sighting)
    return found


def _clear_px(config: RescanConfig, ball: ExpectedBall, camera: PtzCamera) -> float:
    """How far the ball must be elsewhere in a frame for that frame to show the world behind it here."""
    return max(ball.diameter, 1.0) + 2.0 * config.registration_px * float(camera.intrinsics.height) / config.reference_height


def _within(seen: np.ndarray, index: int, reach: int) -> bool:
    """A frame in ``seen`` (sorted) lies within ``reach`` frames of ``index``."""
    k = int(np.searchsorted(seen, index))
    return (k < seen.size and seen[k] - index <= reach) or (k > 0 and index - seen[k - 1] <= reach)


def _gate(config: RescanConfig, diameter: float, scale: float) -> float:
    """How far from the fitted position the ball is looked for (px)."""
    return max(config.gate_px * scale, config.gate_diameters * max(diameter, 1.0))
