"""Memory and time of a replay, and of `eval`, against the length of the log (issue 33, "Scale").

A tiny synthetic flow scene (a 5x5 square circling on a 32x32 textured background, ground truth
every frame, the target marked on frame 0), written with the recorder's LogWriter at 1k, 20k and
200k frames. Each measurement runs in a fresh process and reports its peak RSS (ru_maxrss):

- ``replay_summary``: `trackreplay replay LOG --tracker flow --summary S.json` (trajectory, digest and
  per-frame digests go to temporary Parquet row groups past a bound; the sidecar is copied row group by
  row group)
- ``replay_export``: the same with `--export T.parquet` (a spilled trajectory is gap-filled and written a
  piece at a time: core/export.py ``export_trajectory``)
- ``replay_export_whole``: before that (the reference, through the API): the replay, then the whole table
  read back, gap-filled (``fill_gaps``) and written
- ``eval``: `trackreplay eval T.parquet LOG --json M.json`

Goal: from 1k to 200k frames the peak RSS grows by at most 50 MB; eval linear in time.

``--export-only``: the export step alone, without replaying (minutes instead of hours on a loaded
machine): the replay's spill file of this scene's flow track (one row a frame, ~3 % lost, as the tracker
reports it) is made directly, then each fresh process loads what a replay has loaded (the engine, pyarrow,
OpenCV) and exports it, a piece at a time (``export_trajectory``, ``--interpolate linear``) or the whole table
(``fill_gaps``, as before); both outputs compared.

``--export-only`` also runs `trackreplay export SPILL.parquet OUT.parquet` (``cli_export``: the file as a user's
trajectory, checked and exported a piece at a time; its peak RSS is the whole process's) and compares its rows.

``--eval-only``: `eval` alone, on the scene's log and that flow track as T.parquet: the chunked single-object
path (replay/analysis/eval.py ``evaluate_chunked``) against the whole table (``--per-frame`` takes it); the
two --json files compared. ``--objects 3``: the truth holds three objects (the square and two still boxes), so
eval first finds the object the track lies on most often (``object_followed_parts``, a chunk at a time);
writes long_log_eval_objects.json.

``--csv-only``: ``read_trajectory`` of that flow track written as CSV (what `export`, `smooth`, `flight` and `eval`
do with a CSV input), in a fresh process: read, cast and checked in pieces (``export._csv_in_pieces``) against the
whole file read as text; peak RSS (VmHWM) above the process's base; the two tables compared.

``--csv-export-only``: `trackreplay export T.csv OUT.parquet` on that flow track written as CSV, in a fresh process:
cast and checked a piece at a time into a temporary Parquet file and exported from it a piece at a time
(``export.csv_as_parquet``) against the whole table (``csv_as_parquet`` made to decline: the CSV read, filled and
written whole); peak RSS (VmHWM) above the process with its modules loaded; the two outputs compared.

``--sidecar-only``: `diff`'s reading of a summary's per-frame digest sidecar (replay/analysis/diff.py
``read_sidecar``) and a pass over every frame's fields and kept values, as ``diff_recordings`` asks for them: a
block of frames at a time (``FrameDigests.from_file``) against the whole table (``FrameDigests.from_table``), in a
fresh process; a sidecar of the scene's shape (a track's state and a few filter fields a frame, one large field
without values) written by ``FrameDigests`` spilling as a replay does; the two passes' hashes compared.

``--smooth-only``: `trackreplay smooth T.parquet LOG --out S.parquet` on ONE track of each smoothing model (flow,
colorpf: image; groups: 3-D) of that many rows (``bench_smooth.synthetic_trajectory``: gaps, absent frames, outliers;
written by polars as bench_smooth writes it), LOG a log of tiny PNG frames at its frame times, in a fresh process: the
command as it is (an image track longer than ``smooth_long.LONG_ROWS`` smoothed in two passes, its RTS pass in pieces
with the filtered states in a temporary file, its rows written a piece at a time) against the whole table
(``smooth_in_pieces`` made to decline); peak RSS (VmHWM) above the process with its modules loaded, CPU seconds,
rows per CPU-second; the two outputs and printed fits compared.

``--flight-only``: `trackreplay flight T.parquet LOG --out F.parquet` on the golden tee shot (tests/golden: its log and
trajectory) continued to that many frames (``write_golf_log``: a 32x32 PNG and the last PTZ reading a frame;
``golf_trajectory``: the ball's track predicted, with a line of sight, on every later frame, one row a frame). The fit
uses the shot's 17 measured rows whatever the length (a fit on 200k measured rows is not what a golf log holds, and
would be minutes of least squares): what grows is reading the trajectory, the log's frame times and cameras, and the
fitted flight written at every frame. As it is (the ball's measured rows kept, read a batch at a time; the output
built and written a part at a time) against the whole table (``read_flight_input`` made to decline, the output built
whole), in a fresh process: peak RSS (VmHWM) above the process with its modules loaded; the two outputs and printed
reports compared.

``--mot-only``: `trackreplay eval T.parquet LOG --mot` on the scene's log with ``--objects`` (default 3) truth objects
(the square and still boxes) and a track on each (``write_tracks``): the truth and the trajectory a chunk of frames at a
time (replay/analysis/mot.py ``ChunkedTables``) against the whole tables (``--per-frame`` takes that path); the two
--json files compared; peak RSS of the whole process.

Usage: python benchmarks/bench_long_log.py [--frames 1000,20000,200000] [--export-only | --eval-only | --csv-only |
       --csv-export-only | --sidecar-only | --smooth-only | --flight-only | --mot-only]
Writes benchmarks/results/long_log.json (``--export-only``: long_log_export.json, ``--eval-only``:
long_log_eval.json, ``--csv-only``: long_log_csv.json, ``--csv-export-only``: long_log_csv_export.json,
``--sidecar-only``: long_log_sidecar.json, ``--smooth-only``: long_log_smooth.json, ``--flight-only``:
long_log_flight.json, ``--mot-only``: long_log_mot.json) and prints a table.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks.machine import describe  # noqa: E402
from trackreplay.recorder.image_codec import compressed_image  # noqa: E402
from trackreplay.recorder.writer import LogWriter  # noqa: E402
from trackreplay.schemas import topics as T  # noqa: E402
from trackreplay.schemas.records import GroundTruthFrame, GroundTruthObject, InitRegion, init_annotations_pb  # noqa: E402

SIZE, PERIOD, SQUARE = 32, 50, 5

CLI = """
import resource, sys, time
sys.path.insert(0, {root!r})
from trackreplay.replay.cli.main import main
started = time.perf_counter()
code = main({argv!r})
print(code, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, time.perf_counter() - started)
"""


WHOLE = """
import resource, sys, time
sys.path.insert(0, {root!r})
from trackreplay.replay.core.engine import ReplayRequest, replay
from trackreplay.replay.core.export import fill_gaps, write_trajectory
started = time.perf_counter()
result = replay(ReplayRequest(log={log!r}, tracker="flow"))
write_trajectory(fill_gaps(result.trajectory, "linear", 15), {out!r})
print(0, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, time.perf_counter() - started)
"""


def write_long_log(path: Path, frames: int, objects: int = 1) -> None:
    """The scene: PERIOD pre-encoded PNG pictures cycled (the square's circle repeats every PERIOD frames);
    ``objects`` > 1: the square and ``objects`` - 1 still truth boxes near the corners (not drawn)."""
    background = cv2.GaussianBlur(np.random.default_rng(0).integers(40, 120, (SIZE, SIZE), dtype=np.uint8), (3, 3), 0)
    t = np.arange(PERIOD)
    c = (SIZE - 1) / 2
    centres = np.round(np.stack([c + 6 * np.cos(2 * np.pi * t / PERIOD), c + 6 * np.sin(2 * np.pi * t / PERIOD)], 1)).astype(int)
    pictures = []
    for x, y in centres:
        image = background.copy()
        image[y - SQUARE // 2:y + SQUARE // 2 + 1, x - SQUARE // 2:x + SQUARE // 2 + 1] = 200
        pictures.append(cv2.imencode(".png", image)[1].tobytes())
    with LogWriter(path, flush_every=300) as log:
        for i in range(frames):
            t_ns = i * 1_000_000_000 // 30
            x, y = (float(v) for v in centres[i % PERIOD])
            if i == 0:
                mark = InitRegion(0, t_ns, x, y, float(SQUARE), float(SQUARE), "target")
                log.write(T.ANNOTATIONS_INIT, init_annotations_pb([mark], t_ns), t_ns)
            log.write(T.CAMERA_IMAGE, compressed_image(pictures[i % PERIOD], "png", t_ns, "camera"), t_ns)
            truth = GroundTruthObject(id=1, x=x, y=y, w=float(SQUARE), h=float(SQUARE), vx=None, vy=None, visible=True)
            still = tuple(GroundTruthObject(id=k + 1, x=3.0 + 26.0 * (k % 2), y=3.0 + 26.0 * (k // 2 % 2), w=4.0, h=4.0,
                                            vx=None, vy=None, visible=True) for k in range(1, objects))
            log.write(T.GROUNDTRUTH, GroundTruthFrame(i, t_ns, (truth, *still)).to_pb(), t_ns)


def measure(code: str) -> tuple[str, int, float]:
    """(first printed word, peak RSS KiB, seconds) of a fresh process running ``code``."""
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True).stdout.split()
    return out[-3], int(out[-2]), float(out[-1])


def run_size(tmp: Path, frames: int) -> dict[str, object]:
    log = tmp / f"long-{frames}.mcap"
    started = time.perf_counter()
    write_long_log(log, frames)
    written = time.perf_counter() - started
    traj, summary, metrics = tmp / f"t-{frames}.parquet", tmp / f"s-{frames}.json", tmp / f"m-{frames}.json"
    root = str(ROOT)
    replay = ["replay", str(log), "--tracker", "flow", "--quiet", "--summary", str(summary)]
    code, rss_replay, s_replay = measure(CLI.format(root=root, argv=replay))
    digest = json.loads(summary.read_text())["digest"]
    code_export, rss_export, s_export = measure(CLI.format(root=root, argv=[*replay, "--export", str(traj)]))
    whole = tmp / f"w-{frames}.parquet"
    code_whole, rss_whole, s_whole = measure(WHOLE.format(root=root, log=str(log), out=str(whole)))
    import polars as pl

    same_rows = pl.read_parquet(whole).equals(pl.read_parquet(traj), null_equal=True)
    code_eval, rss_eval, s_eval = measure(CLI.format(root=root, argv=["eval", str(traj), str(log), "--json", str(metrics)]))
    return {
        "frames": frames, "log_bytes": log.stat().st_size, "write_s": round(written, 2),
        "replay_summary": {"exit": int(code), "peak_rss_kib": rss_replay, "seconds": round(s_replay, 2), "digest": digest,
                           "us_per_frame": round(1e6 * s_replay / frames, 1)},
        "replay_export": {"exit": int(code_export), "peak_rss_kib": rss_export, "seconds": round(s_export, 2),
                          "same_digest": json.loads(summary.read_text())["digest"] == digest},
        "replay_export_whole": {"exit": int(code_whole), "peak_rss_kib": rss_whole, "seconds": round(s_whole, 2),
                                "same_rows_as_replay_export": same_rows},
        "eval": {"exit": int(code_eval), "peak_rss_kib": rss_eval, "seconds": round(s_eval, 2),
                 "us_per_frame": round(1e6 * s_eval / frames, 1)},
    }


EXPORT = """
import resource, sys, time
sys.path.insert(0, {root!r})
import cv2, pyarrow.parquet, trackreplay.replay.core.engine
from trackreplay.replay.core.export import export_trajectory, fill_gaps, write_trajectory
from trackreplay.replay.core.trajectory import SpilledTrajectory
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
started = time.perf_counter()
if {whole!r}:
    write_trajectory(fill_gaps(SpilledTrajectory({spill!r}).frame(), "linear", 15), {out!r})
else:
    export_trajectory(SpilledTrajectory({spill!r}), {out!r}, "linear", 15)
print(before, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, time.perf_counter() - started)
"""


def write_spill(path: Path, frames: int) -> None:
    """A flow replay's spill file of this scene: row groups of 2048 rows in replay order."""
    import polars as pl

    from trackreplay.replay.core.trajectory import SCHEMA

    rng = np.random.default_rng(0)
    t = np.arange(frames)
    c = (SIZE - 1) / 2
    lost = rng.random(frames) < 0.03
    x = np.where(lost, np.nan, c + 6 * np.cos(2 * np.pi * t / PERIOD) + rng.normal(0, 0.2, frames))
    y = np.where(lost, np.nan, c + 6 * np.sin(2 * np.pi * t / PERIOD) + rng.normal(0, 0.2, frames))
    nan = np.full(frames, np.nan)
    df = pl.DataFrame({"tracker": "flow", "track_id": 1, "frame": t, "t_ns": t * 1_000_000_000 // 30, "x": x, "y": y,
                       "w": np.where(lost, np.nan, 5.0), "h": np.where(lost, np.nan, 5.0), "vx": np.where(lost, np.nan, 0.1),
                       "vy": np.where(lost, np.nan, 0.1), "X": nan, "Y": nan, "Z": nan, "dx": nan, "dy": nan, "dz": nan,
                       "status": np.where(lost, "lost", "measured"), "confidence": np.where(lost, np.nan, 0.9)})
    df = df.cast(SCHEMA).with_columns(pl.col(c).fill_nan(None) for c, k in SCHEMA.items() if k == pl.Float64)
    df.write_parquet(path, row_group_size=2048)


def export_only(sizes: list[int], out: Path) -> int:
    import polars as pl

    runs = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in sizes:
            spill = Path(tmp) / f"spill-{n}.parquet"
            write_spill(spill, n)
            entry: dict = {"frames": n}
            for name, whole in (("pieces", False), ("whole_table", True)):
                target = Path(tmp) / f"{name}-{n}.parquet"
                code = EXPORT.format(root=str(ROOT), whole=whole, spill=str(spill), out=str(target))
                res = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True).stdout.split()
                entry[name] = {"base_rss_kib": int(res[-3]), "peak_rss_kib": int(res[-2]),
                               "export_mb": round((int(res[-2]) - int(res[-3])) / 1024, 1), "seconds": round(float(res[-1]), 2)}
            # `trackreplay export TRAJ OUT` on the same file as a user's trajectory (checked and exported in pieces)
            cli_out = Path(tmp) / f"cli-{n}.parquet"
            code, rss, seconds = measure(CLI.format(root=str(ROOT), argv=["export", str(spill), str(cli_out)]))
            entry["cli_export"] = {"exit": int(code), "peak_rss_kib": rss, "seconds": round(seconds, 2)}
            whole = pl.read_parquet(Path(tmp) / f"whole_table-{n}.parquet")
            entry["same_rows"] = pl.read_parquet(Path(tmp) / f"pieces-{n}.parquet").equals(whole, null_equal=True)
            entry["cli_same_rows"] = pl.read_parquet(cli_out).equals(whole, null_equal=True)
            runs.append(entry)
            print(json.dumps(entry), flush=True)
    growth = {k: round((runs[-1][k]["peak_rss_kib"] - runs[0][k]["peak_rss_kib"]) / 1024, 1)
              for k in ("pieces", "whole_table", "cli_export")}
    results = {"machine": describe(), "load_average": [round(x, 2) for x in __import__("os").getloadavg()],
               "scene": "the flow track of the long-log scene, one row a frame, 3 % lost",
               "runs": runs, "peak_rss_growth_mb": {"from_frames": sizes[0], "to_frames": sizes[-1], **growth, "target": "<= 50"}}
    out.write_text(json.dumps(results, indent=2) + "\n")
    print(f"export peak RSS growth {sizes[0]} -> {sizes[-1]} frames (MB): {growth} (target <= 50)")
    return 0


