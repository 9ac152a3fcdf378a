"""The Rerun stream of a replay: camera images on ``frame``/``log_time`` timelines, to an .rrd file.

Built only when `--rrd`, `--connect` or `--spawn` is given; without them no Rerun object is ever constructed.
"""

from __future__ import annotations

import hashlib
import os
import socket
import sys
from collections.abc import Callable
from datetime import timedelta
from pathlib import Path

import numpy as np
import polars as pl
import pyarrow as pa
import rerun as rr
import rerun.blueprint as rrb
import rerun.chunk as rc

from trackreplay.recorder.atomic import claim_partial
from trackreplay.schemas.errors import OutputError, TrackreplayError
from trackreplay.trackers.frame import Frame
from trackreplay.replay.views.truth import TruthStream, show_truth

VIEWER_PORT = 9876
VIEWER_URL = f"rerun+http://127.0.0.1:{VIEWER_PORT}/proxy"
RERUN_SCHEMES = ("rerun://", "rerun+http://", "rerun+https://")  # what the SDK's gRPC sink accepts

CAMERA = "camera/image"
RIGHT = "camera/right"


def _batcher() -> rr.ChunkBatcherConfig:
    # Chunk boundaries from data volume only (never from elapsed time), so two replays
    # write the same chunks.
    return rr.ChunkBatcherConfig(flush_tick=timedelta(days=1), flush_num_bytes=8 * 1024 * 1024, flush_num_rows=2**20)


FLUSH_BYTES = 32 * 1024 * 1024  # buffered rows are sent when they exceed this (memory stays flat in log length)
# One image path's rows are sent on their own when they exceed this: a few MB per chunk stay in the
# allocators' caches, where 32 MB chunks of camera frames were fresh memory (page faults) at every
# step, here and in Rerun's encoder (a 720x720 JPEG log: ~1 ms a frame of process CPU less).
IMAGE_FLUSH_BYTES = 4 * 1024 * 1024
# A batch's frames are built into rows this many at a time, as they come: it holds a few frames'
# intermediates, not a whole flush's (about 3x the rows built from them), and their arrays are
# still in cache.
BATCH_FRAMES = 32


