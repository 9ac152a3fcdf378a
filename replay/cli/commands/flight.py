"""`trackreplay flight TRAJ LOG`: the golf ball's 3-D flight fitted to its lines of sight."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from trackreplay.replay.cli.commands.values import finite_json


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = sub.add_parser("flight", help="fit the golf ball's 3-D flight, bounce and roll from one PTZ camera")
    p.add_argument("trajectory", type=Path, help="golf trajectory from `replay --export` (.parquet or .csv)")
    p.add_argument("log", type=Path, help="the log it was replayed from (PTZ encoders, lens table, frame times)")
    p.add_argument("--out", type=Path, help="3-D trajectory at frame times (X, Y, Z rows): .parquet or .csv")
    p.add_argument("--report", type=Path, help="per-shot report as JSON (values and 1-sigma uncertainties)")
    p.add_argument("--rrd", type=Path, help="Rerun 3-D view: camera, lines of sight, fitted path")
    p.add_argument("--track", type=int, help="track id (default: the track with most measured frames)")
    p.add_argument("--no-size", action="store_true", help="ignore the apparent ball size (lines of sight only)")
    p.add_argument("--quiet", action="store_true", help="no progress lines (there are none either when stderr is not a terminal)")
    p.add_argument("--rescan", type=Path, metavar="TRAJ_OUT",
                   help="look again, along the fitted flight, in every frame the tracker did not measure (offline); "
                        "write the trajectory with the frames found there (status measured, fill 'rescan') to this "
                        ".parquet or .csv, and fit the flight to them too")
    p.set_defaults(func=run)
    return p


def _is_ball(name: str) -> bool:
    """Whether the tracker's spec says its tracks are a ball in flight (golf): only those trackers' rows are
    used, or every tracker's when the table has none (a table of another tracker, or of several)."""
    from trackreplay.replay.core import registry

    spec = registry.find(name)
    return spec is not None and spec.ball_flight


def _ball_rows(table):
    """The rows of the ball's trackers (:func:`_is_ball`); the whole table when it has none."""
    import polars as pl

    names = [n for n in table["tracker"].unique(maintain_order=True).to_list() if _is_ball(n)]
    balls = table.filter(pl.col("tracker").is_in(names))
    return balls if balls.height else table


def stage_printer(enabled: bool):
    """``say(what)``: one line on stderr per stage of a fit that takes tens of seconds (the stages of
    :func:`~trackreplay.replay.analysis.flight.fit_flight`, the rescan); None (silent) when not ``enabled``."""
    if not enabled:
        return None

    def say(what: str) -> None:
        print(f"trackreplay: flight: {what}", file=sys.stderr, flush=True)

    return say


def run(args: argparse.Namespace) -> int:
    from trackreplay.replay.core.export import read_trajectory, write_trajectory
    from trackreplay.replay.analysis.flight import (FlightConfig, fit_flight, flight_input, flight_rows, observations,
                                                    read_flight_input, write_flight)
    from trackreplay.replay.analysis.smooth import log_context

    from trackreplay.schemas.errors import TrackreplayError

    for flag, path, what in (("--out", args.out, "a flight"), ("--rescan", args.rescan, "a trajectory")):
        if path is not None and path.suffix.lower() not in (".parquet", ".csv"):  # before the fit, not after it
            raise TrackreplayError(f"{flag} {path}: {what} is written as .parquet or .csv")
    # the fit reads only the ball's measured rows with a line of sight, a batch at a time (issue 33); the
    # rescan looks at every row, so it reads the table whole
    table = read_trajectory(args.trajectory, keep_fill=True) if args.rescan is not None else None
    found_input = None if table is not None else read_flight_input(args.trajectory, _is_ball)
    if found_input is None and table is None:  # a defect, or out of canonical order: read whole (names a defect)
        table = read_trajectory(args.trajectory, keep_fill=True)
    given = found_input if found_input is not None else flight_input(table, _is_ball)
    track = args.track
    if track is not None and track not in given.tracks:
        have = ", ".join(str(t) for t in sorted(given.tracks))
        raise TrackreplayError(f"{args.trajectory} has no track {track} (tracks: {have or 'none'})")
    if track is None:
        track = given.most_measured()
    times, cameras = log_context(args.log)
    obs = observations(given.rows, cameras, track_id=track, what=f"{args.trajectory} (log {args.log})")
    fps = (len(times) - 1) / ((max(times.values()) - min(times.values())) * 1e-9) if len(times) > 1 else 30.0
    config = FlightConfig(use_size=not args.no_size)
    say = stage_printer(not args.quiet and sys.stderr.isatty())
    rescanned: frozenset[int] = frozenset()
    if args.rescan is not None:
        from trackreplay.replay.analysis.flight_rescan import rescan

        if say is not None:
            say("rescanning along the fitted flight (several fits)")
        found = rescan(table, args.log, times, cameras, track_id=track, flight=config, fps=fps,
                       what=f"{args.trajectory} (log {args.log})", tracker=str(_ball_rows(table)["tracker"][0]))
        for warning in found.warnings:
            print(f"trackreplay: rescan: {warning}", file=sys.stderr)
        fit, rescanned = found.fit, frozenset(s.frame for s in found.sightings)
        write_trajectory(found.trajectory, args.rescan)
        print(f"rescan: {len(found.sightings)} frames found along the fitted flight "
              f"(per round: {', '.join(str(n) for n in found.rounds)}"
              + (f"; {len(found.dropped)} dropped, off the final fit: {', '.join(str(f) for f in found.dropped)}" if found.dropped else "")
              + f"); wrote {args.rescan}")
    else:
        fit = fit_flight(obs, config, fps, None if say is None else lambda stage: say(f"fitting: {stage}"))
    print(fit.report.describe())
    # the fitted flight at every frame of the log is written a part at a time (Rerun's view takes it whole)
    rows = flight_rows(fit, times, cameras, track_id=track or 1) if args.rrd else None
    if args.out:
        written = write_flight(fit, times, cameras, args.out, track_id=track or 1)
        print(f"wrote {args.out}: {written} rows")
    if args.report:
        args.report.parent.mkdir(parents=True, exist_ok=True)
        from trackreplay.replay.core.outputs import write_bytes  # NAME.partial, renamed when complete

        write_bytes(args.report, (json.dumps(finite_json(fit.report.as_dict()), indent=2, allow_nan=False) + "\n").encode())
    if args.rrd:
        from trackreplay.replay.views.flight import write_flight_rrd

        write_flight_rrd(args.rrd, fit, rows, name=Path(args.log).stem, rescanned=rescanned)
        print(f"wrote {args.rrd}")
    return 0