def eval_against_whole(traj: Path, log: Path, tmp: Path, n: int, options: list[str]) -> dict:
    """``trackreplay eval TRAJ LOG [options]`` in a fresh process, chunked and on the whole table (``--per-frame``
    takes the whole-table path): each one's exit, peak RSS and seconds, and whether the two ``--json`` agree."""
    entry: dict = {}
    for name, extra in (("chunked", []), ("whole_table", ["--per-frame", str(tmp / f"pf-{n}.parquet")])):
        argv = ["eval", str(traj), str(log), *options, "--json", str(tmp / f"{name}-{n}.json"), *extra]
        code, rss, seconds = measure(CLI.format(root=str(ROOT), argv=argv))
        entry[name] = {"exit": int(code), "peak_rss_kib": rss, "seconds": round(seconds, 2)}
    entry["same_json"] = (tmp / f"chunked-{n}.json").read_text() == (tmp / f"whole_table-{n}.json").read_text()
    return entry


def eval_only(sizes: list[int], out: Path, objects: int = 1) -> int:
    """`eval` alone: the scene's log and its flow track (``write_spill``) as T.parquet, scored in a fresh
    process by the chunked single-object path and by the whole table (``--per-frame`` takes it); the
    same --json asked of both. ``objects`` > 1: the truth holds that many objects (no --gt-id: the one the
    track lies on most often is found, a chunk at a time on the chunked path)."""
    runs = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in sizes:
            log, traj = Path(tmp) / f"long-{n}.mcap", Path(tmp) / f"t-{n}.parquet"
            write_long_log(log, n, objects)
            write_spill(traj, n)
            entry = {"frames": n, "truth_objects": objects, **eval_against_whole(traj, log, Path(tmp), n, [])}
            runs.append(entry)
            print(json.dumps(entry), flush=True)
    growth = {k: round((runs[-1][k]["peak_rss_kib"] - runs[0][k]["peak_rss_kib"]) / 1024, 1) for k in ("chunked", "whole_table")}
    results = {"machine": describe(), "load_average": [round(x, 2) for x in __import__("os").getloadavg()],
               "scene": f"the long-log scene's log ({objects} truth object(s)) and its flow track (one row a frame, 3 % lost)",
               "runs": runs,
               "peak_rss_growth_mb": {"from_frames": sizes[0], "to_frames": sizes[-1], **growth, "target": "<= 50"}}
    out.write_text(json.dumps(results, indent=2) + "\n")
    print(f"eval peak RSS growth {sizes[0]} -> {sizes[-1]} frames (MB): {growth} (target <= 50)")
    return 0


