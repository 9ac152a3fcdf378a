"""The multi-object metrics a chunk of frames at a time (issue 33): the same numbers as the whole tables."""

from __future__ import annotations

import json

import numpy as np
import polars as pl
import pytest

from trackreplay.replay.analysis import mot
from trackreplay.replay.core.trajectory import SCHEMA
from trackreplay.replay.log.groundtruth import GT_SCHEMA

FRAMES = 150


def _scene(seed: int = 0) -> tuple[pl.DataFrame, pl.DataFrame]:
    """Truth rows in message order (frame by frame, objects shuffled; some frames list nothing, some objects
    hidden or unplaced) and a trajectory of two trackers (their track ids overlap) following them with
    switches, lost and predicted rows; both with X, Y, Z."""
    rng = np.random.default_rng(seed)
    truth, traj = [], []
    for f in range(FRAMES):
        t_ns = f * 1_000_000_000 // 30
        ids = [] if f % 17 == 5 else list(rng.permutation(5) + 1)
        for i in ids:
            x, y = 20.0 * i + 5 * np.cos(f / 9 + i), 15.0 + 4 * np.sin(f / 7 * i)
            placed = not (f % 23 == 3 and i == 2)
            truth.append((f, t_ns, int(i), x if placed else None, y if placed else None, 8.0, 10.0, x / 10, y / 10, 1.0,
                          None, None, None if i == 1 else bool(f % 11), None))
            track = int(i) if f < 80 or i > 3 else int(i % 3 + 1)  # ids swap half way
            for tracker, k in (("flow", track), ("colorpf", 6 - track)):
                status = rng.choice(["measured", "measured", "predicted", "lost"])
                if status == "lost":
                    traj.append((tracker, k, f, t_ns, *[None] * 10, "lost"))
                    continue
                dx, dy = rng.normal(0, 2, 2)
                traj.append((tracker, k, f, t_ns, x + dx, y + dy, 8.0 + dx, 10.0, (x + dx) / 10, (y + dy) / 10, 1.0,
                             None, None, None, status))
    gt = pl.DataFrame(truth, schema=GT_SCHEMA, orient="row")
    cols = ("tracker", "track_id", "frame", "t_ns", "x", "y", "w", "h", "X", "Y", "Z", "dx", "dy", "dz", "status")
    table = pl.DataFrame(traj, schema={c: SCHEMA[c] for c in cols}, orient="row")
    table = table.with_columns(pl.lit(None, dtype=pl.Float64).alias(c) for c in SCHEMA if c not in cols)
    return gt, table.select(list(SCHEMA)).sort("tracker", "track_id", "frame")


def _chunks(gt: pl.DataFrame, size: int):
    """``truth_chunks``' shape from a table in message order: ``size`` messages a chunk."""
    frames = np.arange(FRAMES)

    def chunks():
        for lo in range(0, FRAMES, size):
            part = frames[lo:lo + size]
            yield part, gt.filter(pl.col("frame").is_in(part.tolist()))

    return chunks


@pytest.mark.parametrize("size", [1, 7, 64])
def test_metrics_a_chunk_of_frames_at_a_time_are_the_whole_tables(size: int) -> None:
    gt, traj = _scene()
    whole_gt = gt.sort(["id", "frame"])  # as groundtruth_with_frames gives it
    frames = pl.Series("frame", np.arange(FRAMES))
    tables = mot.ChunkedTables(traj.sample(fraction=1.0, shuffle=True, seed=1).lazy(), _chunks(gt, size))
    for space in ("image", "3d"):
        whole = mot.mot_metrics(traj, whole_gt, space=space, frames=frames)
        chunked = mot.mot_metrics_chunked(tables, space=space)
        assert repr(whole.as_dict()) == repr(chunked.as_dict()) and whole.id_switches > 0 and whole.matches > 0
        whole_h = mot.hota_metrics(traj, whole_gt, space=space, frames=frames)
        assert repr(whole_h.as_dict()) == repr(mot.hota_metrics_chunked(tables, space=space).as_dict())
        assert 0 < whole_h.hota < 1
    assert tables.three_d_missing() is None
    flat = mot.ChunkedTables(traj.with_columns(pl.lit(None, dtype=pl.Float64).alias("Z")).lazy(), _chunks(gt, size))
    assert flat.three_d_missing() == "the trajectory has no X, Y, Z"
    unplaced = mot.ChunkedTables(traj.lazy(), _chunks(gt.with_columns(pl.lit(None, dtype=pl.Float64).alias("X")), size))
    assert unplaced.three_d_missing() == mot.three_d_missing(traj, gt.with_columns(pl.lit(None, dtype=pl.Float64).alias("X")))