class FrameLogger:
    """What a tracker's view logs through. Every ``log`` call is one row at the current frame, kept
    (as the Arrow arrays its archetypes produce) and sent in columns: at most ``FLUSH_BYTES`` are
    buffered, then each entity path's rows go out as one chunk per component set, paths in sorted
    order. That saves ``rr.log``'s fixed cost per call (about 85 µs in rerun-sdk 0.41, ten or more
    calls a frame) and makes the chunk order a function of the data alone: nothing passes through
    Rerun's time-driven batcher, so two replays write the same chunks in the same order without
    rewriting the file. ``scalar`` points are sent as columns at the end.

    A view can also keep a whole frame as one record (``batch``) and turn records into rows many
    frames at a time (``columns``, ``entity_rows``, ``image_rows``, ``scalar_rows``): the same rows
    and chunks, without a dozen calls a frame.
    """

    def __init__(self, rec: rr.RecordingStream, flush_bytes: int = FLUSH_BYTES,
                 image_flush_bytes: int | None = None) -> None:
        self.rec = rec
        self._frame = 0
        self._t_ns = 0
        self._series: dict[str, tuple[list[int], list[int], list[float]]] = {}
        self._series_rows: dict[tuple[str, ...], tuple[list[int], list[int], list[np.ndarray]]] = {}
        self._static: set[str] = set()
        self._rows: dict[str, list[tuple[int, int, list]]] = {}
        self._deferred: dict[str, dict[tuple, list[tuple[int, int, dict]]]] = {}
        self._templates: dict[tuple, list[tuple]] = {}
        self._batches: dict[Callable, list[tuple[int, int, object]]] = {}
        self._columns: dict[str, list[tuple]] = {}  # rows of many frames from batches (``columns``)
        self._buffered = 0
        self._image_bytes: dict[str, int] = {}
        self.flush_bytes = flush_bytes
        self.image_flush_bytes = IMAGE_FLUSH_BYTES if image_flush_bytes is None else image_flush_bytes
        self.live_tracks: set[int] = set()  # track ids drawn under tracks/ last frame (views.parts.tracks)

    def set_frame(self, index: int, t_ns: int) -> None:
        self._frame, self._t_ns = index, t_ns

    def log(self, path: str, *entities, static: bool = False) -> None:
        components = _components(entities)
        if static:
            self.flush()  # keep the order: what came before, then this
            _send(self.rec, path, {}, [components])
            return
        self._rows.setdefault(path, []).append((self._frame, self._t_ns, components))
        self._buffered += sum(a.get_total_buffer_size() for _, a in components)  # 25x cheaper than nbytes
        if self._buffered > self.flush_bytes:
            self.flush()

    def image(self, path: str, archetype: type, data: np.ndarray | bytes, **params) -> None:
        """``archetype(data, **params)`` (``rr.Image``, ``rr.SegmentationImage``; ``rr.EncodedImage``
        with ``data`` the encoded bytes) at ``path``, built once per shape and parameters: later
        frames reuse that row's format and parameters and bring only their pixels (a 720p JPEG's
        ``EncodedImage`` costs ~140 µs to build, its pixels as an Arrow list ~6 µs).
        """
        raw = isinstance(data, (bytes, bytearray, memoryview))
        if not raw and (not isinstance(data, np.ndarray) or data.dtype != np.uint8):
            entity = archetype(contents=data, **params) if archetype is rr.EncodedImage else archetype(data, **params)
            self.log(path, entity)
            return
        # The pixels are kept as they are and become Arrow at the send, all frames' at once (_Pixels)
        pixels = bytes(data) if raw and not isinstance(data, bytes) else data if raw else np.ascontiguousarray(data).reshape(-1)
        template, size = self._template(path, archetype, data, raw, params)
        if size is None:
            size = template[1] + len(pixels) * sum(isinstance(a, pa.DataType) for _, a in template[0])
        components = [(d, _Pixels(pixels, a) if isinstance(a, pa.DataType) else a) for d, a in template[0]]
        self._rows.setdefault(path, []).append((self._frame, self._t_ns, components))
        self._buffered += size
        held = self._image_bytes[path] = self._image_bytes.get(path, 0) + size
        if self._buffered > self.flush_bytes:
            self.flush()
        elif held > self.image_flush_bytes:
            self._flush_rows(path)

    def _template(self, path: str, archetype: type, data: np.ndarray | bytes, raw: bool,
                  params: dict) -> tuple[tuple, int | None]:
        """The row template of ``archetype(data, **params)`` at ``path`` (built on first use: then also
        the size of that first row, else None)."""
        key = (path, archetype, None if raw else (data.shape, data.flags.c_contiguous),
               tuple([(k, repr(v)) for k, v in params.items()]) if params else ())
        template = self._templates.get(key)
        if template is not None:
            return template, None
        entity = archetype(contents=data, **params) if archetype is rr.EncodedImage else archetype(data, **params)
        built = _components([entity])
        pixel = [str(d).endswith((":buffer", ":blob")) for d, _ in built]
        # later frames count what their own Arrow arrays held: the template's other components,
        # and per pixel buffer its bytes and two int32 offsets
        fixed = sum(a.get_total_buffer_size() for (_, a), p in zip(built, pixel) if not p) + 8 * sum(pixel)
        template = self._templates[key] = ([(d, a.type if p else a) for (d, a), p in zip(built, pixel)], fixed)
        return template, sum(a.get_total_buffer_size() for _, a in built)

    def defer(self, path: str, archetype: type, **fields) -> None:
        """Log ``archetype(**fields)`` at ``path`` at the current frame without building it now: each
        field is a batch (a list or an array whose first axis is the instances); at ``flush`` every
        field is concatenated over the buffered frames and converted once (``archetype.columns``).
        The cost per frame is then a dict append, not an archetype's construction (10-350 µs).
        """
        key = (archetype, tuple(fields))
        self._deferred.setdefault(path, {}).setdefault(key, []).append((self._frame, self._t_ns, fields))
        self._buffered += sum(getattr(v, "nbytes", 64) for v in fields.values())
        if self._buffered > self.flush_bytes:
            self.flush()

    def batch(self, build: Callable[[FrameLogger, list[tuple[int, int, object]]], None], record: object,
              nbytes: int) -> None:
        """Keep ``record`` (``nbytes`` held) for the current frame. Every ``BATCH_FRAMES`` frames, and at
        the flush, ``build(self, records)`` gets those frames' ``(frame, t_ns, record)`` in order and
        adds their rows through ``columns``, ``entity_rows``, ``image_rows`` and ``scalar_rows``; they
        are sent at the flush, one chunk per path and component set as ever."""
        records = self._batches.setdefault(build, [])
        records.append((self._frame, self._t_ns, record))
        if len(records) >= BATCH_FRAMES:
            self._batches[build] = []  # off the queue before building: a build cut short (Ctrl-C) is not built again at the flush
            build(self, records)
        self._buffered += nbytes
        if self._buffered > self.flush_bytes:
            self.flush()

    def columns(self, path: str, archetype: type, frames: list[int], times: list[int], lengths: list[int],
                **fields) -> None:
        """Rows of ``archetype`` at ``frames``: each field concatenated over them (``lengths``
        instances each). They join the rows ``defer`` keeps for the same path and fields, in one chunk."""
        if frames:
            block = (frames, times, {name: (value, lengths) for name, value in fields.items()})
            self._columns.setdefault(path, []).append(((archetype, tuple(fields)), block))

    def entity_rows(self, path: str, entity: rr.AsComponents, frames: list[int], times: list[int]) -> None:
        """``entity`` (e.g. a ``Clear``) at each of ``frames``, as ``log`` there would have put it."""
        if frames:
            components = _components([entity])
            self._rows.setdefault(path, []).extend((f, t, components) for f, t in zip(frames, times))

    def image_rows(self, path: str, archetype: type, frames: list[int], times: list[int], images: np.ndarray,
                   **params) -> None:
        """``archetype(images[k], **params)`` at ``frames[k]`` (uint8, stacked on a first axis), as
        ``image`` would have kept them."""
        if not len(frames):
            return
        template, _ = self._template(path, archetype, images[0], False, params)
        flat = np.ascontiguousarray(images).reshape(len(frames), -1)
        rows = self._rows.setdefault(path, [])
        for f, t, pixels in zip(frames, times, flat):
            rows.append((f, t, [(d, _Pixels(pixels, a) if isinstance(a, pa.DataType) else a) for d, a in template[0]]))

    def scalar_rows(self, paths: tuple[str, ...], frames: list[int], times: list[int], table: np.ndarray) -> None:
        """``scalars(paths, table[k])`` at each of ``frames``."""
        rows = self._series_rows.setdefault(paths, ([], [], []))
        rows[0].extend(frames)
        rows[1].extend(times)
        rows[2].extend(np.asarray(table, dtype=np.float64))

    def has_static(self, path: str) -> bool:
        """Whether ``static_once`` has logged ``path`` (so a caller can skip building the entity)."""
        return path in self._static

    def static_once(self, path: str, entity: rr.AsComponents) -> None:
        """Log ``entity`` statically at ``path`` the first time only (an annotation context, a layout)."""
        if path not in self._static:
            self._static.add(path)
            self.log(path, entity, static=True)

    def scalar(self, path: str, value: float) -> None:
        frames, times, values = self._series.setdefault(path, ([], [], []))
        frames.append(self._frame)
        times.append(self._t_ns)
        values.append(float(value))

    def scalars(self, paths: tuple[str, ...], values: np.ndarray) -> None:
        """A point on each of ``paths`` (``values[k]`` on ``paths[k]``, float64) at the current frame,
        kept as one row and split into the paths' series at the end; a non-finite value is skipped
        there, as ``scalar`` callers skip it (one call a frame for a filter's dozen series)."""
        frames, times, rows = self._series_rows.setdefault(paths, ([], [], []))
        frames.append(self._frame)
        times.append(self._t_ns)
        rows.append(values)

    def _split_series_rows(self) -> None:
        """``scalars`` rows into the per-path series (frame order kept where a path has both)."""
        for paths, (frames, times, rows) in self._series_rows.items():
            table = np.asarray(rows, dtype=np.float64).reshape(len(rows), len(paths))
            finite = np.isfinite(table)
            for k, path in enumerate(paths):
                keep = finite[:, k]
                f, t, v = self._series.setdefault(path, ([], [], []))
                merge = bool(f)
                f += [x for x, ok in zip(frames, keep.tolist()) if ok]
                t += [x for x, ok in zip(times, keep.tolist()) if ok]
                v += table[keep, k].tolist()
                if merge:  # a path given by scalar() too: back into frame order (stable)
                    order = sorted(range(len(f)), key=f.__getitem__)
                    self._series[path] = ([f[i] for i in order], [t[i] for i in order], [v[i] for i in order])
        self._series_rows.clear()

    def _send_rows(self, path: str, rows: list[tuple]) -> None:
        groups: dict[tuple, list] = {}
        for row in rows:
            groups.setdefault(tuple(d for d, _ in row[2]), []).append(row)
        for group in groups.values():
            _send(self.rec, path, _timelines(group), [r[2] for r in group])

    def _flush_rows(self, path: str) -> None:
        """Send ``path``'s buffered rows now (an image path past ``image_flush_bytes``)."""
        rows = self._rows.pop(path, [])
        self._send_rows(path, rows)
        self._buffered -= self._image_bytes.pop(path, 0)

    def flush(self) -> None:
        """Send the buffered rows: paths in sorted order, one chunk per (path, component set)."""
        import rerun_bindings as bindings

        batches, self._batches = self._batches, {}
        for build, records in batches.items():
            if records:
                build(self, records)
        for path in sorted(set(self._rows) | set(self._deferred) | set(self._columns)):
            # each path off the buffers before it is sent: a flush cut short (Ctrl-C) does not send it again
            rows, deferred, columns = self._rows.pop(path, []), self._deferred.pop(path, {}), self._columns.pop(path, [])
            self._send_rows(path, rows)
            groups = {key: [([r[0] for r in rows], [r[1] for r in rows], {name: _field(rows, name) for name in key[1]})]
                      for key, rows in deferred.items()}
            for key, block in columns:
                groups.setdefault(key, []).append(block)
            for (archetype, _), blocks in groups.items():
                frames, times, fields = _join(blocks)
                bindings.send_arrow_chunk(path, timelines=_timeline_arrays(frames, times),
                                          components=_archetype_columns(archetype, fields), recording=self.rec.to_native())
        self._rows.clear()
        self._deferred.clear()
        self._columns.clear()
        self._buffered = 0
        self._image_bytes.clear()

    def flush_scalars(self) -> None:
        self.flush()
        self._split_series_rows()
        for path in sorted(self._series):
            frames, times, values = self._series[path]
            self.rec.send_columns(
                path,
                indexes=[
                    rr.TimeColumn("frame", sequence=np.asarray(frames, dtype=np.int64)),
                    rr.TimeColumn("log_time", timestamp=np.asarray(times, dtype="datetime64[ns]")),
                ],
                columns=rr.Scalars.columns(scalars=np.asarray(values, dtype=np.float64)),
            )
        self._series.clear()


