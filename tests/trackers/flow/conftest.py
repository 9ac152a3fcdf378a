"""Synthetic images for the gradient-flow tests, generated with numpy from seeded generators."""

from __future__ import annotations

import numpy as np
import pytest


def _spectrum(n: int, sigma: float, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    k = np.fft.fftfreq(n)
    lowpass = np.exp(-2.0 * (np.pi * sigma) ** 2 * (k[:, None] ** 2 + k[None, :] ** 2))
    return np.fft.fft2(rng.normal(size=(n, n))) * lowpass


def shifted_texture(n: int, sigma: float, dx: float, dy: float, seed: int = 0) -> np.ndarray:
    """A periodic smooth texture (Gaussian-filtered noise, std 30 around 100) whose content moves
    by exactly ``(dx, dy)`` px (a phase ramp: no interpolation error)."""
    spec = _spectrum(n, sigma, seed)
    k = np.fft.fftfreq(n)
    base = np.real(np.fft.ifft2(spec))
    img = np.real(np.fft.ifft2(spec * np.exp(-2j * np.pi * (k[None, :] * dx + k[:, None] * dy))))
    return ((img - base.mean()) / base.std() * 30.0 + 100.0).astype(np.float32)


def background(n: int = 256, seed: int = 0) -> np.ndarray:
    """A smooth random 8-bit background spanning 20..180 (the target, at 200, stands out)."""
    spec = _spectrum(n, 3.0, seed)
    img = np.real(np.fft.ifft2(spec))
    img = (img - img.min()) / np.ptp(img)
    return np.round(20.0 + 160.0 * img).astype(np.uint8)


def circle_centres(frames: int = 51, radius: float = 20.0, period: float = 50.0, size: int = 256) -> np.ndarray:
    """Integer target centres on a circle about the image centre (flow-sim1 of the paper, §5.1)."""
    angle = 2.0 * np.pi * np.arange(frames) / period
    c = (size - 1) / 2.0
    return np.round(np.stack([c + radius * np.cos(angle), c + radius * np.sin(angle)], axis=1)).astype(np.int64)


def square_frame(back: np.ndarray, centre: np.ndarray, side: int = 13, value: int = 200) -> np.ndarray:
    img = back.copy()
    h = side // 2
    x, y = int(centre[0]), int(centre[1])
    img[y - h : y + h + 1, x - h : x + h + 1] = value
    return img


@pytest.fixture(scope="module")
def texture_factory():
    return shifted_texture


@pytest.fixture(scope="module")
def scene():
    """Helpers for the paper's simulation 1 drawn with numpy."""
    from types import SimpleNamespace

    return SimpleNamespace(background=background, circle_centres=circle_centres, square_frame=square_frame)