def test_hota_of_frames_given_twice_is_hota_of_a_list() -> None:
    """``hota`` of a function giving the frames afresh (two passes, none kept) is ``hota`` of the list."""
    rng = np.random.default_rng(3)
    frames = []
    for _ in range(60):
        n, m = rng.integers(0, 5, 2)
        sim = rng.random((n, m)) * (rng.random((n, m)) < 0.6)
        frames.append((rng.choice(7, n, replace=False), rng.choice(8, m, replace=False), sim))
    assert repr(mot.hota(frames).as_dict()) == repr(mot.hota(lambda: iter(frames)).as_dict())


def test_eval_mot_reads_the_log_and_the_trajectory_a_chunk_at_a_time(tmp_path, monkeypatch, capsys) -> None:
    """``eval --mot`` on a Parquet trajectory and a log reads neither whole: the same printed metrics and the
    same --json as the whole tables (``--per-frame`` takes that path), image and 3-D."""
    import cv2

    from trackreplay.recorder.image_codec import compressed_image
    from trackreplay.recorder.writer import LogWriter
    from trackreplay.replay.cli.commands import eval_cmd
    from trackreplay.replay.cli.main import main
    from trackreplay.replay.core.export import write_trajectory
    from trackreplay.schemas import topics as T
    from trackreplay.schemas.records import GroundTruthFrame, GroundTruthObject

    gt, traj = _scene(1)
    log, path = tmp_path / "t.mcap", write_trajectory(traj, tmp_path / "t.parquet")
    picture = cv2.imencode(".png", np.zeros((8, 8), np.uint8))[1].tobytes()
    with LogWriter(log) as out:
        for f in range(FRAMES):
            t_ns = f * 1_000_000_000 // 30
            out.write(T.CAMERA_IMAGE, compressed_image(picture, "png", t_ns, "camera"), t_ns)
            objects = tuple(GroundTruthObject(id=r["id"], x=r["x"], y=r["y"], w=r["w"], h=r["h"], X=r["X"], Y=r["Y"], Z=r["Z"],
                                              visible=r["visible"]) for r in gt.filter(pl.col("frame") == f).iter_rows(named=True))
            out.write(T.GROUNDTRUTH, GroundTruthFrame(f, t_ns, objects).to_pb(), t_ns)
    monkeypatch.setattr(mot, "CHUNK_FRAMES", 7)
    whole_reads: list = []
    real = eval_cmd.groundtruth_with_frames
    monkeypatch.setattr(eval_cmd, "groundtruth_with_frames", lambda *a, **k: whole_reads.append(1) or real(*a, **k))
    printed = {}
    for name, extra in (("chunked", ["--mot"]), ("all", []), ("whole", ["--mot", "--per-frame", str(tmp_path / "p.csv")])):
        capsys.readouterr()
        assert main(["eval", str(path), str(log), "--json", str(tmp_path / f"{name}.json"), *extra]) == 0
        printed[name] = capsys.readouterr().out
        assert bool(whole_reads) == (name == "whole")
    assert printed["chunked"] == printed["whole"] and printed["all"].endswith(printed["whole"])
    assert printed["all"].startswith("scoring all 5 tracks against all 5 truth object(s)")
    texts = {name: (tmp_path / f"{name}.json").read_text() for name in printed}
    assert texts["chunked"] == texts["all"] == texts["whole"]
    metrics = json.loads(texts["whole"])
    assert metrics["3d"] is not None and metrics["image"]["id_switches"] > 0
