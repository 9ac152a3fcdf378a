"""Damaged logs through every reading verb: each case ends in success with the right output, or in a
documented exit status with one line on stderr — never a traceback, an internal error, or exit 0
with a wrong result.

Small synthetic logs and fixed seeds: the same ~90 cases on every run, in a few seconds.
"""

from __future__ import annotations

import random
from pathlib import Path

import pytest
from mcap.reader import make_reader

from trackreplay.replay.cli.main import INTERNAL_ERROR, main

# Documented exit statuses (docs/exit_codes.md) a damaged input may end in.
DAMAGED_OK = {0, 1, 2, 3, 7}


def chunk_spans(path: Path) -> list[tuple[int, int]]:
    with open(path, "rb") as fh:
        summary = make_reader(fh).get_summary()
    return sorted((c.chunk_start_offset, c.chunk_start_offset + c.chunk_length) for c in summary.chunk_indexes)


def mutations(path: Path, seed: int = 0) -> list[tuple[str, bytes]]:
    """Truncations, single and multi-byte flips, a zeroed chunk: (name, bytes) pairs."""
    data = path.read_bytes()
    rng = random.Random(seed)
    out = [(f"cut{n}", data[:n]) for n in (0, 8, 9, 40, len(data) // 3, len(data) // 2, len(data) - 30, len(data) - 1)]
    for k in range(12):
        pos = rng.randrange(8, len(data))
        flipped = bytearray(data)
        flipped[pos] ^= 1 << rng.randrange(8)
        out.append((f"flip{k}@{pos}", bytes(flipped)))
    for k in range(4):
        pos = rng.randrange(8, len(data) - 8)
        burst = bytearray(data)
        burst[pos:pos + 8] = rng.randbytes(8)
        out.append((f"burst{k}@{pos}", bytes(burst)))
    start, end = chunk_spans(path)[len(chunk_spans(path)) // 2]
    zeroed = bytearray(data)
    zeroed[start:end] = bytes(end - start)
    out.append(("zeroed-chunk", bytes(zeroed)))
    return out


@pytest.fixture(scope="module")
def damaged(tmp_path_factory, flow_sim1: Path) -> list[tuple[str, Path]]:
    folder = tmp_path_factory.mktemp("damaged")
    cases = []
    for name, data in mutations(flow_sim1):
        path = folder / f"{name}.mcap"
        path.write_bytes(data)
        cases.append((name, path))
    return cases


def one_line(err: str) -> None:
    lines = [line for line in err.splitlines() if line.strip()]
    assert "Traceback" not in err
    assert lines and all(line.startswith(("trackreplay:", "warning:")) for line in lines), err


def test_info_never_fails_badly(damaged, capsys) -> None:
    for name, path in damaged:
        code = main(["info", str(path)])
        _, err = capsys.readouterr()
        assert code in DAMAGED_OK and code != INTERNAL_ERROR, (name, code, err)
        if code:
            one_line(err)


def test_recover_always_leaves_a_valid_log(damaged, tmp_path, capsys) -> None:
    for name, path in damaged:
        out = tmp_path / f"{name}.fixed.mcap"
        code = main(["recover", str(path), str(out)])
        _, err = capsys.readouterr()
        assert code in (0, 1, 2), (name, code, err)
        if out.exists():
            with open(out, "rb") as fh:
                assert make_reader(fh).get_summary() is not None, name
        else:
            one_line(err)  # not an MCAP file at all: nothing written, one sentence


def test_replay_is_right_or_says_so(damaged, flow_sim1, tmp_path, capsys) -> None:
    summary = tmp_path / "intact.json"
    assert main(["replay", str(flow_sim1), "--quiet", "--summary", str(summary)]) == 0
    import json

    intact = json.loads(summary.read_text())
    capsys.readouterr()
    for name, path in damaged:
        out = tmp_path / f"{name}.json"
        code = main(["replay", str(path), "--quiet", "--summary", str(out)])
        _, err = capsys.readouterr()
        assert code in DAMAGED_OK and code != INTERNAL_ERROR, (name, code, err)
        if code == 0:  # success must mean the same answer as the intact log
            got = json.loads(out.read_text())
            assert (got["digest"], got["frames"]) == (intact["digest"], intact["frames"]), (name, err)
        else:
            one_line(err)


def test_copying_verbs_never_pass_damage_on(damaged, flow_sim1, tmp_path, capsys) -> None:
    """`filter` and `annotate` copy a log record for record: a damaged one is refused (exit 3, naming
    `recover`) and nothing is written; `--in-place` leaves the damaged original as it was. An exit 0
    means the copy holds the intact log's images, byte for byte."""
    def images(path: Path) -> list[bytes]:
        with open(path, "rb") as fh:
            return [msg.data for _, ch, msg in make_reader(fh).iter_messages(log_time_order=True) if ch.topic == "/camera/image"]

    intact = images(flow_sim1)
    for name, path in damaged:
        for verb, out in (("filter", tmp_path / f"{name}.filtered.mcap"), ("annotate", tmp_path / f"{name}.marked.mcap")):
            args = [verb, str(path), str(out)] if verb == "filter" else \
                [verb, str(path), "--frame", "0", "--box", "10,10,8,8", "--out", str(out)]
            before = path.read_bytes()
            code = main(args)
            _, err = capsys.readouterr()
            assert code in DAMAGED_OK and code != INTERNAL_ERROR, (verb, name, code, err)
            if code == 0:
                assert images(out) == intact, (verb, name)
            else:
                one_line(err)
                assert not out.exists() and path.read_bytes() == before, (verb, name)
            if code == 3:
                assert "recover" in err, (verb, name, err)
        original = tmp_path / f"{name}.inplace.mcap"
        original.write_bytes(path.read_bytes())
        code = main(["annotate", str(original), "--frame", "0", "--box", "10,10,8,8", "--in-place"])
        capsys.readouterr()
        if code != 0:
            assert original.read_bytes() == path.read_bytes(), name