CSV_READ = """
import sys, time
sys.path.insert(0, {root!r})
import cv2, pyarrow.parquet, trackreplay.replay.core.engine
from trackreplay.replay.core import export
if {whole!r}:
    export._csv_in_pieces = lambda *args: None
def hwm():
    with open("/proc/self/status") as fh:
        return next(int(line.split()[1]) for line in fh if line.startswith("VmHWM:"))
before = hwm()
started = time.perf_counter()
df = export.read_trajectory({csv!r})
print(before, hwm(), time.perf_counter() - started)
df.write_parquet({out!r})
"""


def csv_only(sizes: list[int], out: Path) -> int:
    """``read_trajectory`` of the scene's flow track as CSV: in pieces against the whole file as text."""
    import polars as pl

    runs = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in sizes:
            spill, csv = Path(tmp) / f"spill-{n}.parquet", Path(tmp) / f"t-{n}.csv"
            write_spill(spill, n)
            pl.read_parquet(spill).write_csv(csv)
            entry: dict = {"frames": n, "csv_bytes": csv.stat().st_size}
            for name, whole in (("pieces", False), ("whole_file", True)):
                target = Path(tmp) / f"{name}-{n}.parquet"
                code = CSV_READ.format(root=str(ROOT), whole=whole, csv=str(csv), out=str(target))
                res = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True).stdout.split()
                entry[name] = {"base_rss_kib": int(res[-3]), "peak_rss_kib": int(res[-2]),
                               "read_mb": round((int(res[-2]) - int(res[-3])) / 1024, 1), "seconds": round(float(res[-1]), 2)}
            entry["same_table"] = pl.read_parquet(Path(tmp) / f"pieces-{n}.parquet").equals(
                pl.read_parquet(Path(tmp) / f"whole_file-{n}.parquet"), null_equal=True)
            runs.append(entry)
            print(json.dumps(entry), flush=True)
    growth = {k: round((runs[-1][k]["peak_rss_kib"] - runs[0][k]["peak_rss_kib"]) / 1024, 1) for k in ("pieces", "whole_file")}
    results = {"machine": describe(), "load_average": [round(x, 2) for x in __import__("os").getloadavg()],
               "scene": "the flow track of the long-log scene as CSV, one row a frame, 3 % lost", "runs": runs,
               "peak_rss_growth_mb": {"from_frames": sizes[0], "to_frames": sizes[-1], **growth, "target": "<= 50"}}
    out.write_text(json.dumps(results, indent=2) + "\n")
    print(f"CSV read peak RSS growth {sizes[0]} -> {sizes[-1]} frames (MB): {growth} (target <= 50)")
    return 0 if all(r["same_table"] for r in runs) else 1


