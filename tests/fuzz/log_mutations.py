"""One log rewritten record by record with a structural mutation: streamed without a summary section,
one message moved to another log time, or a channel id declared a second time with another schema.

Shared by ``tests/fuzz/test_structure_mutations.py``, ``tests/replay/log/test_log_time_range.py`` and
``docs/reliability.py`` (they load it by path: tests are not a package).
"""

from __future__ import annotations

from pathlib import Path

from mcap.reader import make_reader
from mcap.records import Channel
from mcap.writer import IndexType, Writer


def rewrite(src: Path, dst: Path, *, streamed: bool = False, chunked: bool = True, chunk_size: int | None = None,
            time: int | None = None, at: int = 5, redeclare: bool = False, library: str = "fuzz") -> Path:
    """``src`` written again to ``dst``: without summary or indexes (``streamed``), with message ``at``
    (file order) at log time ``time``, or with its image channel declared a second time with another
    schema at the 21st message (``redeclare``)."""
    options = dict(index_types=IndexType.NONE, repeat_channels=False, repeat_schemas=False, use_statistics=False,
                   use_summary_offsets=False) if streamed else {}
    if chunk_size is not None:
        options["chunk_size"] = chunk_size
    with open(src, "rb") as fh, open(dst, "wb") as out:
        reader = make_reader(fh)
        writer = Writer(out, use_chunking=chunked, **options)
        writer.start(profile=reader.get_header().profile, library=library)
        ids: dict[tuple[str, int], int] = {}
        for k, (schema, channel, msg) in enumerate(reader.iter_messages(log_time_order=False)):
            if ("s", schema.id) not in ids:
                ids["s", schema.id] = writer.register_schema(schema.name, schema.encoding, schema.data)
            if ("c", channel.id) not in ids:
                ids["c", channel.id] = writer.register_channel(channel.topic, channel.message_encoding, ids["s", schema.id])
            if redeclare and k == 20:
                other = writer.register_schema(f"{library}.Other", "jsonschema", b"{}")
                writer._Writer__chunk_builder.add_channel(Channel(ids["c", channel.id], channel.topic, "json", {}, other))
            t = time if time is not None and k == at else msg.log_time
            writer.add_message(ids["c", channel.id], t, msg.data, t, msg.sequence)
        writer.finish()
    return dst

