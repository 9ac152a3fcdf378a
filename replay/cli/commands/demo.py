"""`trackreplay demo`: synthesise flow-sim1, replay the flow tracker, export and evaluate."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from trackreplay.recorder.synth.flow_sims import FlowSimConfig, write_flow_sim
from trackreplay.replay.cli.commands.values import seed_int
from trackreplay.replay.core.engine import ReplayRequest, replay
from trackreplay.replay.analysis.eval import evaluate, format_summary
from trackreplay.replay.core.export import fill_gaps, write_trajectory
from trackreplay.replay.log.groundtruth import read_groundtruth
from trackreplay.replay.log.reader import LogReader


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = sub.add_parser("demo", help="synthesise flow-sim1, track it, write .mcap/.rrd/.parquet, evaluate")
    p.add_argument("--out", type=Path, default=Path("demo-out"), help="output folder (default ./demo-out)")
    p.add_argument("--scene", default="flow-sim1", choices=("flow-sim1", "flow-sim2", "flow-sim3"))
    p.add_argument("--seed", type=seed_int, default=0, help="seed of the scene and the replay (default 0)")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    log = out / f"{args.scene}.mcap"
    write_flow_sim(log, FlowSimConfig(scene=args.scene, seed=args.seed))
    result = replay(ReplayRequest(log=log, tracker="flow", seed=args.seed, rrd=out / f"{args.scene}-flow.rrd"))
    traj = fill_gaps(result.trajectory, "linear")
    write_trajectory(traj, out / "trajectory.parquet")
    summary, _ = evaluate(traj, read_groundtruth(LogReader(log)))
    (out / "summary.json").write_text(json.dumps({**result.summary(log), "eval": summary.as_dict()}, indent=2) + "\n")
    print(f"log        {log}\nrerun      {result.rrd}   (view: rerun {result.rrd})\ntrajectory {out / 'trajectory.parquet'}")
    print(f"digest     {result.digest}  ({result.frames} frames)\n")
    print(format_summary(summary))
    return 0
