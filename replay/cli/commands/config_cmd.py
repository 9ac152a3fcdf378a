"""`trackreplay config TRACKER [--config c.toml]`: a tracker's config as commented TOML."""

from __future__ import annotations

import argparse
from pathlib import Path

from trackreplay.replay.core import registry
from trackreplay.replay.core.config import load_config
from trackreplay.replay.core.config_toml import config_toml


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = sub.add_parser("config", help="print a tracker's default config as commented TOML",
                       description="Print TRACKER's config as TOML with each field's meaning: the defaults, or "
                                   "--config FILE resolved over them. Save it, edit it, pass it to replay --config.")
    p.add_argument("tracker", type=registry.canonical, choices=registry.NAMES)
    p.add_argument("--config", type=Path, help="a TOML file to resolve over the defaults")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    entry = registry.get(args.tracker)
    print(config_toml(load_config(entry.config_cls, args.config, table=args.tracker), args.tracker), end="")
    return 0