CSV_EXPORT = """
import contextlib, io, sys, time
sys.path.insert(0, {root!r})
import cv2, pyarrow.parquet, trackreplay.replay.core.engine
from trackreplay.replay.analysis import eval as evaluation
from trackreplay.replay.cli.main import main
from trackreplay.replay.core import export
if {whole!r}:
    export.csv_as_parquet = lambda *args: False
def hwm():
    with open("/proc/self/status") as fh:
        return next(int(line.split()[1]) for line in fh if line.startswith("VmHWM:"))
before = hwm()
started = time.perf_counter()
with contextlib.redirect_stdout(io.StringIO()):
    code = main(["export", {csv!r}, {out!r}])
print(code, before, hwm(), time.perf_counter() - started)
"""


def csv_export_only(sizes: list[int], out: Path) -> int:
    """`trackreplay export T.csv OUT.parquet`: in pieces (through a temporary Parquet file) against the whole table."""
    import polars as pl

    runs = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in sizes:
            spill, csv = Path(tmp) / f"spill-{n}.parquet", Path(tmp) / f"t-{n}.csv"
            write_spill(spill, n)
            pl.read_parquet(spill).write_csv(csv)
            entry: dict = {"frames": n, "csv_bytes": csv.stat().st_size}
            for name, whole in (("pieces", False), ("whole_table", True)):
                target = Path(tmp) / f"{name}-{n}.parquet"
                code = CSV_EXPORT.format(root=str(ROOT), whole=whole, csv=str(csv), out=str(target))
                res = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True).stdout.split()
                entry[name] = {"exit": int(res[-4]), "base_rss_kib": int(res[-3]), "peak_rss_kib": int(res[-2]),
                               "export_mb": round((int(res[-2]) - int(res[-3])) / 1024, 1), "seconds": round(float(res[-1]), 2)}
            entry["same_rows"] = pl.read_parquet(Path(tmp) / f"pieces-{n}.parquet").equals(
                pl.read_parquet(Path(tmp) / f"whole_table-{n}.parquet"), null_equal=True)
            runs.append(entry)
            print(json.dumps(entry), flush=True)
    growth = {k: round((runs[-1][k]["peak_rss_kib"] - runs[0][k]["peak_rss_kib"]) / 1024, 1) for k in ("pieces", "whole_table")}
    results = {"machine": describe(), "load_average": [round(x, 2) for x in __import__("os").getloadavg()],
               "scene": "the flow track of the long-log scene as CSV, one row a frame, 3 % lost; --interpolate linear",
               "runs": runs, "peak_rss_growth_mb": {"from_frames": sizes[0], "to_frames": sizes[-1], **growth, "target": "<= 50"}}
    out.write_text(json.dumps(results, indent=2) + "\n")
    print(f"CSV export peak RSS growth {sizes[0]} -> {sizes[-1]} frames (MB): {growth} (target <= 50)")
    return 0 if all(r["same_rows"] for r in runs) else 1


