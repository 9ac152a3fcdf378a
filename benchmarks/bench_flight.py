"""`flight` on long logs (issue 33: ≥ 20k rows/s and flat memory, the bar `smooth` has).

`trackreplay flight` fits one shot (the track with the most measured frames) and then exports the fitted
flight at **every frame of the log** (``flight_rows``: positions, their 1-σ from 15 perturbed flights, the
image position in each frame's camera). The fit's cost is the shot's (its simulations); the export's is the
log's. No long golf log exists, so:

- ``fit``: the golden tee shot (tests/golden: 60 frames, its 17 measured ones with lines of sight) fitted
  by ``fit_flight``, CPU seconds, and the share spent in the RK4 integrator ``_fly`` (its calls timed);
- ``rows``: that fit exported by ``flight_rows`` over a log of 1k, 20k and 200k frames (the golden log's
  60 frames, then frames at 30 fps whose camera is the last frame's), each in a fresh process: peak RSS
  (VmHWM) above the process's RSS with the fit loaded, CPU seconds, rows per CPU-second; with ``--before
  REV`` the same for ``replay/analysis/flight.py`` at git revision REV, and the two tables compared (the
  same to the bit).
- ``context``: ``log_context`` (frame times and the posed camera of every frame, which ``flight`` and
  ``smooth`` read from the log) on a PTZ log of 1k, 20k and 200k frames (a 32x32 PNG a frame, PTZ encoders
  each frame, the golden tee shot's lens table), fresh processes, peak RSS above the process's base; with
  ``--before REV`` the same for ``replay/analysis/smooth.py`` at REV, and the cameras compared;
- ``--numba DIR``: the fit again with ``_fly`` compiled by numba (DIR: a folder where numba is
  installed, e.g. ``pip install --target DIR numba``; not a dependency of the project), its
  compile time, and whether the fitted parameters and covariance are the same to the bit.

Usage: python benchmarks/bench_flight.py [--frames 1000,20000,200000] [--before REV] [--numba DIR]
Writes benchmarks/results/flight.json.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import pickle
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks.machine import describe  # noqa: E402

GOLDEN = ROOT / "tests" / "golden"


def golden_fit():
    """The golden tee shot: its observations, frame times and cameras (read from the log)."""
    from trackreplay.replay.analysis import flight
    from trackreplay.replay.analysis.smooth import log_context
    from trackreplay.replay.core.export import read_trajectory

    times, cameras = log_context(GOLDEN / "golf-teeshot-640x360.mcap")
    traj = read_trajectory(GOLDEN / "golf.trajectory.parquet")
    return flight.observations(traj, cameras, what="the golden tee shot"), times, cameras, traj.height


def bench_fit(module=None) -> dict:
    """CPU seconds of ``fit_flight`` on the golden tee shot and the share in ``_fly``."""
    from trackreplay.replay.analysis import flight

    module = module or flight
    obs, times, cameras, rows = golden_fit()
    spent, calls = [0.0], [0]
    fly = module._fly

    def timed_fly(*args):
        c0 = time.process_time()
        try:
            return fly(*args)
        finally:
            spent[0] += time.process_time() - c0
            calls[0] += 1

    module._flight.cache_clear()
    c0 = time.process_time()
    fit = module.fit_flight(obs, module.FlightConfig(), 30.0)
    plain = time.process_time() - c0
    module._fly = timed_fly
    module._flight.cache_clear()
    try:
        module.fit_flight(obs, module.FlightConfig(), 30.0)
    finally:
        module._fly = fly
    return {"rows": rows, "observations": int(obs.t.size), "cpu_seconds": round(plain, 3),
            "fly_calls": calls[0], "fly_share_of_cpu": round(spent[0] / max(plain, 1e-9), 3)}, fit, times, cameras


ROWS = """
import pickle, sys, time
sys.path.insert(0, {root!r})
sys.argv = ["bench_flight"]
from benchmarks import bench_flight as b
from trackreplay.replay.analysis import flight
fit, times, cameras = pickle.load(open({fit!r}, "rb"))
module = b.flight_at({rev!r}) if {rev!r} else flight
if module is not flight:  # the fit as that module's FlightFit (its positions are what is compared)
    import dataclasses
    fit = module.FlightFit(**{{f.name: getattr(fit, f.name) for f in dataclasses.fields(fit)}})