def _timelines(rows: list[tuple]) -> dict[str, pa.Array]:
    return _timeline_arrays([r[0] for r in rows], [r[1] for r in rows])


def _timeline_arrays(frames: list[int], times: list[int]) -> dict[str, pa.Array]:
    return {
        "frame": pa.array(frames, pa.int64()),
        "log_time": pa.array(np.asarray(times, dtype="datetime64[ns]"), pa.timestamp("ns")),
    }


def _field(rows: list[tuple], name: str) -> tuple[object, list[int]]:
    """A deferred field over ``rows``: the batches concatenated, and each row's number of instances."""
    values = [r[2][name] for r in rows]
    return _concat(values), [len(v) for v in values]


def _join(blocks: list[tuple]) -> tuple:
    """Blocks of rows (frames, times, fields) of one path and component set as one block."""
    if len(blocks) == 1:
        return blocks[0]
    fields = {}
    for name in blocks[0][2]:
        values = [b[2][name][0] for b in blocks]
        same = all(isinstance(v, np.ndarray) for v in values) and len({v.shape[1:] for v in values}) == 1
        fields[name] = (np.concatenate(values) if same else [x for v in values for x in v],
                        [n for b in blocks for n in b[2][name][1]])
    return [f for b in blocks for f in b[0]], [t for b in blocks for t in b[1]], fields


