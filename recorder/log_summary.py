"""What an MCAP log holds, from its summary section, with one-sentence errors.

For the recorder's own edits of existing logs (``annotate``); the replay reader makes the same
checks with the same messages. A file that is missing, not MCAP, or cut short (no footer) is
reported as such, the last with the ``recover`` command to run.
"""

from __future__ import annotations

from pathlib import Path

from mcap.exceptions import McapError
from mcap.reader import make_reader
from mcap.summary import Summary

from trackreplay.schemas.errors import LogError, TruncatedLogError

MCAP_MAGIC = b"\x89MCAP0\r\n"


def truncation_hint(path: Path) -> str:
    return (f"{path} is truncated or corrupt (no valid MCAP footer); "
            f"run `trackreplay recover {path} FIXED.mcap` to salvage every complete chunk")


def log_file(path: str | Path) -> Path:
    """``path`` itself, or the one ``.mcap`` file inside a folder (a ROS 2 bag folder: metadata.yaml
    beside the bag's .mcap)."""
    path = Path(path)
    if path.is_dir():
        found = sorted(path.glob("*.mcap"))
        if len(found) == 1:
            return found[0]
        names = (": " + ", ".join(p.name for p in found)) if found else ""
        raise LogError(f"{path} is a folder with {len(found)} .mcap files{names}; give the log file itself")
    if not path.is_file():
        raise LogError(f"{path} does not exist or is not a file")
    return path


def read_summary(path: str | Path) -> Summary:
    """The log's summary (channels, schemas, statistics); raises ``LogError``/``TruncatedLogError``."""
    path = log_file(path)
    with open(path, "rb") as fh:
        head = fh.read(len(MCAP_MAGIC))
        fh.seek(0, 2)
        fh.seek(max(0, fh.tell() - len(MCAP_MAGIC)))
        tail = fh.read(len(MCAP_MAGIC))
    if head != MCAP_MAGIC:
        raise LogError(f"{path} is not an MCAP file (bad magic bytes)")
    if tail != MCAP_MAGIC:
        raise TruncatedLogError(truncation_hint(path))
    try:
        with open(path, "rb") as fh:
            summary = make_reader(fh).get_summary()
    except McapError as err:
        raise TruncatedLogError(truncation_hint(path) + f" ({type(err).__name__})") from None
    if summary is None:  # a streamed log (no summary section) is read by a linear scan
        from trackreplay.recorder.mcap_scan import RecordDamage
        from trackreplay.recorder.mcap_summary import streamed_summary

        try:
            summary = streamed_summary(path)
        except RecordDamage as bad:
            raise TruncatedLogError(f"{truncation_hint(path)} ({bad})") from None
    if summary is None:
        raise TruncatedLogError(truncation_hint(path))
    return summary


def topic_counts(summary: Summary) -> dict[str, int]:
    """Messages per topic (channels of the same topic added up)."""
    counts = summary.statistics.channel_message_counts if summary.statistics else {}
    out: dict[str, int] = {}
    for cid in sorted(summary.channels):
        topic = summary.channels[cid].topic
        out[topic] = out.get(topic, 0) + counts.get(cid, 0)
    return out


def require_topic(path: str | Path, summary: Summary, topic: str) -> None:
    """Raise a one-sentence ``LogError`` listing the topics present when ``topic`` is absent."""
    present = topic_counts(summary)
    if topic not in present:
        raise LogError(f"{path} has no topic {topic}; topics present: {', '.join(sorted(present)) or 'none'}")