n = {frames}
last = max(times)
frame_times = {{f: times[f] if f in times else times[last] + (f - last) * 33_333_333 for f in range(n)}}
cams = {{f: cameras.get(f, cameras[max(cameras)]) for f in range(n)}}
base = b.high_water_kib()
c0 = time.process_time()
rows = module.flight_rows(fit, frame_times, cams)
cpu = time.process_time() - c0
peak = b.high_water_kib()
rows.write_parquet({out!r})
print(base, peak, cpu)
"""


def high_water_kib() -> int:
    """This process's peak RSS (VmHWM, KiB): its own (ru_maxrss keeps the parent's across fork and exec)."""
    with open("/proc/self/status") as fh:
        return next(int(line.split()[1]) for line in fh if line.startswith("VmHWM:"))


def flight_at(rev: str, name: str = "flight"):
    """``replay/analysis/NAME.py`` at git revision ``rev``, imported as ``NAME_before``."""
    import importlib.util

    source = subprocess.run(["git", "-C", str(ROOT), "show", f"{rev}:replay/analysis/{name}.py"], check=True,
                            capture_output=True, text=True).stdout
    path = Path(tempfile.gettempdir()) / f"trackreplay_{name}_{os.getpid()}.py"
    path.write_text(source)
    try:
        spec = importlib.util.spec_from_file_location(f"{name}_before", path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[f"{name}_before"] = module
        spec.loader.exec_module(module)
    finally:
        path.unlink()
    return module


def write_ptz_log(path: Path, frames: int) -> None:
    """A PTZ log: the golden tee shot's lens table, a 32x32 PNG and a PTZ reading each frame (30 fps)."""
    import cv2

    from trackreplay.recorder.image_codec import compressed_image
    from trackreplay.recorder.writer import LogWriter
    from trackreplay.replay.log.reader import LogReader
    from trackreplay.schemas import topics as T
    from trackreplay.schemas.records import PtzReading

    lens = LogReader(GOLDEN / "golf-teeshot-640x360.mcap").first(T.PTZ_LENS_TABLE)
    picture = cv2.imencode(".png", np.full((32, 32), 90, np.uint8))[1].tobytes()
    with LogWriter(path, flush_every=300) as log:
        log.write(T.PTZ_LENS_TABLE, lens, 0)
        for i in range(frames):
            t_ns = i * 1_000_000_000 // 30
            reading = PtzReading(t_ns, 10.0 * math.sin(i / 300.0), -5.0 + math.cos(i / 500.0), 2000.0 + (i % 900), 3000.0)
            log.write(T.PTZ_ENCODERS, reading.to_pb(), t_ns)
            log.write(T.CAMERA_IMAGE, compressed_image(picture, "png", t_ns, "camera"), t_ns)


CONTEXT = """
import pickle, sys, time
sys.path.insert(0, {root!r})
sys.argv = ["bench_flight"]
from benchmarks import bench_flight as b
from trackreplay.replay.analysis import smooth
module = b.flight_at({rev!r}, "smooth") if {rev!r} else smooth
base = b.high_water_kib()
c0 = time.process_time()
times, cameras = module.log_context({log!r})
cpu = time.process_time() - c0
peak = b.high_water_kib()
sample = sorted(cameras)[::max(1, len(cameras) // 500)]
kept = [(f, cameras[f].pan, cameras[f].tilt, cameras[f].intrinsics, cameras[f].position.tolist()) for f in sample]
pickle.dump((times, kept), open({out!r}, "wb"))
print(base, peak, cpu, len(cameras))
"""


def bench_context(sizes: list[int], before: str | None) -> dict:
    out: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        for n in sizes:
            log = Path(tmp) / f"ptz-{n}.mcap"
            write_ptz_log(log, n)
            entry: dict = {"frames": n}
            for name, rev in (("after", ""), ("before", before)):
                if rev is None:
                    continue
                code = CONTEXT.format(root=str(ROOT), rev=rev, log=str(log), out=str(Path(tmp) / f"{name}-{n}.pkl"))
                got = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True,
                                     cwd=ROOT).stdout.split()
                base, peak, cpu, cams = int(got[-4]), int(got[-3]), float(got[-2]), int(got[-1])
                entry[name] = {"base_rss_kib": base, "peak_rss_kib": peak, "context_mb": round((peak - base) / 1024, 1),
                               "cpu_seconds": round(cpu, 2), "cameras": cams}
            if before is not None:
                entry["same_times_and_cameras"] = ((Path(tmp) / f"after-{n}.pkl").read_bytes()
                                                   == (Path(tmp) / f"before-{n}.pkl").read_bytes())
            out[str(n)] = entry
            print(json.dumps(entry), flush=True)
    growth = {k: round((out[str(sizes[-1])][k]["peak_rss_kib"] - out[str(sizes[0])][k]["peak_rss_kib"]) / 1024, 1)
              for k in ("after", "before") if k in out[str(sizes[0])]}
    return {"runs": out, "peak_rss_growth_mb": {"from_frames": sizes[0], "to_frames": sizes[-1], **growth}}