SIDECAR = """
import hashlib, sys, time
sys.path.insert(0, {root!r})
import polars as pl, pyarrow.parquet
from trackreplay.replay.analysis.diff import read_sidecar
from trackreplay.replay.core.digest import FrameDigests
def hwm():
    with open("/proc/self/status") as fh:
        return next(int(line.split()[1]) for line in fh if line.startswith("VmHWM:"))
before = hwm()
started = time.perf_counter()
frames = FrameDigests.from_table(pl.read_parquet({path!r})) if {whole!r} else read_sidecar(__import__("pathlib").Path({path!r}))
h = hashlib.sha256()
for i in range(len(frames)):
    h.update(repr(sorted(frames.fields(i).items())).encode())
    h.update(b"".join(v.tobytes() for _, v in sorted(frames.values(i).items())))
print(h.hexdigest(), before, hwm(), time.perf_counter() - started)
"""


def write_sidecar(path: Path, frames: int) -> None:
    """A sidecar of ``frames`` frames as a flow replay's spill writes it (row groups of 512 frames)."""
    from trackreplay.replay.core.digest import FrameDigests

    rng = np.random.default_rng(0)
    digests = FrameDigests(spill_frames=512)
    for i in range(frames):
        x, y = rng.normal(size=2)
        digests.add(i, [("states.len", bytes(8), [1.0]), ("states.0.x", rng.bytes(8), [x]), ("states.0.y", rng.bytes(8), [y]),
                        ("states.0.status", rng.bytes(8), None), ("intermediates.flow.velocity", rng.bytes(8), [x, y]),
                        ("intermediates.flow.covariance", rng.bytes(8), list(rng.normal(size=9))),
                        ("intermediates.flow.mask", rng.bytes(8), None)])
    with open(path, "wb") as out:
        digests.write_table(out)


def sidecar_only(sizes: list[int], out: Path) -> int:
    runs = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in sizes:
            side = Path(tmp) / f"s-{n}.frames.parquet"
            write_sidecar(side, n)
            entry: dict = {"frames": n, "sidecar_bytes": side.stat().st_size}
            digests = {}
            for name, whole in (("blocks", False), ("whole_table", True)):
                code = SIDECAR.format(root=str(ROOT), path=str(side), whole=whole)
                res = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True).stdout.split()
                digests[name] = res[-4]
                entry[name] = {"base_rss_kib": int(res[-3]), "peak_rss_kib": int(res[-2]),
                               "read_mb": round((int(res[-2]) - int(res[-3])) / 1024, 1), "seconds": round(float(res[-1]), 2)}
            entry["same_fields_and_values"] = digests["blocks"] == digests["whole_table"]
            runs.append(entry)
            print(json.dumps(entry), flush=True)
    growth = {k: round((runs[-1][k]["peak_rss_kib"] - runs[0][k]["peak_rss_kib"]) / 1024, 1) for k in ("blocks", "whole_table")}
    results = {"machine": describe(), "load_average": [round(x, 2) for x in __import__("os").getloadavg()],
               "sidecar": "7 fields a frame (4 with kept values: 1, 1, 1, 2 and 9 numbers), row groups of 512 frames",
               "runs": runs, "peak_rss_growth_mb": {"from_frames": sizes[0], "to_frames": sizes[-1], **growth, "target": "<= 50"}}
    out.write_text(json.dumps(results, indent=2) + "\n")
    print(f"sidecar read peak RSS growth {sizes[0]} -> {sizes[-1]} frames (MB): {growth} (target <= 50)")
    return 0 if all(r["same_fields_and_values"] for r in runs) else 1


