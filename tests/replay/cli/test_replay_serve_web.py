"""`replay --serve-web`: Rerun's web viewer and gRPC proxy served from a headless machine (no browser here)."""

import os
import signal
import socket
import subprocess
import sys
import time
import urllib.request
import warnings
from pathlib import Path

import pytest
import rerun.chunk as rc

ROOT = Path(__file__).resolve().parents[3]
GOLDEN_FLOW = ROOT / "tests" / "golden" / "flow-sim1-24f.mcap"


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _answers(port: int) -> bool:
    try:
        with socket.create_connection(("127.0.0.1", port), timeout=1.0):
            return True
    except OSError:
        return False


def _wait_for(proc: subprocess.Popen, text: str, seconds: float) -> list[str]:
    """stderr lines up to the first holding ``text``."""
    lines, deadline = [], time.monotonic() + seconds
    while time.monotonic() < deadline:
        line = proc.stderr.readline()
        if not line and proc.poll() is not None:
            break
        lines.append(line)
        if text in line:
            return lines
    raise AssertionError(f"no {text!r} from the replay: {''.join(lines)}")


def _streamed_entities(url: str, tmp_path: Path) -> set[str]:
    """The entity paths a gRPC client (the `rerun` CLI saving to a file) receives from ``url``."""
    cli = Path(sys.executable).with_name("rerun")
    if not cli.is_file():
        pytest.skip("the rerun CLI is not beside the interpreter")
    env = {**os.environ, **{k: str(tmp_path / "xdg") for k in ("XDG_CONFIG_HOME", "XDG_DATA_HOME", "XDG_CACHE_HOME")}}
    saved = tmp_path / "client.rrd"
    client = subprocess.Popen([str(cli), url, "--save", str(saved)], env=env, stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL)
    try:
        deadline, seen = time.monotonic() + 30, set()
        while time.monotonic() < deadline and "/camera/image" not in seen:
            time.sleep(0.5)
            try:
                with warnings.catch_warnings():  # the client's file has no footer yet, and two stores
                    warnings.simplefilter("ignore")
                    reader = rc.RrdReader(str(saved))
                    seen = {str(c.entity_path) for s in reader.recordings() for c in reader.stream(store=s)}
            except Exception:  # not written yet, or mid-write
                continue
        return seen
    finally:
        client.terminate()
        client.wait(timeout=30)


@pytest.mark.slow  # 4 s: the default suite took 4 min 13 s on a fresh clone (budget 4 min); CI runs -m slow
def test_serve_web_answers_streams_the_replay_and_stops_at_ctrl_c(tmp_path: Path) -> None:
    web, grpc = _free_port(), _free_port()
    cmd = [sys.executable, "-m", "trackreplay", "replay", str(GOLDEN_FLOW), "--tracker", "flow", "--end", "0.1",
           "--quiet", "--serve-web", "--web-port", str(web), "--grpc-port", str(grpc), "--serve-seconds", "120"]
    proc = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        lines = _wait_for(proc, "serving the replay at", 120)
        url = f"http://127.0.0.1:{web}/?url=rerun%2Bhttp%3A%2F%2F127.0.0.1%3A{grpc}%2Fproxy"
        assert url in lines[0] and url in lines[-1]
        with urllib.request.urlopen(url, timeout=10) as page:
            assert page.status == 200 and b"<html" in page.read().lower()
        assert _answers(grpc)
        entities = _streamed_entities(f"rerun+http://127.0.0.1:{grpc}/proxy", tmp_path)
        assert {"/camera/image", "/tracks/1", "/truth/boxes"} <= entities
        proc.send_signal(signal.SIGINT)  # Ctrl-C: stop serving, no error
        out, err = proc.communicate(timeout=60)
        assert proc.returncode == 0, err
        assert "flow: 3 frames, digest" in out
        assert not _answers(web) and not _answers(grpc)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()


def test_serve_web_refuses_a_taken_port_and_connect(tmp_path: Path) -> None:
    from trackreplay.replay.cli.main import main

    with socket.socket() as taken:
        taken.bind(("0.0.0.0", 0))
        taken.listen()
        port = taken.getsockname()[1]
        assert main(["replay", str(GOLDEN_FLOW), "--tracker", "flow", "--serve-web", "--grpc-port", str(port),
                     "--web-port", str(_free_port()), "--serve-seconds", "0"]) == 5
    assert main(["replay", str(GOLDEN_FLOW), "--tracker", "flow", "--serve-web", "--connect"]) == 2
