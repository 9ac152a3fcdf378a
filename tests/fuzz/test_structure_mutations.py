"""Valid-but-unusual log structures (issue 33) through info, replay and recover: a log streamed
without a summary section, log times at and beyond 2**63 (a negative time written as unsigned), a
channel id declared twice with different schemas. Each is read right, or refused in one documented
sentence — never an internal error.

One short synthetic log rewritten record by record; the same cases on every run, a few seconds.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from mcap.reader import make_reader
from mcap.records import Channel
from mcap.writer import IndexType, Writer

from trackreplay.replay.cli.main import INTERNAL_ERROR, main


def rewrite(src: Path, dst: Path, *, streamed: bool = False, chunked: bool = True, time: int | None = None,
            redeclare: bool = False) -> Path:
    """``src`` written again: without summary or indexes (``streamed``), with the sixth message at log
    time ``time``, or with its image channel declared a second time with another schema (``redeclare``)."""
    options = dict(index_types=IndexType.NONE, repeat_channels=False, repeat_schemas=False, use_statistics=False,
                   use_summary_offsets=False) if streamed else {}
    with open(src, "rb") as fh, open(dst, "wb") as out:
        reader = make_reader(fh)
        writer = Writer(out, use_chunking=chunked, chunk_size=64 * 1024, **options)
        writer.start(profile=reader.get_header().profile, library="fuzz")
        ids: dict[tuple[str, int], int] = {}
        for k, (schema, channel, msg) in enumerate(reader.iter_messages(log_time_order=False)):
            if ("s", schema.id) not in ids:
                ids["s", schema.id] = writer.register_schema(schema.name, schema.encoding, schema.data)
            if ("c", channel.id) not in ids:
                ids["c", channel.id] = writer.register_channel(channel.topic, channel.message_encoding, ids["s", schema.id])
            if redeclare and k == 20:
                other = writer.register_schema("fuzz.Other", "jsonschema", b"{}")
                writer._Writer__chunk_builder.add_channel(Channel(ids["c", channel.id], channel.topic, "json", {}, other))
            t = time if time is not None and k == 5 else msg.log_time
            writer.add_message(ids["c", channel.id], t, msg.data, t, msg.sequence)
        writer.finish()
    return dst


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