def write_results(out: Path, load_before: list[float], scene: str, runs, growth_key: str, growth: dict) -> None:
    """A benchmark's JSON: the machine, the load before and after, the scene, the runs and the growth against
    the issue's target (<= 50 MB)."""
    import os

    results = {"machine": describe(), "load_average_before": load_before,
               "load_average_after": [round(x, 2) for x in os.getloadavg()], "scene": scene, "runs": runs,
               growth_key: {**growth, "target": "<= 50"}}
    out.write_text(json.dumps(results, indent=2) + "\n")


def smooth_only(sizes: list[int], out: Path, models: tuple[str, ...] = ("flow", "colorpf", "groups")) -> int:
    """`trackreplay smooth` of one long track of each model: as it is against the whole table (fresh processes)."""
    import os

    from benchmarks import bench_smooth

    load_before = [round(x, 2) for x in os.getloadavg()]
    runs: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        for n in sizes:
            log = Path(tmp) / f"log-{n}.mcap"
            bench_smooth.write_frames_log(log, n + 60)  # the track starts within the log's first 50 frames
            for tracker in models:
                table = Path(tmp) / f"{tracker}-{n}.parquet"
                bench_smooth.synthetic_trajectory(n, tracker, tracks=1, seed=2).write_parquet(table)
                entry = bench_smooth.pieces_against_whole(table, log, Path(tmp))
                runs[f"{tracker}/{n}"] = entry
                print(tracker, n, json.dumps(entry), flush=True)
    growth = {t: {k: round(runs[f"{t}/{sizes[-1]}"][k]["command_mb"] - runs[f"{t}/{sizes[0]}"][k]["command_mb"], 1)
                  for k in ("pieces", "whole_table")} for t in models}
    write_results(out, load_before, "one track of each model (benchmarks/bench_smooth.py synthetic_trajectory, seed 2), "
                  "written by polars; a log of 8x8 PNG frames at its frame times", runs,
                  "command_mb_growth", {"from_rows": sizes[0], "to_rows": sizes[-1], **growth})
    for t in models:
        hi = runs[f"{t}/{sizes[-1]}"]
        print(f"{t}: peak above the process {sizes[0]} -> {sizes[-1]} rows +{growth[t]['pieces']} MB "
              f"(whole table +{growth[t]['whole_table']}); {hi['pieces']['rows_per_cpu_s']} rows per CPU-second at "
              f"{sizes[-1]} rows (whole table {hi['whole_table']['rows_per_cpu_s']})")
    return 0 if all(r["identical"] and r["same_printed_fits"] and r["pieces"]["exit"] == 0 for r in runs.values()) else 1


FLIGHT = """
import contextlib, sys, time
sys.path.insert(0, {root!r})
import pyarrow.parquet, scipy.optimize
from trackreplay.replay.analysis import flight, smooth
from trackreplay.replay.cli.main import main
from trackreplay.replay.log.reader import LogReader
from trackreplay.replay.cli.commands import flight as command
if {whole!r}:  # the whole table read, and the whole output built, as before
    flight.read_flight_input = lambda *a, **k: None
    flight.ROWS_CHUNK = 1 << 40
def hwm():
    with open("/proc/self/status") as fh:
        return next(int(line.split()[1]) for line in fh if line.startswith("VmHWM:"))
base = hwm()
c0, w0 = time.process_time(), time.perf_counter()
with open({printed!r}, "w") as fh, contextlib.redirect_stdout(fh):
    code = main({argv!r})
print(code, base, hwm(), time.process_time() - c0, time.perf_counter() - w0)
"""


def write_golf_log(path: Path, frames: int) -> None:
    """The golden tee shot's log (its lens table, PTZ readings and 60 pictures) continued to ``frames`` frames:
    a 32x32 PNG every 1/30 s and the last PTZ reading repeated at each (the camera holds still after the shot)."""
    import dataclasses

    from trackreplay.replay.log.reader import LogReader
    from trackreplay.schemas.records import PtzReading

    golden = LogReader(ROOT / "tests" / "golden" / "golf-teeshot-640x360.mcap")
    picture = cv2.imencode(".png", np.full((32, 32), 90, np.uint8))[1].tobytes()
    last_ptz, last_t = None, 0
    with LogWriter(path, flush_every=300) as log:
        for item in golden.messages([T.PTZ_LENS_TABLE, T.PTZ_ENCODERS, T.CAMERA_IMAGE]):
            log.write(item.topic, item.decode(), item.log_time)
            last_t = max(last_t, item.log_time)
            if item.topic == T.PTZ_ENCODERS:
                last_ptz = PtzReading.from_pb(item.decode())
        images = golden.topics()[T.CAMERA_IMAGE].count
        for i in range(images, frames):
            t_ns = last_t + (i - images + 1) * 1_000_000_000 // 30
            log.write(T.PTZ_ENCODERS, dataclasses.replace(last_ptz, t_ns=t_ns).to_pb(), t_ns)
            log.write(T.CAMERA_IMAGE, compressed_image(picture, "png", t_ns, "camera"), t_ns)


