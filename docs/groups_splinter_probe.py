"""What a splinter is: the sets of unassigned points that would start a group, and the confirmed groups
beside them, on chosen frames of a synthetic scene (docs/groups.md, "The stairs splinters").

    python docs/groups_splinter_probe.py groups-stairs 6 65
    python docs/groups_splinter_probe.py groups-stairs 6 65 --config '{"grouping": {"box_overlap": false}}'

The scene is written and replayed as docs/groups_eval.py does (48 fps, 4 s, the scene's SCENE_CONFIG,
then ``--config``). On each frame asked for, every set that would start a group (§3.4, after the
splinter tests) is printed — its size, centroid in world X Y Z (m, Z up), image centre and row span,
velocity — with every group beside it: confirmed or not, world position, extent and EKF position
standard deviations, velocity and image box (x0 y0 x1 y1). A frame with no such set prints nothing.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))

from groups_eval import SCENE_CONFIG, _deep_merge  # noqa: E402

from trackreplay.recorder.synth.groups.scene import GroupSceneConfig, write_group_scene  # noqa: E402
from trackreplay.replay.core.engine import ReplayRequest, replay  # noqa: E402
from trackreplay.trackers.groups.ekf import POS  # noqa: E402
from trackreplay.trackers.groups.tracker import GroupTracker  # noqa: E402


def probe(frames: frozenset[int]) -> None:
    """Wrap the tracker's step (to count frames) and §3.4 start (to print the sets) for this process."""
    step, start = GroupTracker.step, GroupTracker._start_groups

    def counted(self, frame):  # noqa: ANN001, ANN202
        self.probe_frame = getattr(self, "probe_frame", -1) + 1
        return step(self, frame)

    def printed(self, points, labels, rig, events):  # noqa: ANN001, ANN202
        if self.probe_frame in frames:
            held = self.held_out if len(self.held_out) == len(labels) else np.zeros(len(labels), bool)
            R = self.pose.R if self.pose is not None else np.eye(3)
            for idx in self._start_sets(points, np.where(held, -2, labels)):
                uv = points.uvd[idx, :2]
                print(f"frame {self.probe_frame}: set of {len(idx)} points at world {np.round(R @ points.xyz[idx].mean(0), 2)}, "
                      f"image centre {np.round(uv.mean(0), 1)}, rows {uv[:, 1].min():.1f}-{uv[:, 1].max():.1f}, "
                      f"velocity {np.round(R @ points.velocity[idx].mean(0), 3)}")
                for g in self.groups:
                    sd = np.sqrt(np.diag(R @ g.extent @ R.T))
                    psd = np.sqrt(np.diag(R @ g.ekf.P[np.ix_(POS, POS)] @ R.T))
                    print(f"    group {g.gid} ({'confirmed' if g.hits >= self.config.merge.frames else 'young'}): "
                          f"world {np.round(R @ g.position, 2)}, extent sd {np.round(sd, 2)}, position sd {np.round(psd, 2)}, "
                          f"velocity {np.round(R @ g.velocity, 3)}, box {np.round(g.box, 0)}")
        return start(self, points, labels, rig, events)

    GroupTracker.step, GroupTracker._start_groups = counted, printed


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene")
    ap.add_argument("seed", type=int)
    ap.add_argument("frames", type=int, nargs="+")
    ap.add_argument("--config", type=json.loads, default=None)
    args = ap.parse_args()
    probe(frozenset(args.frames))
    with tempfile.TemporaryDirectory() as tmp:
        log = Path(tmp) / f"{args.scene}-{args.seed}.mcap"
        write_group_scene(log, GroupSceneConfig(scene=args.scene, seed=args.seed, fps=48.0, duration=4.0, encoding="jpeg"))
        config = _deep_merge(SCENE_CONFIG.get(args.scene, {}), args.config or {})
        replay(ReplayRequest(log=log, tracker="groups", seed=0, config=config or None))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