def _archetype_columns(archetype: type, fields: dict[str, tuple[object, list[int]]]) -> dict:
    """One chunk's components: each field (a batch over all its rows, and the rows' numbers of
    instances) converted once and split into rows."""
    columns = {}
    for name, (value, lengths) in fields.items():
        for column in archetype.columns(**{name: value}):
            columns[column.component_descriptor()] = column.partition(lengths).as_arrow_array()
    return columns


def _concat(values: list) -> object:
    """Batches of several frames as one batch: arrays concatenated, a field that builds itself late
    (``parts.Ellipses``) built for all frames at once, anything else chained as a list."""
    build = getattr(type(values[0]), "build_all", None)
    if build is not None and all(type(v) is type(values[0]) for v in values):
        return build(values)
    if all(isinstance(v, np.ndarray) for v in values):
        shapes = {v.shape[1:] for v in values if len(v)}
        if len(shapes) <= 1:
            nonempty = [v for v in values if len(v)] or values[:1]
            return np.concatenate(nonempty) if len(nonempty) > 1 else nonempty[0]
    return [item for v in values for item in v]


def _components(entities) -> list[tuple]:
    """(descriptor, Arrow array) of each component of ``entities``, first of a descriptor kept (as ``rr.log``)."""
    out, seen = [], set()
    for entity in entities:
        batches = entity.as_component_batches() if hasattr(entity, "as_component_batches") else entity
        for batch in batches:
            descriptor = batch.component_descriptor()
            array = batch.as_arrow_array()
            if array is not None and descriptor not in seen:
                seen.add(descriptor)
                out.append((descriptor, array))
    return out


