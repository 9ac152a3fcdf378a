"""Offline smoothing rate (issue 33): rows per second of ``trackreplay smooth``'s smoother before and
after batching it over tracks and noise grid points (``replay/analysis/rts.py``, ``rts_space.py``).

Synthetic trajectories, one per track model: ``colorpf`` (image constant velocity, positions with a
confidence), ``flow`` (the same with the tracker's velocity observed: a 4× larger noise grid) and
``groups`` (3-D constant velocity). Each has several tracks with short predicted/lost gaps, a few
long lost runs, absent frames and 1 % wrong blobs (outliers). The old path is the filterpy smoother
it replaced (one track, one grid point at a time), kept below as the reference; it runs only on a
short table (``--old-rows``, it costs 10-100 ms a row) and its outputs are compared with the new
path's there. The new path runs on 10k and 60k rows, each timed (best of ``--repeats``) and its
peak traced allocation measured in a separate run (tracemalloc).

Layouts (issue 33, the whole ``smooth_trajectory``: kernels and the assembly of the output table):
``--layout-rows`` rows as one long track and as many short tracks (60 rows each), timed for the tree's
module and, with ``--before REV``, for ``replay/analysis/smooth.py`` as it was at git revision REV
(``smooth.py`` and ``rts.py`` loaded from ``git show``; same inputs; outputs compared: they must be
identical).

``--before-dir DIR`` does the same with copies of ``smooth.py`` and ``rts.py`` kept in DIR. The fits must
be the same; their log-likelihoods are compared to a relative tolerance (a long track's grid search sums
its terms piece by piece, ``rts._pieces_loglik``).

``--long-sizes 1000,200000`` (issue 33, "memory flat"): one track of each model at each size, smoothed in a
fresh process (``smooth_trajectory`` on the table read from Parquet, as ``trackreplay smooth`` reads it); its peak
RSS (VmHWM) above the process's RSS with the table read, CPU and wall seconds; with ``--before``/``--before-dir``
the same for the earlier files, and the two outputs compared (identical to the bit). Writes
benchmarks/results/smooth_long.json.

``--command-sizes 1000,20000,200000`` (issue 33, the command): ``trackreplay smooth T.parquet LOG --out S.parquet``
in a fresh process, T one track of each model and the same rows as tracks of ``--command-track-rows`` (2000) rows,
LOG a log of that many tiny PNG frames at T's frame times: the command as it is (a checked Parquet trajectory
read, smoothed and written a few whole tracks at a time, ``replay/cli/commands/smooth.py``) and the whole table
(``smooth_in_pieces`` made to decline, so the table is read whole as before); its peak RSS (VmHWM) above the process's
with the modules loaded, CPU and wall seconds; the two outputs and the printed fits compared. Writes
benchmarks/results/smooth_command.json.

Usage: python benchmarks/bench_smooth.py [--old-rows 600] [--repeats 2] [--before HEAD | --before-dir DIR] [--layout-rows 60000]
       python benchmarks/bench_smooth.py --long-sizes 1000,200000 [--before REV | --before-dir DIR]
       python benchmarks/bench_smooth.py --command-sizes 1000,20000,200000 [--command-track-rows 2000]
Writes benchmarks/results/smooth.json (``--long-sizes``: smooth_long.json, ``--command-sizes``: smooth_command.json).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
import tracemalloc
from pathlib import Path

import numpy as np
import polars as pl
from filterpy.kalman import KalmanFilter

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks.machine import describe  # noqa: E402
from trackreplay.replay.analysis import smooth  # noqa: E402
from trackreplay.replay.core.trajectory import SCHEMA  # noqa: E402

MODELS = ("colorpf", "flow", "groups")
MISSING_VAR = 1e12


def synthetic_trajectory(rows: int, tracker: str, tracks: int = 6, seed: int = 0) -> pl.DataFrame:
    """``tracks`` tracks of ``tracker`` over about ``rows`` rows: curved motion, noise growing as the
    confidence falls, gaps (3 predicted frames then lost, up to 25 frames), absent frames, outliers."""
    rng = np.random.default_rng(seed)
    cols: dict[str, list] = {c: [] for c in SCHEMA}
    for tid in range(1, tracks + 1):
        n = rows // tracks + (rows % tracks if tid == tracks else 0)
        k = np.arange(n, dtype=float)
        phase = rng.uniform(0.0, 2 * math.pi)
        x, y = 320 + 150 * np.cos(k / 90.0 + phase) + 0.02 * k, 240 + 100 * np.sin(k / 70.0 + phase)
        conf = rng.uniform(0.3, 1.0, n)
        status = np.full(n, "measured", dtype=object)
        g = 0
        while g < n:
            g += int(rng.integers(20, max(21, min(200, n // 2))))
            length = int(rng.choice([2, 5, 10, 25]))
            status[g:g + min(3, length)] = "predicted"
            status[g + 3:g + length] = "lost"
            g += length
        mx, my = x + rng.normal(0, 1.5, n) / np.sqrt(conf), y + rng.normal(0, 1.5, n) / np.sqrt(conf)
        wrong = rng.random(n) < 0.01
        mx[wrong] += rng.choice([-60.0, 60.0], wrong.sum())
        pos, keep = status != "lost", rng.random(n) >= 0.005
        frame = int(rng.integers(0, 50)) + np.arange(n)
        nan = np.full(n, np.nan)
        values = {"tracker": np.full(n, tracker, dtype=object), "track_id": np.full(n, tid), "frame": frame,
                  "t_ns": frame * 33_333_333, "status": status, "confidence": np.where(pos, conf, nan)}
        image = tracker != "groups"
        values.update({"x": np.where(pos, mx if image else 1.0, nan), "y": np.where(pos, my if image else 1.0, nan),
                       "w": np.where(pos, 20.0, nan), "h": np.where(pos, 20.0, nan),
                       "vx": np.where(pos, np.gradient(x) + rng.normal(0, 0.3, n), nan) if image else nan,
                       "vy": np.where(pos, np.gradient(y) + rng.normal(0, 0.3, n), nan) if image else nan,
                       "X": nan if image else np.where(pos, mx / 100, nan), "Y": nan if image else np.where(pos, my / 100, nan),
                       "Z": nan if image else np.where(pos, 5 + 0.001 * k, nan), "dx": nan, "dy": nan, "dz": nan})
        for c in SCHEMA:
            cols[c].extend(values[c][keep].tolist())
    df = pl.DataFrame(cols).cast(SCHEMA)
    return df.with_columns(pl.col(c).fill_nan(None) for c, t in SCHEMA.items() if t == pl.Float64)


# --- the reference: the filterpy smoother this replaced, one track and one grid point at a time ---

def _reference_run(z, r, q, sigma, sigma_v, smooth_it):
    have = np.isfinite(z)
    first = int(np.flatnonzero(have[:, 0])[0])
    kf = KalmanFilter(dim_x=4, dim_z=4)
    model = smooth.DEFAULT_SMOOTHING
    kf.F, kf.H, kf.Q = model.F(), model.H(), model.Q(q)
    s0 = sigma * sigma * r[first]
    kf.x = np.array([z[first, 0], 0.0, z[first, 1], 0.0])
    kf.P = np.diag([s0 + 1e4, 1e2, s0 + 1e4, 1e2])
    base = np.array([sigma, sigma, sigma_v, sigma_v]) ** 2
    zs = [None if not have[k].any() else np.where(have[k], z[k], 0.0) for k in range(len(z))]
    Rs = [np.diag(base) if zs[k] is None else np.diag(np.where(have[k], base * r[k], MISSING_VAR)) for k in range(len(z))]
    means, covs, means_p, covs_p = kf.batch_filter(zs, Rs=Rs)
    ll = 0.0
    for k in range(len(z)):
        if zs[k] is None or k == first:
            continue
        sel = have[k]
        y = (zs[k] - kf.H @ means_p[k])[sel]
        S = (kf.H @ covs_p[k] @ kf.H.T + Rs[k])[np.ix_(sel, sel)]
        ll -= 0.5 * (float(y @ np.linalg.solve(S, y)) + math.log(np.linalg.det(S)) + sel.sum() * math.log(2.0 * math.pi))
    if not smooth_it:
        return ll, None, None
    xs, Ps, _, _ = kf.rts_smoother(means, covs)
    return ll, xs, Ps


def _reference_track(z, r, cfg):
    def select():
        best = (cfg.q_grid[0], cfg.sigma_grid[0], cfg.sigma_v_grid[0], -math.inf)
        for q in cfg.q_grid:
            for s in cfg.sigma_grid:
                for sv in cfg.sigma_v_grid if np.isfinite(z[:, 2:]).any() else cfg.sigma_v_grid[:1]:
                    ll = _reference_run(z, r, q, s, sv, False)[0]
                    best = (q, s, sv, ll) if ll > best[3] else best
        return best

    observed = np.isfinite(z[:, :2]).all(axis=1)
    fit = select()
    _, xs, Ps = _reference_run(z, r, *fit[:3], True)
    outliers = np.zeros(len(z), bool)
    if observed.sum() > 4:
        bad = observed & (np.sqrt(((z[:, :2] - xs[:, [0, 2]]) ** 2).sum(axis=1) / (2.0 * fit[1] ** 2 * r)) > cfg.outlier_sigma)
        if bad.any() and (observed & ~bad).sum() >= 2:
            outliers, z[bad] = bad, np.nan
            fit = select()
            _, xs, Ps = _reference_run(z, r, *fit[:3], True)
    return xs, np.stack([Ps[:, i, i] for i in range(4)], axis=1), outliers, fit


def reference_smooth_tracks(zs, confidences, cfg=smooth.SmoothConfig()):
    """The old ``smooth_track`` on every track in turn (filterpy)."""
    out = []
    for z, c in zip(zs, confidences):
        z = np.array(z, dtype=np.float64)
        z = np.concatenate([z, np.full_like(z, np.nan)], axis=1) if z.shape[1] == 2 else z
        z[~np.isfinite(z[:, :2]).all(axis=1)] = np.nan
        out.append(_reference_track(z, 1.0 / np.where(np.isfinite(c), np.maximum(c, cfg.min_confidence), 1.0), cfg))
    return out


def _reference_space_run(model, z, R, accel, smooth_it):
    have = np.isfinite(z).all(axis=1)
    first = int(np.flatnonzero(have)[0])
    kf = KalmanFilter(dim_x=6, dim_z=3)
    kf.F, kf.H, kf.Q = model.F(), model.H(), model.Q(accel)
    kf.x = np.zeros(6)
    kf.x[[0, 2, 4]] = z[first]
    kf.P = np.diag([1.0, 0.05, 1.0, 0.05, 1.0, 0.05]) ** 2 + np.kron(R[first], np.diag([1.0, 0.0]))
    means, covs, means_p, covs_p = kf.batch_filter([z[k] if have[k] else None for k in range(len(z))],
                                                   Rs=[R[k] if have[k] else np.eye(3) for k in range(len(z))])
    ll = 0.0
    for k in np.flatnonzero(have):
        if k != first:
            y, S = z[k] - kf.H @ means_p[k], kf.H @ covs_p[k] @ kf.H.T + R[k]
            ll -= 0.5 * (float(y @ np.linalg.solve(S, y)) + math.log(np.linalg.det(S)) + 3 * math.log(2.0 * math.pi))
    return (ll, *kf.rts_smoother(means, covs)[:2]) if smooth_it else (ll, None, None)


def reference_fit_space(model, tracks, cfg):
    """The old per-track ``_fit_space`` (filterpy), in the batched one's interface."""
    out = []
    for t in tracks:
        z, R0, ok = t.z, t.R0, t.ok.copy()
        best = (model.accel_grid[0], t.grid[0], -math.inf)
        for accel in model.accel_grid:
            for s in t.grid:
                ll = _reference_space_run(model, z, R0 * s * s, accel, False)[0]
                best = (accel, s, ll) if ll > best[2] else best
        accel, s, ll = best
        _, xs, Ps = _reference_space_run(model, z, R0 * s * s, accel, True)
        outliers = np.zeros(len(z), bool)
        if ok.sum() > 4:
            resid = z - xs[:, [0, 2, 4]]
            d2 = np.array([float(resid[k] @ np.linalg.solve(R0[k] * s * s, resid[k])) / 3.0 if ok[k] else 0.0
                           for k in range(len(z))])
            bad = ok & (np.sqrt(d2) > cfg.outlier_sigma)
            if bad.any() and (ok & ~bad).sum() >= 2:
                outliers, z[bad], R0[bad], ok = bad, np.nan, np.eye(3), ok & ~bad
                _, xs, Ps = _reference_space_run(model, z, R0 * s * s, accel, True)
        out.append((accel, s, ll, xs, Ps, ok, outliers))
    return out


