"""Iterative refinement (eq. 9–10) with coarse-to-fine smoothing, and its on-line form (eq. 25).

Each refinement aligns the two frames by the current flow and solves the local least squares of
eq. 5–7 again (eq. 9). Two implementation choices, both measured on translated textures:

- the frames are warped half-way each, ``E(x − w/2, n)`` and ``E(x + w/2, n+1)``, so both carry
  the same bilinear-interpolation blur (warping only the second frame leaves that blur in
  ``E_t`` as spurious motion: 5–10× larger error on a 0.3 px shift);
- each of the m equations is linearised about its own pixel's current flow, so the neighbourhood
  solve gives the corrected flow itself; one correction shared by pixels whose starts differ
  would keep the start's pixel-to-pixel noise for ever.

A consequence of the first: the flow field lives half-way between the two frames.
Coarse to fine (§2, ref. 17) blurs both frames with a Gaussian whose σ shrinks as iterations
proceed; the blur widens the range where the first-order Taylor model (eq. 2) holds.
"""

from __future__ import annotations

import dataclasses
import functools

import cv2
import numpy as np

from trackreplay.trackers.flow.config import FlowConfig
from trackreplay.trackers.flow.derivatives import derivatives
from trackreplay.trackers.flow.local_flow import FlowField, local_flow


def blur(image: np.ndarray, sigma: float) -> np.ndarray:
    if sigma <= 0:
        return image
    return cv2.GaussianBlur(image, (0, 0), sigmaX=sigma, sigmaY=sigma, borderType=cv2.BORDER_REPLICATE)


@functools.lru_cache(maxsize=16)
def _grid(h: int, w: int) -> tuple[np.ndarray, np.ndarray]:
    """Pixel columns (1, w) and rows (h, 1) as float32, made once per window size."""
    xs = np.arange(w, dtype=np.float32)[None, :]
    ys = np.arange(h, dtype=np.float32)[:, None]
    xs.setflags(write=False)
    ys.setflags(write=False)
    return xs, ys


def _remap(image: np.ndarray, gx: np.ndarray, gy: np.ndarray) -> np.ndarray:
    return cv2.remap(image, gx, gy, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)


def warp(image: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``image(x + u, y + v)``, bilinear; beyond the window the edge pixels repeat."""
    h, w = image.shape
    xs, ys = _grid(h, w)
    gx = xs + u
    gy = ys + v
    return _remap(image, gx.astype(np.float32, copy=False), gy.astype(np.float32, copy=False))


def aligned(s0: np.ndarray, s1: np.ndarray, u: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Both frames moved half-way along the flow: ``E(x − w/2, n)``, ``E(x + w/2, n+1)``."""
    hu, hv = np.float32(0.5) * u, np.float32(0.5) * v
    if hu.dtype != np.float32 or hv.dtype != np.float32 or s0.shape != hu.shape:
        return warp(s0, -hu, -hv), warp(s1, hu, hv)
    xs, ys = _grid(*s0.shape)
    # x + (−h) is x − h exactly (IEEE), so this is warp(s0, −hu, −hv) without the negations
    return _remap(s0, xs - hu, ys - hv), _remap(s1, xs + hu, ys + hv)


def _rms(a: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(a, dtype=np.float64))))


def refine_once(
    e0: np.ndarray, e1: np.ndarray, u0: np.ndarray, v0: np.ndarray, sigma: float, config: FlowConfig,
    *, before: bool = True,
) -> tuple[FlowField, float]:
    """One step of eq. 9 from the finite start ``(u0, v0)`` at blur ``sigma``.

    Returns the new field (NaN where eq. 8 rejects the solve; its ``residual`` is the RMS
    misalignment after the step) and the misalignment before it, which eq. 10 compares
    (NaN when ``before`` is False: the on-line step does not compare).
    """
    s0, s1 = blur(e0, sigma), blur(e1, sigma)
    moved = bool(np.any(u0) or np.any(v0))
    a0, a1 = aligned(s0, s1, u0, v0) if moved else (s0, s1)
    ex, ey, et = derivatives(a0, a1, config.derivative, config.derivative_order)
    if moved:
        et = et - ex * u0 - ey * v0
    solved = local_flow(ex, ey, et, config.neighbourhood, config.cond_max, config.min_energy)
    # where eq. 8 accepts, the new flow; elsewhere the start (the alignment needs finite values)
    u = np.where(solved.valid, solved.u, u0).astype(np.float32, copy=False)
    v = np.where(solved.valid, solved.v, v0).astype(np.float32, copy=False)
    b0, b1 = aligned(s0, s1, u, v)
    # the field itself: solved.u/v already hold NaN where rejected
    flow = FlowField(solved.u, solved.v, solved.valid, solved.cond, _rms(b1 - b0), 1)
    return flow, _rms(a1 - a0) if before else float("nan")


