"""Errors a user can cause and act on: each carries one sentence naming the file, topic or line."""


class TrackreplayError(Exception):
    """A user-facing failure; the CLI prints ``str(err)`` and exits with ``exit_code``."""

    exit_code = 2


class LogError(TrackreplayError):
    """A log cannot be read as asked (missing topic, truncated file, undecodable message)."""


class TruncatedLogError(LogError):
    """The log is truncated (it ends before its summary) or damaged (a chunk fails its CRC): readable
    up to, or around, the damage; `trackreplay recover` salvages it."""

    exit_code = 3


class SourceError(TrackreplayError):
    """An input to ``record`` (video, image folder, CSV, annotation file) is malformed."""


class OutputError(TrackreplayError):
    """An output cannot be written (no space left, no permission, a missing folder)."""

    exit_code = 5