def run_reference(table: pl.DataFrame):
    """``smooth_trajectory`` with the filterpy kernels in place of the batched ones."""
    saved = smooth.smooth_tracks, smooth._fit_space
    smooth.smooth_tracks, smooth._fit_space = reference_smooth_tracks, reference_fit_space
    try:
        return smooth.smooth_trajectory(table)
    finally:
        smooth.smooth_tracks, smooth._fit_space = saved


# --- measurement ---

def compare(old: pl.DataFrame, new: pl.DataFrame, old_fits, new_fits) -> dict:
    """Largest absolute difference per float column, and whether every other column and fit agree."""
    diffs = {}
    for c in old.columns:
        if old[c].dtype == pl.Float64:
            a, b = old[c].to_numpy().astype(float), new[c].to_numpy().astype(float)
            assert np.array_equal(np.isnan(a), np.isnan(b)), f"{c}: nulls differ"
            diffs[c] = float(np.max(np.abs(a - b)[~np.isnan(a)], initial=0.0))
    same = all(old[c].equals(new[c]) for c in old.columns if old[c].dtype != pl.Float64)
    fits = [(f.q, f.sigma, f.observations, f.outliers, f.filled) for f in old_fits] == \
           [(f.q, f.sigma, f.observations, f.outliers, f.filled) for f in new_fits]
    worst_ll = max((abs(a.log_likelihood - b.log_likelihood) for a, b in zip(old_fits, new_fits)), default=0.0)
    image = ("x", "y") if "X_std" not in diffs or old["X_std"].null_count() == old.height else ("X", "Y", "Z")
    return {"max_abs_diff_position": max(diffs[c] for c in image), "max_abs_diff_any_column": max(diffs.values()),
            "worst_column": max(diffs, key=diffs.get), "other_columns_equal": same, "fits_equal": fits,
            "max_abs_diff_log_likelihood": worst_ll}


