"""Issue 12: a time gap bounds the EKF's work. The golf EKF sub-steps at 1/60 s; a gap longer than
``ekf.max_gap_s`` is a restart (the track goes lost, the EKF forgets the ball) instead of millions
of sub-steps (a 1-day gap took 143 s, a log time near 2**63 ns never finished)."""

import dataclasses
import time

import numpy as np
import pytest

from trackreplay.trackers.golf import GolfConfig, GolfTracker
from trackreplay.trackers.golf.landing import BallisticEkf
from trackreplay.trackers.golf.config import EkfConfig

DAY_NS = 86_400 * 10**9


@pytest.mark.parametrize("gap_ns", [DAY_NS, 2**63 - 10**12], ids=["one_day", "near_2_63"])
def test_time_gap_replays_fast_and_restarts(ptz_sequence, gap_ns):
    _, _, _, frames = ptz_sequence(40)
    gap_at = 20  # frames from here on come gap_ns later (near 2**63: just below the largest log time)
    shifted = [f if f.index < gap_at else dataclasses.replace(f, t_ns=f.t_ns + gap_ns - frames[-1].t_ns) for f in frames]
    tracker = GolfTracker(GolfConfig(), np.random.default_rng(0))
    worst, states = 0.0, []
    for f in shifted:
        t0 = time.perf_counter()
        states.append(tracker.step(f))
        worst = max(worst, time.perf_counter() - t0)
        if f.index == gap_at - 1:
            assert tracker.ekf.initialised  # the filter was running before the gap
    assert worst < 0.5  # well under a second per frame (was minutes, or a hang)
    status = [s[0].status for s in states]
    assert status[gap_at] == "lost"  # the gap is a restart, not a coasted flight


def test_ekf_forgets_on_a_long_gap_and_bounds_its_substeps():
    ekf = BallisticEkf(EkfConfig(), 0.02)
    ekf.kf.x = np.array([0.0, 50.0, 10.0, 5.0, 30.0, 10.0])
    ekf.kf.P = np.eye(6)
    ekf.initialised = True
    t0 = time.perf_counter()
    ekf.predict(1e9)
    assert time.perf_counter() - t0 < 0.05 and not ekf.initialised
    ekf.initialised = True
    ekf.predict(float("inf"))
    assert not ekf.initialised
    ekf.initialised = True
    ekf.predict(EkfConfig().max_gap_s)  # the longest gap integrated: 120 sub-steps
    assert ekf.initialised and np.all(np.isfinite(ekf.kf.x))