def _iterate(e0: np.ndarray, e1: np.ndarray, u: np.ndarray, v: np.ndarray, config: FlowConfig) -> FlowField:
    """Eq. 7 (or eq. 9 from a start), then eq. 9 while eq. 10 holds, σ from ``config.sigmas``."""
    best: FlowField | None = None
    for n in range(config.refine_iterations):
        new, before = refine_once(e0, e1, u, v, config.sigma_at(n), config)
        if new.residual > before:  # eq. 10 fails: keep the previous estimate
            break
        best = dataclasses.replace(new, iterations=n + 1)
        # a rejected pixel keeps its earlier estimate as the start of the next step
        u = np.where(new.valid, new.u, u).astype(np.float32)
        v = np.where(new.valid, new.v, v).astype(np.float32)
    if best is None:
        best = dataclasses.replace(FlowField.zeros(e0.shape), residual=before)
    return best


def refine_flow(e0: np.ndarray, e1: np.ndarray, config: FlowConfig) -> FlowField:
    """Offline flow between two frames: up to ``config.refine_iterations`` solves (eq. 7, 9, 10).

    With ``config.pyramid_levels`` > 0 (not in the paper) the same iteration runs first on
    half-resolution copies; the flow, doubled and upsampled, starts the next finer level.
    """
    e0 = np.asarray(e0, dtype=np.float32)
    e1 = np.asarray(e1, dtype=np.float32)
    pyramid = [(e0, e1)]
    for _ in range(config.pyramid_levels):
        a, b = pyramid[-1]
        if min(a.shape) < 4 * max(config.derivative, config.neighbourhood):
            break
        pyramid.append((cv2.pyrDown(a, borderType=cv2.BORDER_REPLICATE), cv2.pyrDown(b, borderType=cv2.BORDER_REPLICATE)))
    u = np.zeros(pyramid[-1][0].shape, np.float32)
    v = np.zeros_like(u)
    flow = FlowField.zeros(e0.shape)
    for level in range(len(pyramid) - 1, -1, -1):
        a, b = pyramid[level]
        if u.shape != a.shape:
            size = (a.shape[1], a.shape[0])
            u = 2.0 * cv2.resize(u, size, interpolation=cv2.INTER_LINEAR)
            v = 2.0 * cv2.resize(v, size, interpolation=cv2.INTER_LINEAR)
        flow = _iterate(a, b, u, v, config)
        u = np.where(flow.valid, flow.u, u).astype(np.float32)
        v = np.where(flow.valid, flow.v, v).astype(np.float32)
    return flow


def online_step(e0: np.ndarray, e1: np.ndarray, prev_flow: FlowField | None, config: FlowConfig, *, step: int = 0) -> FlowField:
    """On-line flow (§4.1, eq. 25): ONE refinement per frame, started from the previous frame's flow.

    ``prev_flow`` None gives the initial estimate of eq. 7. ``step`` counts frames since the start
    and picks σ from ``config.sigmas``: time replaces the iteration count, blur included.
    """
    e0 = np.asarray(e0, dtype=np.float32)
    e1 = np.asarray(e1, dtype=np.float32)
    if prev_flow is None:
        u = np.zeros(e0.shape, np.float32)
        v = np.zeros_like(u)
    else:
        u, v = prev_flow.filled()
    flow, _ = refine_once(e0, e1, u, v, config.sigma_at(step), config, before=False)
    return flow