def timed(table: pl.DataFrame, repeats: int) -> tuple[float, float]:
    """Best wall and best CPU seconds of ``repeats`` runs (on a shared machine the CPU time is the
    work; the wall time also counts the waits for a core)."""
    wall, cpu = math.inf, math.inf
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        smooth.smooth_trajectory(table)
        wall, cpu = min(wall, time.perf_counter() - t0), min(cpu, time.process_time() - c0)
    return wall, cpu


def peak_bytes(table: pl.DataFrame) -> int:
    tracemalloc.start()
    smooth.smooth_trajectory(table)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return peak


def bench_model(tracker: str, old_rows: int, sizes: tuple[int, ...], repeats: int) -> dict:
    smooth.smooth_trajectory(synthetic_trajectory(300, tracker, tracks=2))  # imports, registry
    short = synthetic_trajectory(old_rows, tracker, seed=1)
    t0, c0 = time.perf_counter(), time.process_time()
    old, old_fits = run_reference(short)
    t_old, c_old = time.perf_counter() - t0, time.process_time() - c0
    t_new, c_new = timed(short, repeats)
    new, new_fits = smooth.smooth_trajectory(short)
    n = short.height
    result = {"old": {"rows": n, "seconds": t_old, "cpu_seconds": c_old, "rows_per_s": n / t_old,
                      "rows_per_cpu_s": n / c_old},
              "new_same_rows": {"seconds": t_new, "cpu_seconds": c_new, "rows_per_s": n / t_new,
                                "rows_per_cpu_s": n / c_new},
              "agreement": compare(old, new, old_fits, new_fits), "new": {}}
    for rows in sizes:
        table = synthetic_trajectory(rows, tracker, seed=2)
        wall, cpu = timed(table, repeats)
        result["new"][str(rows)] = {"rows": table.height, "seconds": wall, "cpu_seconds": cpu,
                                    "rows_per_s": table.height / wall, "rows_per_cpu_s": table.height / cpu,
                                    "peak_traced_bytes": peak_bytes(table)}
    result["speedup_vs_old_cpu"] = result["new"][str(sizes[-1])]["rows_per_cpu_s"] / result["old"]["rows_per_cpu_s"]
    return result