class _Pixels:
    """One image's pixel buffer (or encoded blob) as logged: uint8 array or bytes, and the Arrow type
    of its component (``list<uint8>``). ``_send`` makes one Arrow array of a chunk's frames from
    these (``column``), which holds what each frame's own ``from_arrays`` held (~8 µs a frame less)."""

    __slots__ = ("data", "type")

    def __init__(self, data: np.ndarray | bytes, type: pa.DataType) -> None:
        self.data, self.type = data, type

    def __len__(self) -> int:
        return 1

    def get_total_buffer_size(self) -> int:
        return len(self.data) + 8

    def arrow(self) -> pa.Array:
        return _Pixels.column([self])

    @staticmethod
    def column(items: list[_Pixels]) -> pa.Array:
        offsets = np.zeros(len(items) + 1, dtype=np.int32)
        np.cumsum([len(p.data) for p in items], out=offsets[1:])
        flat = [np.frombuffer(p.data, dtype=np.uint8) if isinstance(p.data, bytes) else p.data for p in items]
        values = flat[0] if len(flat) == 1 else np.concatenate(flat)
        return pa.ListArray.from_arrays(pa.array(offsets), pa.array(values, type=pa.uint8()), type=items[0].type)


def _send(rec: rr.RecordingStream, path: str, timelines: dict, rows: list[list[tuple]]) -> None:
    """One chunk: ``rows`` (each a list of (descriptor, array), all with the same descriptors) at ``timelines``."""
    import rerun_bindings as bindings

    columns = {}
    for k, (descriptor, _) in enumerate(rows[0]):
        arrays = [row[k][1] for row in rows]
        if all(type(a) is _Pixels for a in arrays) and len({a.type for a in arrays}) == 1:
            offsets = np.arange(len(arrays) + 1, dtype=np.int32)
            columns[descriptor] = pa.ListArray.from_arrays(pa.array(offsets), _Pixels.column(arrays))
            continue
        arrays = [a.arrow() if type(a) is _Pixels else a for a in arrays]
        offsets = np.zeros(len(arrays) + 1, dtype=np.int32)
        np.cumsum([len(a) for a in arrays], out=offsets[1:])
        values = arrays[0] if len(arrays) == 1 else pa.concat_arrays(arrays)
        columns[descriptor] = pa.ListArray.from_arrays(pa.array(offsets), values)
    bindings.send_arrow_chunk(path, timelines=timelines, components=columns, recording=rec.to_native())


