"""A log's messages as JSON-ready records (``trackreplay cat``): log time, topic, schema, the
message's index on its topic, and its decoded fields.

Protobuf, ROS 2 CDR and JSON messages become plain dicts and lists. Binary fields (an image's bytes,
a point cloud's buffer, a ROS ``uint8[]``, a JSON message's base64 ``data`` over 256 characters) over 64
bytes are not printed: each becomes ``{"size": bytes}`` with, for
a PNG or JPEG, the ``shape`` ``[height, width]`` its header gives (a raw image's width, height and
encoding are fields of its own).
"""

from __future__ import annotations

import base64
import math
from collections.abc import Iterator
from typing import Any

import numpy as np
from google.protobuf.message import Message as ProtoMessage

from trackreplay.replay.log.decode import encoded_size
from trackreplay.replay.log.reader import LogMessage, LogReader

MAX_DEPTH = 64  # nesting deeper than this is not a message anyone wrote


SHORT_BYTES = 64  # byte fields up to this long are printed as numbers (a flag array, not a picture)


def _blob(data: bytes) -> dict[str, Any] | list[int]:
    if len(data) <= SHORT_BYTES:
        return list(data)
    out: dict[str, Any] = {"size": len(data)}
    size = encoded_size(data[:65536])
    if size is not None:
        out["shape"] = [size[1], size[0]]
    return out


def to_json(value: Any, depth: int = 0) -> Any:
    """``value`` (a decoded message or one of its fields) as JSON-ready data."""
    if depth > MAX_DEPTH:
        return "..."
    if isinstance(value, ProtoMessage):
        return {f.name: to_json(getattr(value, f.name), depth + 1) for f in value.DESCRIPTOR.fields}
    if isinstance(value, (bytes, bytearray, memoryview)):
        return _blob(bytes(value))
    if isinstance(value, np.ndarray):
        return _blob(value.tobytes()) if value.dtype == np.uint8 else to_json(value.tolist(), depth + 1)
    if isinstance(value, dict):
        if isinstance(value.get("data"), str) and len(value["data"]) > 256:  # a JSON message's bytes, as base64
            value = {**value, "data": _base64_blob(value["data"])}
        return {str(k): to_json(v, depth + 1) for k, v in value.items()}
    if isinstance(value, float):
        return value if math.isfinite(value) else str(value)  # strict JSON has no nan or infinity
    if isinstance(value, (str, int, bool)) or value is None:
        return value
    if isinstance(value, (list, tuple)) or hasattr(value, "__len__") and hasattr(value, "__getitem__"):
        items = list(value)
        if len(items) > SHORT_BYTES and all(isinstance(v, int) and 0 <= v < 256 for v in items):  # a ROS uint8[] as a list
            return _blob(bytes(items))
        return [to_json(v, depth + 1) for v in items]
    names = _field_names(value)
    if names:  # ROS 2 messages (mcap_ros2's dynamic types: fields in __slots__)
        return {k: to_json(getattr(value, k), depth + 1) for k in names}
    return str(value)


def _field_names(value: Any) -> list[str]:
    names = [n for cls in type(value).__mro__ for n in getattr(cls, "__slots__", ()) if not n.startswith("_")]
    names += [n for n in getattr(value, "__dict__", {}) if not n.startswith("_") and n not in names]
    return [n for n in names if hasattr(value, n)]


def _base64_blob(text: str) -> Any:
    try:
        return _blob(base64.b64decode(text, validate=True))
    except ValueError:
        return text


def message_record(item: LogMessage) -> dict[str, Any]:
    """One message as a record: ``log_time_ns, topic, schema, index, message``."""
    return {"log_time_ns": item.log_time, "topic": item.topic, "schema": item.schema, "index": item.index,
            "message": to_json(item.decode())}


def records(reader: LogReader, topics: list[str], limit: int | None = None,
            lost: list[LogMessage] | None = None) -> Iterator[dict[str, Any]]:
    """The messages of ``topics`` in log-time order, at most ``limit``; those of damaged chunks are
    appended to ``lost`` instead."""
    if limit == 0:
        return
    n = 0
    for item in reader.messages(topics):
        if item.lost is not None:
            if lost is not None:
                lost.append(item)
            continue
        yield message_record(item)
        n += 1
        if limit is not None and n >= limit:
            return
