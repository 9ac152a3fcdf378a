"""The Rerun stream of a replay: camera images on ``frame``/``log_time`` timelines, to an .rrd file.

Built only when ``--rrd`` is given; without it no Rerun object is ever constructed.
"""

from __future__ import annotations

import hashlib
from datetime import timedelta
from pathlib import Path

import numpy as np
import rerun as rr
import rerun.blueprint as rrb
import rerun.chunk as rc

from trackreplay.schemas.errors import OutputError
from trackreplay.trackers.frame import Frame

CAMERA = "camera/image"
RIGHT = "camera/right"


def _batcher() -> rr.ChunkBatcherConfig:
    # Chunk boundaries from data volume only (never from elapsed time), so two replays
    # write the same chunks.
    return rr.ChunkBatcherConfig(flush_tick=timedelta(days=1), flush_num_bytes=8 * 1024 * 1024, flush_num_rows=2**20)


class FrameLogger:
    """What a tracker's view logs through: ``log`` passes straight to Rerun at the current
    frame; ``scalar`` buffers time-series points and sends them as columns at the end, which
    costs a fraction of one ``rr.log`` per point.
    """

    def __init__(self, rec: rr.RecordingStream) -> None:
        self.rec = rec
        self._frame = 0
        self._t_ns = 0
        self._series: dict[str, tuple[list[int], list[int], list[float]]] = {}
        self._static: set[str] = set()
        self.live_tracks: set[int] = set()  # track ids drawn under tracks/ last frame (views.parts.tracks)

    def set_frame(self, index: int, t_ns: int) -> None:
        self._frame, self._t_ns = index, t_ns
        self.rec.set_time("frame", sequence=index)
        self.rec.set_time("log_time", timestamp=np.datetime64(t_ns, "ns"))

    def log(self, path: str, *entities, **kwargs) -> None:
        self.rec.log(path, *entities, **kwargs)

    def static_once(self, path: str, entity: rr.AsComponents) -> None:
        """Log ``entity`` statically at ``path`` the first time only (an annotation context, a layout)."""
        if path not in self._static:
            self._static.add(path)
            self.rec.log(path, entity, static=True)

    def scalar(self, path: str, value: float) -> None:
        frames, times, values = self._series.setdefault(path, ([], [], []))
        frames.append(self._frame)
        times.append(self._t_ns)
        values.append(float(value))

    def flush_scalars(self) -> None:
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


def _stream(recording_id: str) -> rr.RecordingStream:
    rec = rr.RecordingStream("trackreplay", recording_id=recording_id, send_properties=False, batcher_config=_batcher())
    # Rerun's own `log_time` is the wall clock at logging; ours is the capture time from the log.
    rec.set_log_time_enabled(False)
    return rec


class RerunSink:
    """Owns the RecordingStream; trackers' views log through ``self.logger``.

    The stream is written to ``<path>.partial`` and rewritten in a canonical chunk order on
    ``close`` (see :func:`canonical_chunks`), so ``rerun rrd compare`` of two replays passes
    without ``--unordered``.
    """

    def __init__(self, path: str | Path, recording_id: str, blueprint: rrb.Blueprint) -> None:
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.partial = self.path.with_name(self.path.name + ".partial")
        self.recording_id = recording_id
        self.blueprint = blueprint
        self.rec = _stream(recording_id)
        self.rec.save(str(self.partial))
        self.logger = FrameLogger(self.rec)

    def begin_frame(self, frame: Frame) -> None:
        rec = self.rec
        self.logger.set_frame(frame.index, frame.t_ns)
        if frame.encoded is not None and frame.encoding in ("jpeg", "png"):
            media = "image/jpeg" if frame.encoding == "jpeg" else "image/png"
            rec.log(CAMERA, rr.EncodedImage(contents=frame.encoded, media_type=media))
        else:
            model = "L" if frame.image.ndim == 2 else "BGR"
            rec.log(CAMERA, rr.Image(frame.image, color_model=model))
        if frame.right is not None:
            model = "L" if frame.right.ndim == 2 else "BGR"
            rec.log(RIGHT, rr.Image(frame.right, color_model=model))

    def close(self) -> None:
        try:
            self._close()
        except (RuntimeError, OSError) as err:  # the SDK's file writer reports a full disk as RuntimeError
            self.partial.unlink(missing_ok=True)
            self.path.unlink(missing_ok=True)
            raise OutputError(f"cannot write {self.path} ({err}); no .rrd was kept") from None

    def _close(self) -> None:
        self.logger.flush_scalars()
        self.rec.flush()
        self.rec.disconnect()
        out = _stream(self.recording_id)
        out.save(str(self.path), default_blueprint=self.blueprint)
        out.send_chunks(canonical_chunks(self.partial))  # a ChunkStore: ~3x faster to send than a list
        out.flush()
        out.disconnect()
        self.partial.unlink()


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