def check_connect_url(url: str) -> str:
    """``url`` when it is a Rerun viewer's gRPC address, else one sentence naming the schemes accepted
    (the SDK's own refusal was an internal error)."""
    if not url.startswith(RERUN_SCHEMES) or len(url) == len(next(s for s in RERUN_SCHEMES if url.startswith(s))):
        raise TrackreplayError(f"--connect {url!r} is not a Rerun viewer URL; one starts with "
                               f"{', '.join(RERUN_SCHEMES)} (e.g. rerun+http://127.0.0.1:9876/proxy)")
    return url


def missing_display() -> str | None:
    """Why a viewer window cannot open here (Linux without X11 or Wayland), else None."""
    displays = ("DISPLAY", "WAYLAND_DISPLAY", "WAYLAND_SOCKET")
    if sys.platform.startswith("linux") and not any(os.environ.get(v) for v in displays):
        return "no display (DISPLAY and WAYLAND_DISPLAY are unset)"
    return None


def _viewer_listening(port: int) -> bool:
    try:
        with socket.create_connection(("127.0.0.1", port), timeout=1.0):
            return True
    except OSError:
        return False


def spawn_viewer(rec: rr.RecordingStream) -> str | None:
    """Start a Rerun viewer for ``rec`` (the SDK's global spawn ignores a stream that is not the global
    one); None once it listens, else why it did not start."""
    reason = missing_display()
    if reason is None:
        beside = Path(sys.executable).with_name("rerun")  # the SDK's own viewer, when the venv is not on PATH
        try:
            rr.spawn(port=VIEWER_PORT, connect=False, hide_welcome_screen=True, recording=rec,
                     executable_path=str(beside) if beside.is_file() else None)
        except Exception as err:  # no viewer executable: the SDK's refusal is a paragraph, keep its first line
            reason = str(err).strip().splitlines()[0].rstrip(".")
        else:
            if not _viewer_listening(VIEWER_PORT):
                reason = f"the viewer it started is not listening on port {VIEWER_PORT}"
    return None if reason is None else f"cannot open a Rerun viewer: {reason}"


WEB_PORT = 9090  # the SDK's default for its web viewer


def _port_free(port: int) -> bool:
    """Whether ``port`` can be listened on (the SDK's gRPC server only logs a taken port, then serves nothing)."""
    with socket.socket() as probe:
        try:
            probe.bind(("0.0.0.0", port))
        except OSError:
            return False
    return True


