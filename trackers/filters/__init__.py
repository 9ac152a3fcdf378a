"""Estimation filters shared by the trackers: particles, Kalman/EKF (filterpy), gating, Gaussian merging."""
