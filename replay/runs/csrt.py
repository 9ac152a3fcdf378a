"""OpenCV's CSRT as the baseline row of a box case (``tracker = "csrt"`` in ``evaluate``'s table).

CSRT lives only in opencv-contrib-python-headless, which must never share a venv with trackreplay's
opencv-python-headless (both install the module ``cv2``). So it runs in its own venv, as the
colour-PF benchmark runs it (benchmarks/bench_colorpf.py): ``TRACKREPLAY_CSRT_VENV`` or
``$XDG_CACHE_HOME/trackreplay/csrt-venv`` (default ``~/.cache/…``), built there on first use
(``python -m venv`` + ``pip install opencv-contrib-python-headless numpy``). The frames a replay
would see, from the first mark on, are written as PNG files and :mod:`csrt_side` tracks them from
the first mark's box (re-marks are not given to CSRT). CSRT has no confidence: its rows carry none,
so its ECE is not applicable.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import cv2
import polars as pl

from trackreplay.recorder.annotate import Mark
from trackreplay.replay.log.frames import FrameTopics, iter_frames
from trackreplay.replay.log.reader import LogReader
from trackreplay.schemas.errors import TrackreplayError

CSRT_VENV_ENV = "TRACKREPLAY_CSRT_VENV"
SIDE = Path(__file__).with_name("csrt_side.py")
BUILD_TIMEOUT_S = 900


class BaselineUnavailable(TrackreplayError):
    """CSRT's venv cannot be found or built here (the evaluation runs on without the baseline)."""


def csrt_venv(environ: dict[str, str] | None = None) -> Path:
    env = os.environ if environ is None else environ
    if env.get(CSRT_VENV_ENV):
        return Path(env[CSRT_VENV_ENV])
    cache = Path(env.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return cache / "trackreplay" / "csrt-venv"


def _has_csrt(py: Path) -> bool:
    if not py.is_file():
        return False
    probe = subprocess.run([str(py), "-c", "import cv2; cv2.TrackerCSRT_create"], capture_output=True, timeout=120)
    return probe.returncode == 0


def ensure_csrt(venv: Path) -> Path:
    """The venv's python with CSRT, built on first use; :class:`BaselineUnavailable` (one sentence) if it cannot be."""
    py = venv / "bin" / "python"
    if _has_csrt(py):
        return py
    steps = ([sys.executable, "-m", "venv", str(venv)],
             [str(venv / "bin" / "pip"), "install", "-q", "opencv-contrib-python-headless", "numpy"])
    for step in steps:
        try:
            done = subprocess.run(step, capture_output=True, text=True, timeout=BUILD_TIMEOUT_S)
        except (OSError, subprocess.TimeoutExpired) as err:
            raise BaselineUnavailable(f"cannot build the CSRT venv in {venv} ({err})") from None
        if done.returncode != 0:
            last = (done.stderr.strip().splitlines() or ["no output"])[-1]
            raise BaselineUnavailable(f"cannot build the CSRT venv in {venv} ({' '.join(step[:3])}: {last})")
    if not _has_csrt(py):
        raise BaselineUnavailable(f"the venv {venv} has no cv2.TrackerCSRT_create (opencv-contrib-python-headless)")
    return py


def csrt_track(py: Path, log: Path, mark: Mark) -> tuple[pl.DataFrame, list[float]]:
    """CSRT over ``log``'s frames from ``mark``'s on: a trajectory table (centre and size, ``measured``
    or ``lost``, no confidence) and its step times (s)."""
    reader = LogReader(log)
    with tempfile.TemporaryDirectory(prefix="trackreplay-csrt-") as tmp:
        folder = Path(tmp) / "frames"
        folder.mkdir()
        indices, times_ns = [], []
        for frame in iter_frames(reader, FrameTopics.detect(reader, None, None)):
            if frame.index >= mark.frame:
                cv2.imwrite(str(folder / f"{frame.index:08d}.png"), frame.image)
                indices.append(frame.index)
                times_ns.append(frame.t_ns)
        if not indices or indices[0] != mark.frame:
            raise TrackreplayError(f"{log}: CSRT found no frame {mark.frame} to start from")
        out = Path(tmp) / "csrt.json"
        box = f"{mark.x},{mark.y},{mark.w},{mark.h}"
        done = subprocess.run([str(py), str(SIDE), str(folder), box, str(out)], capture_output=True, text=True)
        if done.returncode != 0:
            last = (done.stderr.strip().splitlines() or ["no output"])[-1]
            raise TrackreplayError(f"CSRT failed on {log} ({last})")
        result = json.loads(out.read_text())
    rows = []
    for index, t_ns, b in zip(indices, times_ns, result["boxes"]):
        rows.append({"tracker": "csrt", "track_id": 1, "frame": index, "t_ns": t_ns,
                     "x": b[0] + b[2] / 2 if b else None, "y": b[1] + b[3] / 2 if b else None,
                     "w": b[2] if b else None, "h": b[3] if b else None,
                     "status": "measured" if b else "lost", "confidence": None})
    schema = {"tracker": pl.String, "track_id": pl.Int64, "frame": pl.Int64, "t_ns": pl.Int64, "x": pl.Float64,
              "y": pl.Float64, "w": pl.Float64, "h": pl.Float64, "status": pl.String, "confidence": pl.Float64}
    return pl.DataFrame(rows, schema=schema), list(result["times"])
