"""The shared Rerun drawing pieces: geometry of the Gaussian outlines, labels, clearing, statics."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import rerun as rr
import rerun.chunk as rc

from trackreplay.replay.views.rerun_sink import FrameLogger
from trackreplay.replay.views import parts
from trackreplay.trackers.base import TrackState


def _mahalanobis(points: np.ndarray, mean: np.ndarray, cov: np.ndarray) -> np.ndarray:
    d = points - mean
    return np.sqrt(np.einsum("ni,ij,nj->n", d, np.linalg.inv(cov), d))


def test_ellipse_lies_on_the_n_sigma_contour_of_a_rotated_covariance() -> None:
    rot = np.array([[np.cos(0.6), -np.sin(0.6)], [np.sin(0.6), np.cos(0.6)]])
    cov = rot @ np.diag([9.0, 1.0]) @ rot.T
    mean = np.array([10.0, -4.0])
    line = parts.ellipse_polyline(mean, cov, n_sigma=2.0, segments=64)
    assert line.shape == (65, 2)
    np.testing.assert_allclose(line[0], line[-1])
    np.testing.assert_allclose(_mahalanobis(line, mean, cov), 2.0, rtol=1e-9)
    # the long axis is 2 sigma = 6 px, along the rotated x axis
    assert np.max(np.linalg.norm(line - mean, axis=1)) == pytest.approx(6.0, rel=1e-3)


def test_ellipsoid_sections_lie_on_the_n_sigma_surface() -> None:
    a = np.array([[2.0, 0.3, 0.1], [0.3, 1.0, -0.2], [0.1, -0.2, 0.5]])
    mean = np.array([1.0, 2.0, 3.0])
    lines = parts.ellipsoid_polylines(mean, a, n_sigma=3.0)
    assert len(lines) == 3
    for line in lines:
        np.testing.assert_allclose(_mahalanobis(line, mean, a), 3.0, rtol=1e-9)


def test_field_labels_follow_the_given_names_and_formats() -> None:
    labels = parts.field_labels({"area": np.array([12.4, 7.0]), "circularity": np.array([0.8, 0.345]),
                                 "reason": np.array(["ok", "size"])}, {"area": "{:.0f}", "circularity": "{:.2f}"})
    assert labels == ["12/0.80/ok", "7/0.34/size"]


def test_kalman_series_rejects_names_that_do_not_fit_the_state() -> None:
    with pytest.raises(ValueError, match="2 names for a state of 3"):
        parts.kalman_series(FrameLogger(rr.RecordingStream("t")), "k", np.zeros(3), np.eye(3), ["a", "b"])


def _record(tmp_path: Path, draw) -> dict[str, list[rc.Chunk]]:
    rec = rr.RecordingStream("parts-test", recording_id="parts", send_properties=False)
    rec.set_log_time_enabled(False)
    path = tmp_path / "parts.rrd"
    rec.save(str(path))
    logger = FrameLogger(rec)
    draw(logger)
    logger.flush_scalars()
    rec.flush()
    rec.disconnect()
    chunks: dict[str, list[rc.Chunk]] = {}
    for chunk in rc.RrdReader(str(path)).stream():
        chunks.setdefault(str(chunk.entity_path), []).append(chunk)
    return chunks


def _components(chunks: list[rc.Chunk]) -> set[str]:
    return {name for c in chunks for name in c.to_record_batch().schema.names}


def test_a_track_that_disappears_or_is_lost_is_cleared(tmp_path: Path) -> None:
    def draw(logger: FrameLogger) -> None:
        logger.set_frame(0, 0)
        parts.tracks(logger, [TrackState(1, x=5.0, y=5.0), TrackState(2, x=9.0, y=9.0)])
        logger.set_frame(1, 1)
        parts.tracks(logger, [TrackState(1, status="lost")])  # 1 lost, 2 gone without a state

    chunks = _record(tmp_path, draw)
    for track in ("/tracks/1", "/tracks/2"):
        assert "Clear:is_recursive" in _components(chunks[track])
        assert "Boxes2D:centers" in _components(chunks[track])


def test_annotation_context_is_logged_once_and_statically(tmp_path: Path) -> None:
    def draw(logger: FrameLogger) -> None:
        for i in range(3):
            logger.set_frame(i, i)
            parts.annotation_context(logger, "crop", [(0, "bg", (0, 0, 0, 0)), (1, "ball", (255, 0, 255, 200))])
            parts.mask_over_crop(logger, "crop", np.eye(4, dtype=bool), (10, 20), image=np.zeros((4, 4), np.uint8))

    chunks = _record(tmp_path, draw)
    static = [c for c in chunks["/crop"] if c.is_static]
    assert len(static) == 1 and static[0].num_rows == 1
    assert sum(c.num_rows for c in chunks["/crop/mask"]) == 3
    assert {"/crop/image", "/crop/mask"} <= set(chunks)


def test_nothing_to_draw_clears_instead_of_leaving_the_last_frame(tmp_path: Path) -> None:
    def draw(logger: FrameLogger) -> None:
        logger.set_frame(0, 0)
        parts.particles(logger, "p", np.zeros((0, 4)), np.zeros(0))
        parts.blobs(logger, "b", np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0, bool), points_path="bp")
        parts.covariance_ellipses(logger, "e", np.full((1, 2), np.nan), np.eye(2)[None])
        parts.scalar(logger, "s", float("nan"))

    chunks = _record(tmp_path, draw)
    for path in ("/p", "/b", "/bp", "/e"):
        assert _components(chunks[path]) >= {"Clear:is_recursive"}
    assert "/s" not in chunks
