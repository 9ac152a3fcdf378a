"""Rewrite the golden logs and their expected digests (run only when a change is intended).

    python tests/golden/regenerate.py [--keep-logs] [TRACKER ...]   # all, or only the named ones (others kept as they are)

``--keep-logs``: replay the logs already here instead of writing them again (a tracker change: the
input stays byte for byte what it was, only the expected digest and trajectory move).

Review the digest change in the diff: it says which trackers' outputs moved. Each tracker's
trajectory is kept beside its log (``<tracker>.trajectory.parquet``) so that a digest change
that leaves the trajectory alone can be told from one that moves it.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1]))

from trackreplay.recorder.synth.flow_sims import FlowSimConfig, write_flow_sim  # noqa: E402
from trackreplay.replay.core.engine import ReplayRequest, replay  # noqa: E402

def _golf(path: Path) -> None:
    from trackreplay.recorder.synth.golf.flight import Launch
    from trackreplay.recorder.synth.golf.operator import OperatorConfig
    from trackreplay.recorder.synth.golf.scene import GolfSceneConfig, write_golf_teeshot

    write_golf_teeshot(path, GolfSceneConfig(
        width=640, height=360, seed=3, duration=2.0, jpeg_quality=80,
        launch=Launch(speed=32.0, elevation=24.0, azimuth=0.0, backspin_rpm=7000.0),
        operator=OperatorConfig(size_tee_px=20.0, size_launch_px=7.0, size_landing_px=14.0, size_ground_px=16.0),
    ))


def _colorpf(path: Path) -> None:
    from trackreplay.recorder.synth.colorpf import ColorPfSceneConfig, write_colorpf_scene

    write_colorpf_scene(path, ColorPfSceneConfig(scene="colorpf-approach", width=320, height=240, frames=32,
                                                 jpeg_quality=85))


def _groups(path: Path) -> None:
    from trackreplay.recorder.synth.groups.scene import GroupSceneConfig, write_group_scene

    # 32 stereo pairs, 320x240 (the paper's f on a quarter of its VGA picture), JPEG 75, 24 fps, from
    # 0.6 s into the crossing, with the rig's pose (/stereo/pose: rows in the world frame, Z up). With
    # the per-frame parameters rescaled to 24 fps (time window 3 frames) both groups are tracked:
    # group 1 from frame 11, group 2 (the farther) from frame 18, to the end
    write_group_scene(path, GroupSceneConfig(scene="groups-crossing", fps=24.0, lead_in=8, duration=24 / 24.0,
                                             start_s=0.6, encoding="jpeg", jpeg_quality=75, width=320, height=240))


GOLDEN = {
    # tracker: (log file, how it is made)
    "flow": ("flow-sim1-24f.mcap", lambda p: write_flow_sim(p, FlowSimConfig(scene="flow-sim1", frames=24))),
    "golf": ("golf-teeshot-640x360.mcap", _golf),
    "colorpf": ("colorpf-approach-320x240.mcap", _colorpf),
    "groups": ("groups-crossing-320x240.mcap", _groups),
}


def main() -> None:
    args = sys.argv[1:]
    keep = "--keep-logs" in args
    only = {a for a in args if a != "--keep-logs"} or set(GOLDEN)
    expected = json.loads((HERE / "expected.json").read_text()) if (HERE / "expected.json").exists() else {}
    for tracker, (name, make) in GOLDEN.items():
        if tracker not in only:
            continue
        path = HERE / name
        if not (keep and path.exists()):
            make(path)
        result = replay(ReplayRequest(log=path, tracker=tracker, seed=0))
        expected[tracker] = {"log": name, "seed": 0, "frames": result.frames, "digest": result.digest}
        result.trajectory.write_parquet(HERE / f"{tracker}.trajectory.parquet")
        print(f"{tracker}: {name} {result.digest}")
    (HERE / "expected.json").write_text(json.dumps(expected, indent=2, sort_keys=True) + "\n")


if __name__ == "__main__":
    main()
