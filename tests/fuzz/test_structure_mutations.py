"""Valid-but-unusual log structures (issue 33) through info, replay and recover: a log streamed
without a summary section, log times at and beyond 2**63 (a negative time written as unsigned), a
channel id declared twice with different schemas. Each is read right, or refused in one documented
sentence — never an internal error.

One short synthetic log rewritten record by record; the same cases on every run, a few seconds.
"""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest

from trackreplay.replay.cli.main import INTERNAL_ERROR, main


spec = importlib.util.spec_from_file_location("log_mutations", Path(__file__).with_name("log_mutations.py"))
MUTATIONS = importlib.util.module_from_spec(spec)
spec.loader.exec_module(MUTATIONS)


def rewrite(src: Path, dst: Path, **options) -> Path:
    return MUTATIONS.rewrite(src, dst, chunk_size=64 * 1024, **options)


CASES = {  # name: (rewrite options, exit statuses documented for it, the same digest as the source when 0)
    "streamed": (dict(streamed=True), {0}),
    "streamed-unchunked": (dict(streamed=True, chunked=False), {0}),
    "time-2^63-1": (dict(time=2**63 - 1), {0, 2}),
    "time-2^63": (dict(time=2**63), {2}),
    "time-negative-wrapped": (dict(time=2**64 - 1), {2}),
    "channel-declared-twice": (dict(redeclare=True), {0}),
}


@pytest.fixture(scope="module")
def mutated(tmp_path_factory, short_sim: Path) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("structure")
    return {name: rewrite(short_sim, folder / f"{name}.mcap", **options) for name, (options, _) in CASES.items()}


def _one_sentence(err: str) -> None:
    lines = [line for line in err.splitlines() if line.strip()]
    assert "Traceback" not in err and "internal error" not in err, err
    assert all(line.startswith(("trackreplay:", "warning:")) for line in lines), err


@pytest.mark.parametrize("name", CASES)
def test_info_replay_and_recover(name: str, mutated, short_sim: Path, tmp_path: Path, capsys) -> None:
    path, documented = mutated[name], CASES[name][1]
    assert main(["replay", str(short_sim), "--quiet", "--summary", str(tmp_path / "intact.json")]) == 0
    capsys.readouterr()
    for verb in (["info", str(path)], ["replay", str(path), "--quiet", "--summary", str(tmp_path / "s.json")],
                 ["recover", str(path), str(tmp_path / "fixed.mcap")]):
        code = main(verb)
        _, err = capsys.readouterr()
        assert code != INTERNAL_ERROR and (code in documented or verb[0] == "recover" and code in (0, 1)), \
            (name, verb[0], code, err)
        if code:
            _one_sentence(err)
    if 0 in documented and name != "time-2^63-1":
        got, intact = (json.loads((tmp_path / f).read_text()) for f in ("s.json", "intact.json"))
        assert got["digest"] == intact["digest"], name
        assert main(["recover", str(path), str(tmp_path / "fixed.mcap")]) == 0, name  # complete: not "partial"
        capsys.readouterr()
    if name == "channel-declared-twice":
        main(["info", str(path)])
        assert "declared twice" in capsys.readouterr().out
