"""`trackreplay synth SCENE OUT.mcap`: synthetic scenes with ground truth."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from recorder.synth.flow_sims import SCENES as FLOW_SCENES
from recorder.synth.flow_sims import FlowSimConfig, write_flow_sim
from recorder.synth.texture import PHOTOS


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = sub.add_parser("synth", help="write a synthetic scene with ground truth to MCAP")
    p.add_argument("scene", choices=FLOW_SCENES, help="flow-sim1|2|3: the gradient-flow paper's simulations")
    p.add_argument("out", type=Path, help="output .mcap")
    p.add_argument("--seed", type=int, default=0, help="seed of the procedural background (default 0)")
    p.add_argument("--background", default="texture", choices=("texture", *PHOTOS),
                   help="procedural texture (default) or a photo bundled with scikit-image")
    p.add_argument("--encoding", default="png", choices=("png", "jpeg", "raw"), help="image encoding (default png, lossless)")
    p.add_argument("--frames", type=int, default=51, help="number of frames, t = 0..frames-1 (paper: 51)")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    cfg = FlowSimConfig(scene=args.scene, seed=args.seed, background=args.background, encoding=args.encoding, frames=args.frames)
    n = write_flow_sim(args.out, cfg)
    print(f"wrote {args.out}: {args.scene}, {n} frames with ground truth", file=sys.stderr)
    return 0
