"""Tracking algorithms. Pure: no files, no clock, no global randomness."""
