"""Issue 33, defect 8: a channel id declared twice with different schemas was replayed as the first
silently; it is now warned about and counted (info, the reader, replay)."""

from pathlib import Path

from mcap.reader import make_reader
from mcap.records import Channel
from mcap.writer import Writer

from trackreplay.replay.cli.main import main
from trackreplay.replay.log.info import format_info, log_info
from trackreplay.replay.log.reader import LogReader

GOLDEN = Path(__file__).resolve().parents[2] / "golden" / "flow-sim1-24f.mcap"


def redeclared(dst: Path) -> tuple[Path, int]:
    """The golden flow log with its image channel declared again, half-way, with another schema."""
    with open(GOLDEN, "rb") as fh, open(dst, "wb") as out:
        reader = make_reader(fh)
        writer = Writer(out, chunk_size=64 * 1024)
        writer.start(profile=reader.get_header().profile, library="test")
        schemas: dict[int, int] = {}
        channels: dict[int, int] = {}
        other = writer.register_schema("test.Other", "jsonschema", b"{}")
        images = 0
        for schema, channel, msg in reader.iter_messages(log_time_order=False):
            if schema.id not in schemas:
                schemas[schema.id] = writer.register_schema(schema.name, schema.encoding, schema.data)
            if channel.id not in channels:
                channels[channel.id] = writer.register_channel(channel.topic, channel.message_encoding, schemas[schema.id])
            if channel.topic == "/camera/image":
                images += 1
                if images == 12:  # a second declaration of the same id, as a buggy writer leaves it
                    cid = channels[channel.id]
                    writer._Writer__chunk_builder.add_channel(Channel(cid, "/camera/image", "json", {}, other))
                    conflicted = cid
            writer.add_message(channels[channel.id], msg.log_time, msg.data, msg.publish_time, msg.sequence)
        writer.finish()
    return dst, conflicted


def test_info_warns_and_counts_a_redeclared_channel(tmp_path: Path) -> None:
    log, cid = redeclared(tmp_path / "twice.mcap")
    info = log_info(log)
    assert len(info["channel_conflicts"]) == 1 and f"channel {cid} is declared twice" in info["channel_conflicts"][0]
    assert "WARNING: 1 channel declaration(s) contradict an earlier one" in format_info(info)


def test_the_reader_and_replay_warn_about_it(tmp_path: Path, capsys) -> None:
    log, cid = redeclared(tmp_path / "twice.mcap")
    reader = LogReader(log)
    assert len(list(reader.messages(["/camera/image"]))) == 24
    assert list(reader.channel_conflicts) == [cid]
    assert main(["replay", str(log), "--tracker", "flow"]) == 0
    err = capsys.readouterr().err
    assert f"warning: {log}: channel {cid} is declared twice with different contents" in err


def test_a_clean_log_has_no_conflicts() -> None:
    reader = LogReader(GOLDEN)
    list(reader.messages(["/camera/image"]))
    assert reader.channel_conflicts == {} and log_info(GOLDEN)["channel_conflicts"] == []