class WebViewer:
    """Rerun's gRPC message proxy (it buffers what replays stream to it, for viewers that connect
    later) and the SDK's web viewer over HTTP, pointed at it: for a machine without a display, open
    ``url`` in a browser (over an SSH tunnel of both ports from elsewhere). Replays stream to
    ``connect_url``; the proxy lives as long as this object's recording, so ``serve`` keeps the
    process up after the replay."""

    def __init__(self, grpc_port: int = VIEWER_PORT, web_port: int = WEB_PORT, memory_limit: str = "25%") -> None:
        from urllib.parse import quote

        for flag, port in (("--grpc-port", grpc_port), ("--web-port", web_port)):
            if not _port_free(port):
                raise OutputError(f"port {port} is in use; choose another with {flag}")
        self._holder = rr.RecordingStream("trackreplay-web", send_properties=False)
        self.connect_url = self._holder.serve_grpc(grpc_port=grpc_port, server_memory_limit=memory_limit)
        try:
            rr.serve_web_viewer(web_port=web_port, open_browser=False, connect_to=self.connect_url)
        except RuntimeError as err:  # a port taken since the check
            self.close()
            raise OutputError(f"cannot serve the web viewer on port {web_port} ({err})") from None
        self.url = f"http://127.0.0.1:{web_port}/?url={quote(self.connect_url, safe='')}"

    def serve(self, seconds: float | None = None) -> None:
        """Keep serving for ``seconds`` (None: until Ctrl-C, which stops it without an error)."""
        import time

        deadline = None if seconds is None else time.monotonic() + seconds
        try:
            while deadline is None or time.monotonic() < deadline:
                time.sleep(0.2 if deadline is None else max(0.0, min(0.2, deadline - time.monotonic())))
        except KeyboardInterrupt:
            pass

    def close(self) -> None:
        self._holder.disconnect()


def _stream(recording_id: str) -> rr.RecordingStream:
    rec = rr.RecordingStream("trackreplay", recording_id=recording_id, send_properties=False, batcher_config=_batcher())
    # Rerun's own `log_time` is the wall clock at logging; ours is the capture time from the log.
    rec.set_log_time_enabled(False)
    return rec


class RerunSink:
    """Owns the RecordingStream; trackers' views log through ``self.logger``.

    The stream is written to ``<path>.partial`` and renamed on ``close``. Everything, the camera
    images included, goes through the :class:`FrameLogger`'s columns, so the chunk order depends on
    the data only and ``rerun rrd compare`` of two replays passes without ``--unordered`` (no
    rewrite of the file in a canonical order is needed; :func:`canonical_chunks` stays for files
    written otherwise).
    """

    def __init__(self, path: str | Path | None, recording_id: str, blueprint: rrb.Blueprint, *,
                 connect: str | None = None, spawn: bool = False, truth: pl.DataFrame | None = None) -> None:
        """Write to ``path`` (an .rrd), and/or stream live to the viewer at ``connect`` (a gRPC URL such
        as ``rerun+http://127.0.0.1:9876/proxy``) or to one ``spawn`` starts (needs a display).
        ``truth`` (the log's ground-truth table) goes under ``truth/`` at the frames logged (views.truth)."""
        self.path = None if path is None else Path(path)
        self.partial = None
        self.recording_id = recording_id
        self.rec = _stream(recording_id)
        self.truth = None if truth is None or truth.is_empty() else TruthStream(self.rec, truth)
        if self.truth is not None:
            blueprint = show_truth(blueprint, self.truth.paths)
        self.blueprint = blueprint
        sinks: list = []
        if self.path is not None:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self.partial = claim_partial(self.path)  # this process's own: another replay to the same path has its own
            sinks.append(rr.FileSink(str(self.partial)))
        self.viewer_error: str | None = None  # raised by `close`, once the .rrd is written
        if spawn:
            self.viewer_error = spawn_viewer(self.rec)
            if self.viewer_error is not None and self.path is None and connect is None:
                raise OutputError(f"{self.viewer_error}; use --rrd FILE (and `rerun FILE` where there is a display) "
                                  "or --connect URL")  # nothing else to write: fail before the replay
            if self.viewer_error is None:
                connect = connect or VIEWER_URL
        if connect is not None:
            sinks.append(rr.GrpcSink(check_connect_url(connect)))
        self.rec.set_sinks(*sinks, default_blueprint=blueprint)
        self.logger = FrameLogger(self.rec)

    def begin_frame(self, frame: Frame) -> None:
        logger = self.logger
        logger.set_frame(frame.index, frame.t_ns)
        if self.truth is not None:
            self.truth.add_frame(frame.index, frame.t_ns)
        if frame.encoded is not None and frame.encoding in ("jpeg", "png"):
            media = "image/jpeg" if frame.encoding == "jpeg" else "image/png"
            logger.image(CAMERA, rr.EncodedImage, frame.encoded, media_type=media)
        else:
            logger.image(CAMERA, rr.Image, frame.image, color_model="L" if frame.image.ndim == 2 else "BGR")
        if frame.right is not None:
            logger.image(RIGHT, rr.Image, frame.right, color_model="L" if frame.right.ndim == 2 else "BGR")

    def close(self) -> None:
        try:
            self._close()
        except (RuntimeError, OSError) as err:  # the SDK's file writer reports a full disk as RuntimeError
            if self.path is None:
                raise OutputError(f"cannot stream to the Rerun viewer ({err})") from None
            self.partial.unlink(missing_ok=True)  # only the file this replay created: `path` may be another's finished one
            raise OutputError(f"cannot write {self.path} ({err}); no new .rrd was kept") from None

    def _close(self) -> None:
        if self.truth is not None:
            self.truth.flush()
        self.logger.flush_scalars()
        self.rec.flush()
        self.rec.disconnect()
        if self.partial is not None:
            self.partial.replace(self.path)
        if self.viewer_error is not None:
            where = (f"; {self.path} was written: open it with `rerun {self.path}` where there is a display"
                     if self.path is not None else "")
            raise OutputError(self.viewer_error + where)


