"""Colour particle filter robust to background, illumination and size changes (seed 002)."""
