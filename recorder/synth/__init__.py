"""Synthetic scenes written as logs with ground truth."""