def canonical_chunks(path: str | Path) -> "rc.ChunkStore":
    """The recording's chunks of an .rrd (as a store) in an order that does not depend on the process, with
    fresh chunk ids assigned in that order.

    Rerun's batcher splits one entity's rows into one chunk per component set (a ``Clear`` and a
    ``Points2D`` on the same path make two) and emits those in hash-map order, which differs
    between processes; readers (``rerun rrd compare``, the store) order chunks by chunk id, so
    two replays differed in order, not content. Here chunks are sorted by entity path, then by
    their first row id (row ids grow in logging order), and re-created so their new ids follow
    that order.
    """
    keyed = []
    for chunk in rc.RrdReader(str(path)).stream():
        batch = chunk.to_record_batch()
        first_row = batch.column(batch.schema.names.index("rerun.controls.RowId"))[0].as_py() if batch.num_rows else b""
        index = None if chunk.is_static else sorted(chunk.timeline_names)
        keyed.append((str(chunk.entity_path), first_row, batch, index))
    keyed.sort(key=lambda k: (k[0], k[1]))
    chunks = []
    for _, _, batch, index in keyed:  # naming the index columns makes Rerun assign fresh ids
        chunks += rc.Chunk.from_record_batch(batch, index=index)
    return rc.ChunkStore.from_chunks(chunks)


def rrd_digest(path: str | Path) -> str:
    """sha256 of an .rrd's logged content, ignoring row and chunk ids (which are time-based).

    Two replays of the same log, config and seed give the same value.
    """
    import pyarrow as pa
    import rerun.chunk as rc

    digests: list[bytes] = []
    for chunk in rc.RrdReader(str(path)).stream():
        batch = chunk.to_record_batch()
        keep = [i for i, name in enumerate(batch.schema.names) if name != "rerun.controls.RowId"]
        table = pa.Table.from_arrays([batch.column(i) for i in keep], names=[batch.schema.names[i] for i in keep])
        sink = pa.BufferOutputStream()
        with pa.ipc.new_stream(sink, table.schema) as writer:
            writer.write_table(table)
        h = hashlib.sha256(str(chunk.entity_path).encode() + b"\0" + bytes(chunk.is_static))
        h.update(sink.getvalue().to_pybytes())
        digests.append(h.digest())
    return hashlib.sha256(b"".join(sorted(digests))).hexdigest()
