"""Backgrounds for synthetic scenes: a deterministic natural-looking texture, or a bundled photo."""

from __future__ import annotations

import numpy as np

from trackreplay.schemas.errors import SourceError

PHOTOS = ("camera", "moon", "coins", "text", "brick", "grass", "gravel")


def natural_texture(height: int, width: int, seed: int = 0, *, beta: float = 2.0, lo: float = 20, hi: float = 180) -> np.ndarray:
    """Grey ``uint8`` texture with a 1/f^beta power spectrum (the statistics of natural images).

    Values span ``[lo, hi]`` so a target of brightness 200 stands out, as in the paper's simulations.
    """
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(0x7E47,)))
    fy = np.fft.fftfreq(height)[:, None]
    fx = np.fft.rfftfreq(width)[None, :]
    f = np.sqrt(fx * fx + fy * fy)
    f[0, 0] = 1.0
    amplitude = f ** (-beta / 2.0)
    amplitude[0, 0] = 0.0
    phase = rng.uniform(0.0, 2.0 * np.pi, size=amplitude.shape)
    field = np.fft.irfft2(amplitude * np.exp(1j * phase), s=(height, width))
    field = (field - field.min()) / (np.ptp(field) or 1.0)
    return np.round(lo + (hi - lo) * field).astype(np.uint8)


def photo_background(name: str, height: int, width: int) -> np.ndarray:
    """A grey photograph bundled with scikit-image, centre-cropped/resized to the size asked."""
    if name not in PHOTOS:
        raise SourceError(f"unknown background photo {name!r}; choose one of {', '.join(PHOTOS)} or 'texture'")
    try:
        import skimage.data
    except ImportError:
        raise SourceError("background photos need scikit-image (pip install scikit-image)") from None
    import cv2

    image = np.asarray(getattr(skimage.data, name)())
    if image.ndim == 3:
        image = cv2.cvtColor(image[..., :3], cv2.COLOR_RGB2GRAY)
    if image.dtype != np.uint8:
        image = cv2.normalize(image.astype(np.float64), None, 0, 255, cv2.NORM_MINMAX).astype(np.uint8)
    side = min(image.shape[:2])
    y0, x0 = (image.shape[0] - side) // 2, (image.shape[1] - side) // 2
    square = image[y0 : y0 + side, x0 : x0 + side]
    return cv2.resize(square, (width, height), interpolation=cv2.INTER_AREA)
