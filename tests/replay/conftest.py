"""Fixtures of the replay tests."""

from __future__ import annotations

import json
import os
import subprocess
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest


@pytest.fixture
def reference_side() -> Callable[..., Any]:
    """Runs a reference implementation that cannot live in our venv (motmetrics needs numpy < 2,
    TrackEval its own pins) in its own venv: ``reference_side(env_var, default_python, script, *args)``
    runs ``script`` (Python source printing JSON) with the interpreter named by ``env_var`` (else
    ``default_python``) and returns the parsed output. Skips when that interpreter is missing; a
    failing script fails the test (the venv was given, so a crash is a finding, not an absence)."""

    def run(env_var: str, default_python: str, script: str, *args: str | Path) -> Any:
        python = Path(os.environ.get(env_var, default_python))
        if not python.is_file():
            pytest.skip(f"no reference venv at {python} (set {env_var})")
        out = subprocess.run([str(python), "-c", script, *map(str, args)], capture_output=True, text=True, timeout=120)
        if out.returncode:
            pytest.fail(f"the reference side ({python}) failed: {out.stderr.strip().splitlines()[-1:]}")
        return json.loads(out.stdout)

    return run


@pytest.fixture
def disk_full_at(monkeypatch: pytest.MonkeyPatch) -> Callable[[str], None]:
    """``disk_full_at(name)``: the disk fills up (ENOSPC) as a file called ``name`` is completed, i.e. when
    its ``name.partial`` is synced; a writer that wrote ``name`` directly never syncs and so never fails."""
    import errno

    real = os.fsync

    def fail_for(name: str) -> None:
        def fsync(fd: int) -> None:
            if os.readlink(f"/proc/self/fd/{fd}").endswith(f"/{name}.partial"):
                raise OSError(errno.ENOSPC, "No space left on device")
            real(fd)

        monkeypatch.setattr(os, "fsync", fsync)

    return fail_for


@pytest.fixture
def benchmark_module() -> Callable[[str], Any]:
    """Loads ``benchmarks/NAME.py`` by path (the benchmarks are scripts, not an installed package), for the
    tests that check a benchmark's synthetic inputs or its reference implementation:
    ``benchmark_module("bench_smooth")``."""
    import importlib.util
    import sys

    def load(name: str) -> Any:
        path = Path(__file__).resolve().parents[2] / "benchmarks" / f"{name}.py"
        spec = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module  # (dataclasses in the module look themselves up there)
        spec.loader.exec_module(module)
        return module

    return load
