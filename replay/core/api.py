"""The Python API for notebooks and scripts: one call replays a log (see README "Python API")."""

from __future__ import annotations

from pathlib import Path

from trackreplay.replay.core.config import ConfigSource
from trackreplay.replay.core.engine import ReplayRequest, ReplayResult, replay


def replay_log(log: str | Path, tracker: str, *, config: ConfigSource = None, seed: int = 0,
               rrd: str | Path | None = None, start_s: float | None = None, end_s: float | None = None,
               image_topic: str | None = None) -> ReplayResult:
    """Replay ``tracker`` over ``log`` exactly as ``trackreplay replay`` does.

    ``config`` is None (the tracker's defaults), its config dataclass, a dict nested like the
    config (``{"particles": {"n": 500}}``) or a TOML file (the tracker's table or the top level).
    Returns the trajectory as a Polars DataFrame (``.trajectory``; past 2048 rows the replay keeps it
    in a temporary Parquet file and each access reads it back, ``.scan_trajectory()`` queries it
    lazily in bounded memory: docs/memory.md), the ``.digest`` the CLI
    prints for the same log, config and seed, the frame count and the tracker's ``.notices``;
    with ``rrd`` every intermediate also goes to that Rerun file.
    """
    return replay(ReplayRequest(
        log=Path(log), tracker=tracker, config=config, seed=seed, rrd=None if rrd is None else Path(rrd),
        start_s=start_s, end_s=end_s, image_topic=image_topic,
    ))