def golf_trajectory(path: Path, log: Path, frames: int) -> None:
    """The golden tee shot's trajectory (60 frames, 17 measured with a line of sight) continued with the
    ball's track predicted (a position and a line of sight, no measurement) on every later frame of the log:
    one row a frame; the fit uses the shot's measured rows only."""
    import polars as pl

    from trackreplay.replay.analysis.smooth import log_context
    from trackreplay.replay.core.export import read_trajectory
    from trackreplay.replay.core.trajectory import SCHEMA

    shot = read_trajectory(ROOT / "tests" / "golden" / "golf.trajectory.parquet")
    times, _ = log_context(log)
    f = np.arange(shot.height, frames)
    rng = np.random.default_rng(0)
    later = pl.DataFrame({"tracker": "golf", "track_id": 1, "frame": f, "t_ns": np.array([times[int(i)] for i in f], np.int64),
                          "x": rng.uniform(0, 640, f.size), "y": rng.uniform(0, 360, f.size), "w": 6.0, "h": 6.0,
                          "X": None, "Y": None, "Z": None, "dx": rng.normal(0, 1, f.size), "dy": 1.0, "dz": -0.1,
                          "vx": None, "vy": None, "status": "predicted", "confidence": 0.3}).cast(SCHEMA)
    pl.concat([shot.cast(SCHEMA), later]).write_parquet(path)


def flight_only(sizes: list[int], out: Path) -> int:
    """`trackreplay flight T.parquet LOG --out F.parquet`: as it is against the whole table (fresh processes)."""
    import os

    import polars as pl

    load_before = [round(x, 2) for x in os.getloadavg()]
    runs = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in sizes:
            log, traj = Path(tmp) / f"golf-{n}.mcap", Path(tmp) / f"t-{n}.parquet"
            write_golf_log(log, n)
            golf_trajectory(traj, log, n)
            entry: dict = {"frames": n, "rows": n}
            for name, whole in (("pieces", False), ("whole_table", True)):
                target, printed = Path(tmp) / f"{name}.parquet", Path(tmp) / f"{name}.txt"
                argv = ["flight", str(traj), str(log), "--out", str(target), "--quiet"]
                code = FLIGHT.format(root=str(ROOT), whole=whole, printed=str(printed), argv=argv)
                got = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True,
                                     cwd=ROOT).stdout.split()
                status, base, peak, cpu, wall = int(got[-5]), int(got[-4]), int(got[-3]), float(got[-2]), float(got[-1])
                entry[name] = {"exit": status, "base_rss_kib": base, "peak_rss_kib": peak,
                               "command_mb": round((peak - base) / 1024, 1), "cpu_seconds": round(cpu, 2),
                               "seconds": round(wall, 2)}
            entry["identical"] = pl.read_parquet(Path(tmp) / "pieces.parquet").equals(
                pl.read_parquet(Path(tmp) / "whole_table.parquet"), null_equal=True)
            entry["same_report"] = ((Path(tmp) / "pieces.txt").read_text().splitlines()[:-1]
                                    == (Path(tmp) / "whole_table.txt").read_text().splitlines()[:-1])
            runs.append(entry)
            print(json.dumps(entry), flush=True)
    growth = {k: round(runs[-1][k]["command_mb"] - runs[0][k]["command_mb"], 1) for k in ("pieces", "whole_table")}
    write_results(out, load_before, "the golden tee shot's log and trajectory continued to N frames (a 32x32 PNG and the "
                  "last PTZ reading a frame; the ball's track predicted, with a line of sight, on every later frame)", runs,
                  "command_mb_growth", {"from_frames": sizes[0], "to_frames": sizes[-1], **growth})
    print(f"flight: peak above the process {sizes[0]} -> {sizes[-1]} frames +{growth['pieces']} MB "
          f"(whole table +{growth['whole_table']})")
    return 0 if all(r["identical"] and r["same_report"] and r["pieces"]["exit"] == 0 for r in runs) else 1


