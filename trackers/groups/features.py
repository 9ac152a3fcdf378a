"""§3.1 KLT features on the foreground with a 3-D position from the disparity, and the time window.

Features are Shi–Tomasi corners of the left foreground, tracked by pyramidal Lucas–Kanade with a
forward–backward check; a feature that leaves the foreground or fails the check is dropped. Each
keeps its last ``window`` observations ``(u, v, d)``. Only features tracked over the whole window
(Fig. 3) with a disparity in at least half of it are **observation points**: position from the
current ``(u, v)`` and the window's median disparity, velocity (m/frame) the least-squares slope of
the window's 3-D positions.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from trackreplay.trackers.geometry.stereo import StereoRig
from trackreplay.trackers.groups.config import KltConfig


@dataclass(frozen=True, eq=False)
class ObservationPoints:
    ids: np.ndarray  # (M,) feature ids
    uvd: np.ndarray  # (M, 3) current u v and the window's median d
    xyz: np.ndarray  # (M, 3) camera frame, m
    velocity: np.ndarray  # (M, 3) m/frame
    track_uv: np.ndarray  # (M, W, 2) the window's image positions (the KLT tracks drawn in the view)

    @classmethod
    def empty(cls, window: int = 2) -> ObservationPoints:
        return cls(np.zeros(0, np.int64), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, window, 2)))

    def __len__(self) -> int:
        return len(self.ids)

    def take(self, keep: np.ndarray) -> ObservationPoints:
        return ObservationPoints(self.ids[keep], self.uvd[keep], self.xyz[keep], self.velocity[keep], self.track_uv[keep])


def disparity_at(disparity: np.ndarray, uv: np.ndarray, window: int) -> np.ndarray:
    """Median of the finite disparities in a ``window`` square around each point (NaN if none)."""
    if len(uv) == 0:
        return np.zeros(0)
    h, w = disparity.shape
    r = window // 2
    off = np.arange(-r, r + 1)
    ui = np.clip(np.round(uv[:, 0]).astype(np.int64)[:, None, None] + off[None, None, :], 0, w - 1)
    vi = np.clip(np.round(uv[:, 1]).astype(np.int64)[:, None, None] + off[None, :, None], 0, h - 1)
    patch = disparity[vi, ui].reshape(len(uv), -1).astype(np.float64)
    out = np.full(len(uv), np.nan)
    ok = np.isfinite(patch).any(axis=1)
    if ok.any():
        out[ok] = np.nanmedian(patch[ok], axis=1)
    return out


class KltFeatures:
    """Feature tracks with their last ``window`` (u, v, d) observations; ids counted per instance."""

    def __init__(self, cfg: KltConfig, disparity_window: int) -> None:
        self.cfg = cfg
        self.disparity_window = disparity_window
        self.prev: np.ndarray | None = None
        self.uv = np.zeros((0, 2), np.float32)
        self.ids = np.zeros(0, np.int64)
        self.hist = np.zeros((0, cfg.window, 3))  # oldest first; NaN rows where not yet tracked
        self.age = np.zeros(0, np.int64)
        self.next_id = 0

    def step(self, grey: np.ndarray, foreground: np.ndarray, disparity: np.ndarray) -> None:
        cfg = self.cfg
        h, w = grey.shape
        if self.prev is not None and len(self.uv):
            lk = dict(winSize=(cfg.win, cfg.win), maxLevel=cfg.levels,
                      criteria=(cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 20, 0.03))
            p0 = self.uv.reshape(-1, 1, 2)
            p1, st, _ = cv2.calcOpticalFlowPyrLK(self.prev, grey, p0, None, **lk)
            back, st2, _ = cv2.calcOpticalFlowPyrLK(grey, self.prev, p1, None, **lk)
            p1, back = p1.reshape(-1, 2), back.reshape(-1, 2)
            fb = np.linalg.norm(back - self.uv, axis=1)
            inside = (p1[:, 0] >= 0) & (p1[:, 0] <= w - 1) & (p1[:, 1] >= 0) & (p1[:, 1] <= h - 1)
            keep = (st.ravel() == 1) & (st2.ravel() == 1) & (fb < cfg.forward_backward_px) & inside
            ui = np.clip(np.round(p1[:, 0]).astype(np.int64), 0, w - 1)
            vi = np.clip(np.round(p1[:, 1]).astype(np.int64), 0, h - 1)
            keep &= foreground[vi, ui]
            self.uv, self.ids, self.hist, self.age = p1[keep], self.ids[keep], self.hist[keep], self.age[keep] + 1
        else:
            self.uv, self.ids, self.hist, self.age = (self.uv[:0], self.ids[:0], self.hist[:0], self.age[:0])
        # new corners on the foreground away from the tracked ones
        room = cfg.max_corners - len(self.uv)
        if room > 0 and foreground.any():
            mask = foreground.astype(np.uint8) * 255
            for u, v in np.round(self.uv).astype(np.int64).tolist():
                cv2.circle(mask, (u, v), int(cfg.min_distance), 0, -1)
            corners = cv2.goodFeaturesToTrack(grey, room, cfg.quality, cfg.min_distance, mask=mask, blockSize=5)
            if corners is not None:
                new = corners.reshape(-1, 2).astype(np.float32)
                n = len(new)
                self.uv = np.vstack([self.uv, new])
                self.ids = np.concatenate([self.ids, np.arange(self.next_id, self.next_id + n)])
                self.hist = np.concatenate([self.hist, np.full((n, cfg.window, 3), np.nan)])
                self.age = np.concatenate([self.age, np.ones(n, np.int64)])
                self.next_id += n
        d = disparity_at(disparity, self.uv.astype(np.float64), self.disparity_window)
        entry = np.concatenate([self.uv.astype(np.float64), d[:, None]], axis=1)
        self.hist = np.concatenate([self.hist[:, 1:], entry[:, None, :]], axis=1)
        self.prev = grey

    def observation_points(self, rig: StereoRig) -> ObservationPoints:
        W = self.cfg.window
        full = self.age >= W
        d_hist = self.hist[:, :, 2]
        enough = np.isfinite(d_hist).sum(axis=1) >= (W + 1) // 2
        keep = full & enough & np.isfinite(self.hist[:, -1, 0])
        if not keep.any():
            return ObservationPoints.empty(W)
        hist = self.hist[keep]
        d_med = np.nanmedian(hist[:, :, 2], axis=1)
        good = d_med > 0
        hist, d_med, ids = hist[good], d_med[good], self.ids[keep][good]
        if len(ids) == 0:
            return ObservationPoints.empty(W)
        uvd = np.concatenate([hist[:, -1, :2], d_med[:, None]], axis=1)
        xyz = rig.to_points(uvd)
        # velocity: least-squares slope of the window's 3-D positions (missing disparities take the median)
        d_fill = np.where(np.isfinite(hist[:, :, 2]) & (hist[:, :, 2] > 0), hist[:, :, 2], d_med[:, None])
        all_uvd = np.concatenate([hist[:, :, :2], d_fill[:, :, None]], axis=2)
        pts = rig.to_points(all_uvd.reshape(-1, 3)).reshape(len(ids), W, 3)
        t = np.arange(W, dtype=np.float64) - (W - 1) / 2.0
        velocity = np.einsum("w,nwk->nk", t, pts) / float(t @ t)
        return ObservationPoints(ids, uvd, xyz, velocity, hist[:, :, :2].copy())
