"""Rewrite the golden logs and their expected digests (run only when a change is intended).

    python tests/golden/regenerate.py

Review the digest change in the diff: it says which trackers' outputs moved.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1]))

from recorder.synth.flow_sims import FlowSimConfig, write_flow_sim  # noqa: E402
from replay.engine import ReplayRequest, replay  # noqa: E402

GOLDEN = {
    # tracker: (log file, how it is made)
    "flow": ("flow-sim1-24f.mcap", lambda p: write_flow_sim(p, FlowSimConfig(scene="flow-sim1", frames=24))),
}


def main() -> None:
    expected = {}
    for tracker, (name, make) in GOLDEN.items():
        path = HERE / name
        make(path)
        result = replay(ReplayRequest(log=path, tracker=tracker, seed=0))
        expected[tracker] = {"log": name, "seed": 0, "frames": result.frames, "digest": result.digest}
        print(f"{tracker}: {name} {result.digest}")
    (HERE / "expected.json").write_text(json.dumps(expected, indent=2, sort_keys=True) + "\n")


if __name__ == "__main__":
    main()