def write_tracks(path: Path, frames: int, objects: int) -> None:
    """The scene's flow track (``write_spill``) and a track on each still truth box (``write_long_log``'s
    ``objects`` - 1, their centres jittered, 5 % lost): several tracks, canonical order, row groups of 2048 rows."""
    import polars as pl

    from trackreplay.replay.core.trajectory import SCHEMA

    write_spill(path, frames)
    tracks = [pl.read_parquet(path)]
    rng = np.random.default_rng(1)
    t = np.arange(frames)
    for k in range(1, objects):
        lost = rng.random(frames) < 0.05
        x = np.where(lost, np.nan, 3.0 + 26.0 * (k % 2) + rng.normal(0, 0.3, frames))
        y = np.where(lost, np.nan, 3.0 + 26.0 * (k // 2 % 2) + rng.normal(0, 0.3, frames))
        nan = np.full(frames, np.nan)
        df = pl.DataFrame({"tracker": "flow", "track_id": k + 1, "frame": t, "t_ns": t * 1_000_000_000 // 30, "x": x, "y": y,
                           "w": np.where(lost, np.nan, 4.0), "h": np.where(lost, np.nan, 4.0), "vx": nan, "vy": nan,
                           "X": nan, "Y": nan, "Z": nan, "dx": nan, "dy": nan, "dz": nan,
                           "status": np.where(lost, "lost", "measured"), "confidence": np.where(lost, np.nan, 0.8)})
        tracks.append(df.cast(SCHEMA).with_columns(pl.col(c).fill_nan(None) for c, v in SCHEMA.items() if v == pl.Float64))
    pl.concat(tracks).write_parquet(path, row_group_size=2048)


def mot_only(sizes: list[int], out: Path, objects: int = 3) -> int:
    """`eval T.parquet LOG --mot`: the scene's log with ``objects`` truth objects and a track on each, scored in
    a fresh process a chunk of frames at a time against the whole tables (``--per-frame`` takes that path); the
    same --json asked of both."""
    import os

    load_before = [round(x, 2) for x in os.getloadavg()]
    runs = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in sizes:
            log, traj = Path(tmp) / f"long-{n}.mcap", Path(tmp) / f"t-{n}.parquet"
            write_long_log(log, n, objects)
            write_tracks(traj, n, objects)
            entry = {"frames": n, "truth_objects": objects, "tracks": objects,
                     **eval_against_whole(traj, log, Path(tmp), n, ["--mot"])}
            runs.append(entry)
            print(json.dumps(entry), flush=True)
    growth = {k: round((runs[-1][k]["peak_rss_kib"] - runs[0][k]["peak_rss_kib"]) / 1024, 1) for k in ("chunked", "whole_table")}
    write_results(out, load_before, f"the long-log scene's log ({objects} truth objects) and a track on each (the flow "
                  "track, one row a frame, 3 % lost; still tracks on the still boxes, 5 % lost)", runs,
                  "peak_rss_growth_mb", {"from_frames": sizes[0], "to_frames": sizes[-1], **growth})
    print(f"eval --mot peak RSS growth {sizes[0]} -> {sizes[-1]} frames (MB): {growth} (target <= 50)")
    return 0 if all(r["same_json"] and r["chunked"]["exit"] == 0 for r in runs) else 1


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--frames", default="1000,20000,200000", help="log lengths, comma-separated")
    ap.add_argument("--out", type=Path, default=None)
    ap.add_argument("--export-only", action="store_true", help="the export step alone, on a spill file made directly")
    ap.add_argument("--eval-only", action="store_true", help="eval alone (chunked and whole table), on the flow track made directly")
    ap.add_argument("--csv-only", action="store_true", help="read_trajectory of a CSV input: in pieces and whole")
    ap.add_argument("--csv-export-only", action="store_true", help="`export T.csv OUT.parquet`: in pieces and whole")
    ap.add_argument("--sidecar-only", action="store_true", help="diff's read of a per-frame digest sidecar: blocks and whole")
    ap.add_argument("--smooth-only", action="store_true", help="`smooth` of one long track per model: as is and whole")
    ap.add_argument("--flight-only", action="store_true", help="`flight` on the golden shot continued: as is and whole")
    ap.add_argument("--mot-only", action="store_true", help="`eval --mot` (several tracks and truth objects): chunked and whole")
    ap.add_argument("--objects", type=int, default=1, help="--eval-only: truth objects in the log (several: no --gt-id); "
                    "--mot-only: truth objects and tracks (at least 2; default 3)")
    args = ap.parse_args()
    sizes = [int(x) for x in args.frames.split(",")]
    if args.mot_only:
        return mot_only(sizes, args.out or ROOT / "benchmarks" / "results" / "long_log_mot.json", args.objects if args.objects > 1 else 3)
    if args.flight_only:
        return flight_only(sizes, args.out or ROOT / "benchmarks" / "results" / "long_log_flight.json")
    if args.smooth_only:
        return smooth_only(sizes, args.out or ROOT / "benchmarks" / "results" / "long_log_smooth.json")
    if args.csv_export_only:
        return csv_export_only(sizes, args.out or ROOT / "benchmarks" / "results" / "long_log_csv_export.json")
    if args.sidecar_only:
        return sidecar_only(sizes, args.out or ROOT / "benchmarks" / "results" / "long_log_sidecar.json")
    if args.csv_only:
        return csv_only(sizes, args.out or ROOT / "benchmarks" / "results" / "long_log_csv.json")
    if args.eval_only:
        name = "long_log_eval.json" if args.objects == 1 else "long_log_eval_objects.json"
        return eval_only(sizes, args.out or ROOT / "benchmarks" / "results" / name, args.objects)
    if args.export_only:
        return export_only(sizes, args.out or ROOT / "benchmarks" / "results" / "long_log_export.json")
    args.out = args.out or ROOT / "benchmarks" / "results" / "long_log.json"
    load_before = [round(x, 2) for x in __import__("os").getloadavg()]
    with tempfile.TemporaryDirectory() as tmp:
        runs = []
        for n in sizes:
            runs.append(run_size(Path(tmp), n))
            print(json.dumps(runs[-1]), flush=True)
    first, last = runs[0], runs[-1]
    growth = {k: round((last[k]["peak_rss_kib"] - first[k]["peak_rss_kib"]) / 1024, 1)
              for k in ("replay_summary", "replay_export", "replay_export_whole", "eval")}
    results = {
        "machine": describe(),
        "load_average_before": load_before,
        "load_average_after": [round(x, 2) for x in __import__("os").getloadavg()],
        "scene": f"{SIZE}x{SIZE} grey PNG, a {SQUARE}x{SQUARE} square on a circle of period {PERIOD} frames, flow tracker",
        "runs": runs,
        "peak_rss_growth_mb": {"from_frames": first["frames"], "to_frames": last["frames"], **growth, "target": "<= 50"},
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(results, indent=2) + "\n")
    for r in runs:
        print(f"{r['frames']:>7} frames: replay --summary {r['replay_summary']['peak_rss_kib'] / 1024:.0f} MB "
              f"{r['replay_summary']['seconds']:.1f} s; with --export {r['replay_export']['peak_rss_kib'] / 1024:.0f} MB "
              f"(whole-table fill {r['replay_export_whole']['peak_rss_kib'] / 1024:.0f} MB); "
              f"eval {r['eval']['peak_rss_kib'] / 1024:.0f} MB {r['eval']['seconds']:.1f} s")
    print(f"peak RSS growth {first['frames']} -> {last['frames']} frames (MB): {growth} (target <= 50)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