def bench_rows(fit, times, cameras, sizes: list[int], before: str | None) -> dict:
    import polars as pl

    out: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        saved = Path(tmp) / "fit.pkl"
        saved.write_bytes(pickle.dumps((fit, times, cameras)))
        for n in sizes:
            entry: dict = {"frames": n}
            for name, rev in (("after", ""), ("before", before)):
                if rev is None:
                    continue
                target = Path(tmp) / f"{name}-{n}.parquet"
                code = ROWS.format(root=str(ROOT), fit=str(saved), rev=rev, frames=n, out=str(target))
                got = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True,
                                     cwd=ROOT).stdout.split()
                base, peak, cpu = int(got[-3]), int(got[-2]), float(got[-1])
                entry[name] = {"base_rss_kib": base, "peak_rss_kib": peak, "rows_mb": round((peak - base) / 1024, 1),
                               "cpu_seconds": round(cpu, 2), "rows_per_cpu_s": round(n / cpu)}
            if before is not None:
                entry["identical"] = pl.read_parquet(Path(tmp) / f"after-{n}.parquet").equals(
                    pl.read_parquet(Path(tmp) / f"before-{n}.parquet"), null_equal=True)
            out[str(n)] = entry
            print(json.dumps(entry), flush=True)
    growth = {k: round((out[str(sizes[-1])][k]["peak_rss_kib"] - out[str(sizes[0])][k]["peak_rss_kib"]) / 1024, 1)
              for k in ("after", "before") if k in out[str(sizes[0])]}
    return {"runs": out, "peak_rss_growth_mb": {"from_frames": sizes[0], "to_frames": sizes[-1], **growth}}


NUMBA_KERNEL = '''
import math

from numba import njit


@njit(cache=False)
def kernel(px, py, pz, vx, vy, vz, t, h, kd, l0, l1, v0, wx, wy, wz, contact_z, t_end, G, rows):
    h2, h6 = 0.5 * h, h / 6.0
    n = 0
    rows[n, 0], rows[n, 1], rows[n, 2], rows[n, 3], rows[n, 4], rows[n, 5], rows[n, 6] = t, px, py, pz, vx, vy, vz
    n += 1
    while t < t_end:
        s = math.sqrt(vx * vx + vy * vy + vz * vz)
        L = (l0 + l1 * (v0 / (s if s > 1e-6 else 1e-6) - 1.0)) * s
        ds = kd * s
        ax1 = L * (wy * vz - wz * vy) - ds * vx
        ay1 = L * (wz * vx - wx * vz) - ds * vy
        az1 = L * (wx * vy - wy * vx) - ds * vz - G
        bx, by, bz = vx + h2 * ax1, vy + h2 * ay1, vz + h2 * az1
        s = math.sqrt(bx * bx + by * by + bz * bz)
        L = (l0 + l1 * (v0 / (s if s > 1e-6 else 1e-6) - 1.0)) * s
        ds = kd * s
        ax2 = L * (wy * bz - wz * by) - ds * bx
        ay2 = L * (wz * bx - wx * bz) - ds * by
        az2 = L * (wx * by - wy * bx) - ds * bz - G
        cx, cy, cz = vx + h2 * ax2, vy + h2 * ay2, vz + h2 * az2
        s = math.sqrt(cx * cx + cy * cy + cz * cz)
        L = (l0 + l1 * (v0 / (s if s > 1e-6 else 1e-6) - 1.0)) * s
        ds = kd * s
        ax3 = L * (wy * cz - wz * cy) - ds * cx
        ay3 = L * (wz * cx - wx * cz) - ds * cy
        az3 = L * (wx * cy - wy * cx) - ds * cz - G
        dx, dy, dz = vx + h * ax3, vy + h * ay3, vz + h * az3
        s = math.sqrt(dx * dx + dy * dy + dz * dz)
        L = (l0 + l1 * (v0 / (s if s > 1e-6 else 1e-6) - 1.0)) * s
        ds = kd * s
        ax4 = L * (wy * dz - wz * dy) - ds * dx
        ay4 = L * (wz * dx - wx * dz) - ds * dy
        az4 = L * (wx * dy - wy * dx) - ds * dz - G
        nx = px + h6 * (vx + 2 * bx + 2 * cx + dx)
        ny = py + h6 * (vy + 2 * by + 2 * cy + dy)
        nz = pz + h6 * (vz + 2 * bz + 2 * cz + dz)
        nvx = vx + h6 * (ax1 + 2 * ax2 + 2 * ax3 + ax4)
        nvy = vy + h6 * (ay1 + 2 * ay2 + 2 * ay3 + ay4)
        nvz = vz + h6 * (az1 + 2 * az2 + 2 * az3 + az4)
        if nz <= contact_z and nvz < 0:
            rows[n, 0], rows[n, 1], rows[n, 2], rows[n, 3], rows[n, 4], rows[n, 5] = nx, ny, nz, nvx, nvy, nvz
            return n, t, True
        t += h
        px, py, pz, vx, vy, vz = nx, ny, nz, nvx, nvy, nvz
        rows[n, 0], rows[n, 1], rows[n, 2], rows[n, 3], rows[n, 4], rows[n, 5], rows[n, 6] = t, px, py, pz, vx, vy, vz
        n += 1
    return n, t, False
'''