def module_at(rev: str, name: str):
    """``replay/analysis/NAME.py`` at git revision ``rev``, imported as ``NAME_before``."""
    import importlib.util
    import subprocess

    source = subprocess.run(["git", "-C", str(ROOT), "show", f"{rev}:replay/analysis/{name}.py"], check=True,
                            capture_output=True, text=True).stdout
    path = Path(os.environ.get("TMPDIR", "/tmp")) / f"trackreplay_{name}_{os.getpid()}.py"
    path.write_text(source)
    try:
        spec = importlib.util.spec_from_file_location(f"{name}_before", path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[f"{name}_before"] = module
        spec.loader.exec_module(module)
    finally:
        path.unlink()
    return module


def smooth_at(rev: str):
    """The smoother as it was at ``rev``: its ``smooth.py`` with that revision's ``rts.py`` kernels."""
    module = module_at(rev, "smooth")
    module.rts = module_at(rev, "rts")
    return module


def smooth_from(folder: Path):
    """The smoother of the copies ``folder/smooth.py`` and ``folder/rts.py`` (an earlier tree's files)."""
    import importlib.util

    def load(name: str):
        spec = importlib.util.spec_from_file_location(f"{name}_before", folder / f"{name}.py")
        module = importlib.util.module_from_spec(spec)
        sys.modules[f"{name}_before"] = module
        spec.loader.exec_module(module)
        return module

    module = load("smooth")
    module.rts = load("rts")
    return module


def bench_layouts(rows: int, repeats: int, before) -> dict:
    """Rows per second of the whole ``smooth_trajectory`` on one long track and on many short ones."""
    out: dict = {}
    for tracker in MODELS:
        for layout, tracks in (("one_long_track", 1), ("short_tracks_60_rows", max(1, rows // 60))):
            table = synthetic_trajectory(rows, tracker, tracks=tracks, seed=2)
            entry: dict = {"rows": table.height, "tracks": tracks}
            for name, module in (("after", smooth), ("before", before)):
                if module is None:
                    continue
                module.smooth_trajectory(synthetic_trajectory(300, tracker, tracks=2))  # imports, registry
                wall, cpu = math.inf, math.inf
                for _ in range(repeats):
                    t0, c0 = time.perf_counter(), time.process_time()
                    result = module.smooth_trajectory(table)
                    wall, cpu = min(wall, time.perf_counter() - t0), min(cpu, time.process_time() - c0)
                entry[name] = {"seconds": wall, "cpu_seconds": cpu, "rows_per_s": table.height / wall,
                               "rows_per_cpu_s": table.height / cpu}
                entry.setdefault("_results", []).append(result)
            if before is not None:
                (a, fa), (b, fb) = entry.pop("_results")
                fits = [{**vars(f), "log_likelihood": None} for f in fa] == [{**vars(f), "log_likelihood": None} for f in fb]
                entry["identical"] = a.equals(b, null_equal=True) and fits  # the table to the bit, the same fits
                entry["max_rel_diff_log_likelihood"] = max(
                    (abs(x.log_likelihood - y.log_likelihood) / max(abs(y.log_likelihood), 1e-300) for x, y in zip(fa, fb)),
                    default=0.0)  # rts._pieces_loglik sums a long track's terms piece by piece
            entry.pop("_results", None)
            out[f"{tracker}/{layout}"] = entry
            print(tracker, layout, {k: round(v["rows_per_cpu_s"]) for k, v in entry.items() if isinstance(v, dict)},
                  "identical" if entry.get("identical") else "", flush=True)
    return out


LONG = """
import sys, time
sys.path.insert(0, {root!r})
import polars as pl
sys.argv = ["bench_smooth"]
from benchmarks import bench_smooth as b
module = b.smooth if not {before!r} else b.smooth_at({before!r}) if {rev!r} else b.smooth_from(b.Path({before!r}))
module.smooth_trajectory(pl.read_parquet({table!r}).head(300))  # imports, registry
table = pl.read_parquet({table!r})
base = b.high_water_kib()
c0, w0 = time.process_time(), time.perf_counter()
out, fits = module.smooth_trajectory(table)
cpu, wall = time.process_time() - c0, time.perf_counter() - w0
peak = b.high_water_kib()
out.write_parquet({out!r})
print(base, peak, cpu, wall)
"""


def high_water_kib() -> int:
    """This process's peak RSS (VmHWM, KiB): its own address space's (ru_maxrss keeps the parent's peak
    across fork and exec, and this benchmark's parent builds the tables)."""
    with open("/proc/self/status") as fh:
        return next(int(line.split()[1]) for line in fh if line.startswith("VmHWM:"))


def bench_long(sizes: list[int], before: str | None, before_is_rev: bool) -> dict:
    """One track of each model at each size, smoothed in a fresh process (see the module docstring)."""
    import subprocess
    import tempfile

    result: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        for tracker in MODELS:
            for rows in sizes:
                table = Path(tmp) / f"{tracker}-{rows}.parquet"
                synthetic_trajectory(rows, tracker, tracks=1, seed=2).write_parquet(table)
                entry: dict = {"rows": pl.scan_parquet(table).select(pl.len()).collect().item()}
                for name, which in (("after", None), ("before", before)):
                    if name == "before" and before is None:
                        continue
                    out = Path(tmp) / f"{name}-{tracker}-{rows}.parquet"
                    code = LONG.format(root=str(ROOT), before=which, rev=before_is_rev, table=str(table), out=str(out))
                    got = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True,
                                         cwd=ROOT).stdout.split()
                    base, peak, cpu, wall = int(got[-4]), int(got[-3]), float(got[-2]), float(got[-1])
                    entry[name] = {"base_rss_kib": base, "peak_rss_kib": peak, "smooth_mb": round((peak - base) / 1024, 1),
                                   "cpu_seconds": round(cpu, 2), "seconds": round(wall, 2),
                                   "rows_per_cpu_s": round(entry["rows"] / cpu), "rows_per_s": round(entry["rows"] / wall)}
                if before is not None:
                    entry["identical"] = pl.read_parquet(Path(tmp) / f"after-{tracker}-{rows}.parquet").equals(
                        pl.read_parquet(Path(tmp) / f"before-{tracker}-{rows}.parquet"), null_equal=True)
                result[f"{tracker}/{rows}"] = entry
                print(tracker, rows, json.dumps(entry), flush=True)
    growth = {}
    for tracker in MODELS:
        lo, hi = result[f"{tracker}/{sizes[0]}"], result[f"{tracker}/{sizes[-1]}"]
        growth[tracker] = {k: round((hi[k]["peak_rss_kib"] - lo[k]["peak_rss_kib"]) / 1024, 1) for k in ("after", "before")
                           if k in hi}
    return {"runs": result, "peak_rss_growth_mb": {"from_rows": sizes[0], "to_rows": sizes[-1], **growth}}


COMMAND = """
import contextlib, sys, time
sys.path.insert(0, {root!r})
sys.argv = ["bench_smooth"]
from benchmarks import bench_smooth as b
import pyarrow.parquet
from trackreplay.replay.analysis import eval as evaluation, smooth
from trackreplay.replay.cli.main import main
from trackreplay.replay.log.reader import LogReader
from trackreplay.replay.cli.commands import smooth as command
if {whole!r}:
    command.smooth_in_pieces = lambda *a, **k: None  # the whole table, as before
base = b.high_water_kib()
c0, w0 = time.process_time(), time.perf_counter()
with open({printed!r}, "w") as fh, contextlib.redirect_stdout(fh):
    code = main({argv!r})
cpu, wall = time.process_time() - c0, time.perf_counter() - w0
print(code, base, b.high_water_kib(), cpu, wall)
"""


def write_frames_log(path: Path, frames: int) -> None:
    """A log of ``frames`` tiny PNG pictures at :func:`synthetic_trajectory`'s frame times (frame i at
    i × 33 333 333 ns): what ``smooth`` reads of a log is each frame's time."""
    import cv2
    from trackreplay.recorder.image_codec import compressed_image
    from trackreplay.recorder.writer import LogWriter
    from trackreplay.schemas import topics as T

    png = cv2.imencode(".png", np.zeros((8, 8), np.uint8))[1].tobytes()
    with LogWriter(path, flush_every=1000) as log:
        for i in range(frames):
            t_ns = i * 33_333_333
            log.write(T.CAMERA_IMAGE, compressed_image(png, "png", t_ns, "camera"), t_ns)


def pieces_against_whole(table: Path, log: Path, tmp: Path) -> dict:
    """``trackreplay smooth TABLE LOG`` in a fresh process, in pieces and with the whole table: each one's
    exit, peak RSS above the process's base, CPU and wall time, rows per CPU-second; whether the two
    outputs and printed fits are the same."""
    import subprocess

    entry: dict = {"rows": pl.scan_parquet(table).select(pl.len()).collect().item()}
    for name, whole in (("pieces", False), ("whole_table", True)):
        out, printed = tmp / f"{name}.parquet", tmp / f"{name}.txt"
        argv = ["smooth", str(table), str(log), "--out", str(out)]
        code = COMMAND.format(root=str(ROOT), whole=whole, printed=str(printed), argv=argv)
        got = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True, cwd=ROOT).stdout.split()
        status, base, peak, cpu, wall = int(got[-5]), int(got[-4]), int(got[-3]), float(got[-2]), float(got[-1])
        entry[name] = {"exit": status, "base_rss_kib": base, "peak_rss_kib": peak,
                       "command_mb": round((peak - base) / 1024, 1), "cpu_seconds": round(cpu, 2),
                       "seconds": round(wall, 2), "rows_per_cpu_s": round(entry["rows"] / cpu)}
    entry["identical"] = pl.read_parquet(tmp / "pieces.parquet").equals(pl.read_parquet(tmp / "whole_table.parquet"),
                                                                         null_equal=True)
    entry["same_printed_fits"] = ((tmp / "pieces.txt").read_text().splitlines()[:-1]
                                  == (tmp / "whole_table.txt").read_text().splitlines()[:-1])
    return entry


def bench_command(sizes: list[int], track_rows: int, models: tuple[str, ...] = MODELS) -> dict:
    """``trackreplay smooth`` in pieces and on the whole table, fresh processes (see the module docstring)."""
    import tempfile

    result: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        logs: dict[int, Path] = {}
        for rows in sizes:
            logs[rows] = Path(tmp) / f"log-{rows}.mcap"
            write_frames_log(logs[rows], rows + 60)  # a track starts within its first 50 frames
            for tracker in models:
                for layout, tracks in (("one_track", 1), (f"tracks_of_{track_rows}", max(1, rows // track_rows))):
                    table = Path(tmp) / f"{tracker}-{layout}-{rows}.parquet"
                    synthetic_trajectory(rows, tracker, tracks=tracks, seed=2).write_parquet(table)
                    entry = {**pieces_against_whole(table, logs[rows], Path(tmp)), "tracks": tracks}
                    result[f"{tracker}/{layout}/{rows}"] = entry
                    print(tracker, layout, rows, json.dumps(entry), flush=True)
    growth: dict = {}
    for key in {k.rsplit("/", 1)[0] for k in result}:
        lo, hi = result[f"{key}/{sizes[0]}"], result[f"{key}/{sizes[-1]}"]
        growth[key] = {k: round((hi[k]["command_mb"] - lo[k]["command_mb"]), 1) for k in ("pieces", "whole_table")}
    return {"runs": result, "command_mb_growth": {"from_rows": sizes[0], "to_rows": sizes[-1], "target": "<= 50",
                                                  **dict(sorted(growth.items()))}}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old-rows", type=int, default=600)
    ap.add_argument("--sizes", type=int, nargs="+", default=[10_000, 60_000])
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--models", nargs="+", default=list(MODELS), choices=MODELS)
    ap.add_argument("--before", help="git revision whose replay/analysis/smooth.py to time beside the tree's")
    ap.add_argument("--before-dir", type=Path, help="a folder with an earlier smooth.py and rts.py to time beside the tree's")
    ap.add_argument("--layout-rows", type=int, default=60_000)
    ap.add_argument("--skip-models", action="store_true", help="only the layouts")
    ap.add_argument("--long-sizes", help="one track per model at these row counts (comma-separated), fresh processes")
    ap.add_argument("--command-sizes", help="`trackreplay smooth` at these row counts (comma-separated), fresh processes")
    ap.add_argument("--command-track-rows", type=int, default=2000, help="rows of a track in the many-tracks layout")
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    load_before = os.getloadavg()
    if args.command_sizes:
        command = bench_command([int(x) for x in args.command_sizes.split(",")], args.command_track_rows, tuple(args.models))
        out = {"machine": describe(), "load_average_before": load_before, "load_average_after": os.getloadavg(), **command}
        path = args.out or ROOT / "benchmarks" / "results" / "smooth_command.json"
        path.write_text(json.dumps(out, indent=2) + "\n")
        print(json.dumps(command["command_mb_growth"]), f"wrote {path}")
        ok = all(r["identical"] and r["same_printed_fits"] and r["pieces"]["exit"] == 0 for r in command["runs"].values())
        return 0 if ok else 1
    if args.long_sizes:
        sizes = [int(x) for x in args.long_sizes.split(",")]
        before = args.before or (str(args.before_dir.resolve()) if args.before_dir else None)
        long = bench_long(sizes, before, bool(args.before))
        out = {"machine": describe(), "load_average_before": load_before, "load_average_after": os.getloadavg(),
               "before": args.before or (args.before_dir and "files of --before-dir"), **long}
        path = args.out or ROOT / "benchmarks" / "results" / "smooth_long.json"
        path.write_text(json.dumps(out, indent=2) + "\n")
        print(json.dumps(long["peak_rss_growth_mb"]), f"wrote {path}")
        return 0
    args.out = args.out or ROOT / "benchmarks" / "results" / "smooth.json"
    before = smooth_at(args.before) if args.before else smooth_from(args.before_dir) if args.before_dir else None
    layouts = bench_layouts(args.layout_rows, args.repeats, before)
    results = {} if args.skip_models else {m: bench_model(m, args.old_rows, tuple(args.sizes), args.repeats)
                                           for m in args.models}
    out = {"machine": describe(), "load_average_before": load_before, "load_average_after": os.getloadavg(),
           "layouts": {"before_revision": args.before or (args.before_dir and "files of --before-dir"), "rows": args.layout_rows,
                       **layouts},
           "tracks_per_table": 6, "models": results}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(out, indent=2))
    for m, r in results.items():
        rates = ", ".join(f"{k} rows {v['rows_per_s']:.0f}/s wall, {v['rows_per_cpu_s']:.0f}/s CPU "
                          f"(peak {v['peak_traced_bytes'] / v['rows']:.0f} B/row)" for k, v in r["new"].items())
        a = r["agreement"]
        print(f"{m}: old {r['old']['rows_per_cpu_s']:.1f} rows/s CPU; new {rates}; {r['speedup_vs_old_cpu']:.0f}x; "
              f"position diff {a['max_abs_diff_position']:.2g}, any column {a['max_abs_diff_any_column']:.2g} "
              f"({a['worst_column']}), other columns equal {a['other_columns_equal']}, fits equal {a['fits_equal']}")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
