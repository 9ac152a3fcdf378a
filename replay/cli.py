"""The ``trackreplay`` command: one entry point, one module per verb."""

from __future__ import annotations

import argparse
import importlib
import sys

import trackreplay
from trackreplay.schemas.errors import TrackreplayError

# Verb modules in help order; each has add_parser(subparsers) and run(args).
VERBS = ("record", "synth", "info", "recover", "annotate", "replay_cmd", "export", "eval_cmd", "overlay", "bench", "demo")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="trackreplay",
        description="Record camera/PTZ/stereo logs to MCAP, replay trackers deterministically, inspect in Rerun.",
    )
    parser.add_argument("--version", action="version", version=f"trackreplay {trackreplay.__version__}")
    sub = parser.add_subparsers(dest="verb", required=True, metavar="VERB")
    for name in VERBS:
        importlib.import_module(f"trackreplay.replay.commands.{name}").add_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except TrackreplayError as err:
        print(f"trackreplay: error: {err}", file=sys.stderr)
        return err.exit_code
    except KeyboardInterrupt:
        print("trackreplay: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 0


if __name__ == "__main__":
    sys.exit(main())