def bench_numba(folder: Path, plain_fit) -> dict:
    """The fit with ``_fly``'s loop compiled by numba (the same operations in the same order)."""
    import importlib.util

    sys.path.append(str(folder))
    source = Path(tempfile.mkdtemp()) / "flight_numba_kernel.py"
    source.write_text(NUMBA_KERNEL)
    spec = importlib.util.spec_from_file_location("flight_numba_kernel", source)
    compiled = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(compiled)
    kernel = compiled.kernel
    from trackreplay.replay.analysis import flight

    c0 = time.process_time()
    kernel(0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 0.0, 0.01, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.1, 9.81, np.empty((20, 7)))
    compile_s = time.process_time() - c0

    def fly(p, v, t, h, kd, kl, w, contact_z, t_end, phase, out):
        rows = np.empty((int(max(0.0, (t_end - t) / h)) + 3, 7))
        n, tc, hit = kernel(*p, *v, t, h, kd, *kl, *w, contact_z, t_end, flight.G, rows)
        out.extend((*r, phase) for r in rows[:n].tolist())
        last = rows[n - 1]
        if hit:
            return flight._contact(tuple(last[1:7]), tuple(rows[n, :6]), tc, h, contact_z, phase, out)
        return tuple(last[1:4]), tuple(last[4:7]), float(last[0]), False

    saved = flight._fly
    flight._fly = fly
    flight._flight.cache_clear()
    try:
        obs = golden_fit()[0]
        c0 = time.process_time()
        fit = flight.fit_flight(obs, flight.FlightConfig(), 30.0)
        cpu = time.process_time() - c0
    finally:
        flight._fly = saved
        flight._flight.cache_clear()
    import numba

    same = bool(np.array_equal(fit.theta, plain_fit.theta) and np.array_equal(fit.cov, plain_fit.cov))
    return {"numba": numba.__version__, "compile_cpu_seconds": round(compile_s, 3), "fit_cpu_seconds": round(cpu, 3),
            "theta_and_cov_identical": same}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--frames", default="1000,20000,200000", help="log lengths for flight_rows, comma-separated")
    ap.add_argument("--before", help="git revision whose replay/analysis/flight.py to compare with")
    ap.add_argument("--numba", type=Path, help="a folder with numba installed: time the fit with _fly compiled")
    ap.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results" / "flight.json")
    args = ap.parse_args()
    load = [round(x, 2) for x in os.getloadavg()]
    fit_result, fit, times, cameras = bench_fit()
    print("fit", json.dumps(fit_result), flush=True)
    result = {"machine": describe(), "load_average_before": load, "fit": fit_result,
              "rows": bench_rows(fit, times, cameras, [int(x) for x in args.frames.split(",")], args.before),
              "before": args.before}
    result["context"] = bench_context([int(x) for x in args.frames.split(",")], args.before)
    if args.numba:
        result["numba"] = bench_numba(args.numba, fit)
        print("numba", json.dumps(result["numba"]), flush=True)
    result["load_average_after"] = [round(x, 2) for x in os.getloadavg()]
    args.out.write_text(json.dumps(result, indent=2) + "\n")
    print(f"wrote {args.out}")
    same = [r.get("identical", True) for r in result["rows"]["runs"].values()]
    same += [r.get("same_times_and_cameras", True) for r in result["context"]["runs"].values()]
    return 0 if all(same) else 1


if __name__ == "__main__":
    sys.exit(main())
