"""Topics chosen by name, glob or regular expression (``filter``, ``cat``).

A pattern is an exact topic, a glob (``camera/*``, ``/stereo/*/image``: ``*`` ``?`` ``[…]``) or,
prefixed ``re:``, a regular expression that must match the whole topic (``re:/stereo/(left|right)/.*``).
A pattern without a leading ``/`` also matches the topic without its own (``camera/*`` matches
``/camera/image``), as topics are usually written both ways. A pattern that matches no topic is an
error naming it and the topics present (a typo would otherwise select nothing, or everything).
"""

from __future__ import annotations

import fnmatch
import re
from collections.abc import Iterable, Sequence

from trackreplay.schemas.errors import LogError, TrackreplayError

GLOB_CHARS = "*?["


def topic_matcher(pattern: str):
    """A predicate topic -> bool for one pattern; a bad regular expression is refused in one sentence."""
    if pattern.startswith("re:"):
        try:
            rx = re.compile(pattern[3:])
        except re.error as err:
            raise TrackreplayError(f"topic pattern {pattern!r} is not a valid regular expression ({err})") from None
        return lambda topic: rx.fullmatch(topic) is not None or (not pattern[3:].startswith("/") and
                                                                  rx.fullmatch(topic.lstrip("/")) is not None)
    if any(c in pattern for c in GLOB_CHARS):
        bare = not pattern.startswith("/")
        return lambda topic: fnmatch.fnmatchcase(topic, pattern) or (bare and fnmatch.fnmatchcase(topic.lstrip("/"), pattern))
    return lambda topic: topic == pattern or (not pattern.startswith("/") and topic == "/" + pattern)


def select_topics(present: Iterable[str], include: Sequence[str] = (), exclude: Sequence[str] = (),
                  source: str = "the log") -> list[str]:
    """The ``present`` topics that match an ``include`` pattern (every topic when there is none) and no
    ``exclude`` pattern, sorted."""
    topics = sorted(set(present))
    listed = ", ".join(topics) or "none"
    chosen: set[str] = set()
    for pattern in include:
        hits = {t for t in topics if topic_matcher(pattern)(t)}
        if not hits:
            raise LogError(f"{source} has no topic {_what(pattern)}; topics present: {listed}")
        chosen |= hits
    if not include:
        chosen = set(topics)
    for pattern in exclude:
        hits = {t for t in topics if topic_matcher(pattern)(t)}
        if not hits:
            raise LogError(f"{source} has no topic {_what(pattern)} to exclude; topics present: {listed}")
        chosen -= hits
    if not chosen:
        raise LogError(f"{source}: no topic is left once {', '.join(map(repr, exclude))} are excluded")
    return sorted(chosen)


def _what(pattern: str) -> str:
    exact = not pattern.startswith("re:") and not any(c in pattern for c in GLOB_CHARS)
    return pattern if exact else f"matching {pattern!r}"
