"""replay --connect streams the replay to a running Rerun viewer/server (here: `rerun --save`, headless)."""

from __future__ import annotations

import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
import rerun.chunk as rc

from trackreplay.replay.cli.main import main

RERUN = Path(sys.executable).with_name("rerun")


def _rerun_binary() -> Path:
    """The viewer binary the ``rerun`` script starts (the script forwards no signal to it)."""
    import rerun_cli

    return Path(rerun_cli.__file__).parent / "rerun"


def _default_sigint() -> None:
    """In the server's process: Ctrl-C as by default. A process started while its parent ignores SIGINT
    ignores it too, and the server then never stops: twice in fresh-clone runs of the whole suite the
    server outlived its Ctrl-C, as it does when this test runs in a process that ignores SIGINT (what made
    the suite's process ignore it was not found)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.skipif(not RERUN.exists(), reason="the rerun CLI of rerun-sdk is not installed beside this Python")
def test_connect_streams_every_frame_to_a_running_server(short_sim: Path, tmp_path: Path) -> None:
    port = free_port()
    saved = tmp_path / "live.rrd"
    server = subprocess.Popen([str(_rerun_binary()), "--port", str(port), "--save", str(saved)], preexec_fn=_default_sigint,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 30
        while True:  # wait until it listens
            try:
                socket.create_connection(("127.0.0.1", port), timeout=0.5).close()
                break
            except OSError:
                assert time.monotonic() < deadline, "rerun never listened"
                time.sleep(0.1)
        rrd = tmp_path / "also.rrd"
        url = f"rerun+http://127.0.0.1:{port}/proxy"
        assert main(["replay", str(short_sim), "--quiet", "--connect", url, "--rrd", str(rrd)]) == 0
        time.sleep(1.0)
    finally:
        server.send_signal(signal.SIGINT)  # rerun finishes the .rrd it saves on Ctrl-C
        try:
            server.wait(timeout=60)
        except subprocess.TimeoutExpired:
            server.kill()
            raise
    live = {str(c.entity_path) for c in rc.RrdReader(str(saved)).stream()}
    local = {str(c.entity_path) for c in rc.RrdReader(str(rrd)).stream()}
    assert "/camera/image" in live and live >= local - {"/__properties"}
