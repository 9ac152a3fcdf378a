"""Synthetic broadcast tee shots (seed 000): ball physics, a camera operator on a PTZ head, rendering,
ground truth and the user's marked ball regions, written as a log.

- ``flight``: launch, drag, Magnus lift, bounce, roll (``simulate_shot`` -> ``Trajectory``).
- ``lens``: a 1x–20x broadcast zoom lens as the log's lens table.
- ``operator``: the operator's pan/tilt/zoom/focus and the encoders that log them.
- ``world``: course layout, distractors, the occluding tree.
- ``render``: frames from the world model under a pose.
- ``truth``: per-frame ground truth and the annotation regions.
- ``scene``: ``GolfSceneConfig`` and ``write_golf_teeshot``.
"""

from trackreplay.recorder.synth.golf.flight import PHASES, BallModel, Flight, Launch, Trajectory, simulate_shot
from trackreplay.recorder.synth.golf.lens import BroadcastLens
from trackreplay.recorder.synth.golf.operator import EncoderModel, OperatorConfig
from trackreplay.recorder.synth.golf.scene import GolfSceneConfig, GolfSceneSummary, GolfShot, plan_shot, write_golf_teeshot

__all__ = [
    "PHASES", "BallModel", "BroadcastLens", "EncoderModel", "Flight", "GolfSceneConfig", "GolfSceneSummary", "GolfShot",
    "Launch", "OperatorConfig", "Trajectory", "plan_shot", "simulate_shot", "write_golf_teeshot",
]
