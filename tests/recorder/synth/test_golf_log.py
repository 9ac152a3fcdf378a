"""The golf-teeshot log: topics, ground truth, annotations, variants, determinism, command line."""

import math
from pathlib import Path

import numpy as np
import pytest

from trackreplay.recorder.synth.flow_sims import FlowSimConfig, write_flow_sim
from trackreplay.recorder.synth.golf.flight import AIR, REST, ROLL, TEE
from trackreplay.recorder.synth.golf.scene import GolfSceneConfig, SceneConfigError, logged_readings, plan_shot, write_golf_teeshot
from trackreplay.recorder.synth.golf.truth import choose_annotations
from trackreplay.replay.cli.main import main
from trackreplay.replay.log.frames import read_hints
from trackreplay.replay.log.groundtruth import read_groundtruth
from trackreplay.replay.log.reader import LogReader
from trackreplay.schemas import topics as T
from trackreplay.schemas.records import LensTable, PtzReading

SMALL = dict(width=320, height=180, duration=1.0)


def _messages(path: Path) -> list[tuple[str, int, bytes]]:
    reader = LogReader(path)
    return [(m.topic, m.log_time, m.data) for m in reader.messages(reader.topics())]


@pytest.fixture(scope="module")
def default_shot():
    return plan_shot(GolfSceneConfig())


def test_log_holds_every_topic_at_capture_time(tmp_path: Path) -> None:
    out = tmp_path / "shot.mcap"
    summary = write_golf_teeshot(out, GolfSceneConfig(**SMALL))
    reader = LogReader(out)
    topics = reader.topics()
    assert {T.CAMERA_IMAGE, T.PTZ_ENCODERS, T.PTZ_LENS_TABLE, T.GROUNDTRUTH, T.ANNOTATIONS_INIT} <= set(topics)
    assert topics[T.CAMERA_IMAGE].count == topics[T.GROUNDTRUTH].count == summary.frames == 30
    assert topics[T.PTZ_ENCODERS].count == summary.encoder_readings == 101
    assert topics[T.PTZ_LENS_TABLE].count == 1 and topics[T.ANNOTATIONS_INIT].count == 1
    assert topics[T.CAMERA_IMAGE].schema == "foxglove.CompressedImage"
    times = [m.log_time for m in reader.messages([T.CAMERA_IMAGE])]
    assert times == [round(k * 1e9 / 30) for k in range(30)]
    first = next(iter(reader.messages([T.CAMERA_IMAGE]))).decode()
    assert first.format == "jpeg"
    lens = LensTable.from_pb(reader.first(T.PTZ_LENS_TABLE))
    assert (lens.width, lens.height) == (320, 180) and lens.camera_position == (-10.0, -2.0, 2.5)
    for m in reader.messages([T.PTZ_ENCODERS]):
        assert PtzReading.from_pb(m.decode()).t_ns == m.log_time
    gt = read_groundtruth(reader)
    assert gt.height == 30 and gt["id"].unique().to_list() == [1]
    tee = gt.filter(gt["t_ns"] < 500_000_000)  # before the launch: on the tee, in the middle of the frame
    assert tee.height == 15 and tee["visible"].all()
    assert abs(tee["x"][0] - 160) < 2 and abs(tee["y"][0] - 90) < 2
    out_of_frame = gt.filter(gt["x"].is_null())  # the operator lags at launch: no position, not visible
    assert out_of_frame["visible"].to_list() == [False] * out_of_frame.height
    assert gt["X"].null_count() == 0 and gt["w"].drop_nulls().min() > 0


def test_same_seed_same_bytes_other_seed_other_images(tmp_path: Path) -> None:
    cfg = GolfSceneConfig(**SMALL, seed=7)
    a, b, c = tmp_path / "a.mcap", tmp_path / "b.mcap", tmp_path / "c.mcap"
    write_golf_teeshot(a, cfg)
    write_golf_teeshot(b, cfg)
    write_golf_teeshot(c, GolfSceneConfig(**SMALL, seed=8))
    ma, mb, mc = _messages(a), _messages(b), _messages(c)
    assert ma == mb
    images = lambda ms: [d for t, _, d in ms if t == T.CAMERA_IMAGE]  # noqa: E731
    assert images(ma) != images(mc)
    encoders = lambda ms: [d for t, _, d in ms if t == T.PTZ_ENCODERS]  # noqa: E731
    assert encoders(ma) != encoders(mc)  # encoder noise is seeded too


def test_ground_truth_is_consistent_with_the_flight(default_shot) -> None:
    shot = default_shot
    phases = {tr.phase for tr in shot.truth}
    assert {TEE, AIR, ROLL, REST} <= phases
    for tr in shot.truth[::7]:
        assert np.allclose(tr.position, shot.ball_at(tr.t)[0])
        if tr.uv is not None:
            uv = shot.camera_at(tr.t).project_points(tr.position)[0]
            assert np.allclose(uv, tr.uv)
            assert tr.diameter == pytest.approx(2 * shot.camera_at(tr.t).intrinsics.fx * shot.cfg.ball.radius
                                                / np.linalg.norm(tr.position - shot.cfg.camera_xyz))
    # Velocity in px/frame matches the displacement between frames where the motion is smooth.
    k = 100
    a, b = shot.truth[k], shot.truth[k + 1]
    mid = 0.5 * (np.array(a.velocity_px) + np.array(b.velocity_px))
    assert np.allclose(np.array(b.uv) - np.array(a.uv), mid, atol=0.05)
    record = shot.truth[0].record(0)
    assert record.objects[0].visible is True and record.objects[0].X == pytest.approx(0.0)


def test_annotations_mark_ball_over_sky_and_over_ground_on_real_frames(default_shot) -> None:
    shot = default_shot
    notes = choose_annotations(shot)
    sky = [a for a in notes if a.background == "sky"]
    ground = [a for a in notes if a.background == "ground"]
    assert len(sky) >= 2 and len(ground) >= 2
    assert notes[0].region.frame == 0  # the ball on the tee, before the shot
    for a in notes:
        r = a.region
        tr = shot.truth[r.frame]
        assert 0 <= r.frame < len(shot.frame_times) and r.label == "ball"
        assert r.t_ns == round(r.frame * 1e9 / shot.cfg.fps)
        assert tr.visible and math.hypot(r.x - tr.uv[0], r.y - tr.uv[1]) < 1e-9
        assert r.w == r.h >= tr.diameter
        assert tr.background == a.background
    assert all(shot.truth[a.region.frame].phase == AIR for a in sky)


def test_annotations_are_in_the_log_and_replay_finds_them(tmp_path: Path) -> None:
    out = tmp_path / "ann.mcap"
    summary = write_golf_teeshot(out, GolfSceneConfig(width=640, height=360, duration=4.0))
    hints = read_hints(LogReader(out), T.ANNOTATIONS_INIT)
    assert [h.frame for h in hints] == sorted(summary.annotation_frames_sky + summary.annotation_frames_ground)
    assert summary.annotation_frames_ground[0] == 0 and len(summary.annotation_frames_sky) >= 2


def test_occlusion_hides_the_ball_in_the_window(default_shot) -> None:
    for window in ((2.0, 3.0), (8.5, 10.0), (4.5, 7.0)):
        shot = plan_shot(GolfSceneConfig(occlusion=window))
        inside = [tr for tr in shot.truth if window[0] <= tr.t < window[1]]
        assert inside and not any(tr.visible for tr in inside)
        assert all(tr.occluded for tr in inside if tr.in_frame)
        # The ball shows again within a short while after the window.
        later = [tr for tr in shot.truth if window[1] + 0.5 <= tr.t < window[1] + 1.5]
        assert any(tr.visible for tr in later)
        ahead = [tr for tr in shot.truth if window[0] - 1.0 <= tr.t < window[0] - 0.5]
        assert sum(tr.visible for tr in ahead) >= 0.5 * len(ahead)
    clear = default_shot
    assert sum(tr.occluded for tr in clear.truth) == 0


def test_encoder_dropout_leaves_no_readings_in_the_window(tmp_path: Path) -> None:
    out = tmp_path / "drop.mcap"
    write_golf_teeshot(out, GolfSceneConfig(width=320, height=180, duration=1.5, encoder_dropout=(0.5, 1.0)))
    t = np.array([m.log_time for m in LogReader(out).messages([T.PTZ_ENCODERS])]) / 1e9
    assert not np.any((t >= 0.5) & (t < 1.0))
    assert np.any(t < 0.5) and np.any(t >= 1.0)
    shot = plan_shot(GolfSceneConfig(encoder_dropout=(2.0, 2.4)))
    t = np.array([r.t_ns for r in logged_readings(shot)]) / 1e9
    assert len(t) == int(shot.duration * 100) + 1 - 40


def test_no_bounce_variant(default_shot) -> None:
    shot = plan_shot(GolfSceneConfig(bounce=False))
    assert shot.trajectory.bounce_times == ()
    land = shot.cfg.launch_at + shot.trajectory.landing_time
    after = [tr for tr in shot.truth if tr.t > land]
    assert after and max(tr.position[2] for tr in after) == pytest.approx(shot.cfg.ball.radius)
    assert len(default_shot.trajectory.bounce_times) >= 2


def test_bad_options_fail_with_one_sentence() -> None:
    with pytest.raises(SceneConfigError, match="--occlusion"):
        GolfSceneConfig(occlusion=(3.0, 2.0)).validate()
    with pytest.raises(SceneConfigError, match="--fps"):
        GolfSceneConfig(fps=0.0).validate()
    with pytest.raises(SceneConfigError, match="camera"):
        GolfSceneConfig(camera="drone").validate()


@pytest.mark.slow  # 6 s: the default suite took 4 min 13 s on a fresh clone (budget 4 min); CI runs -m slow
def test_cli_writes_a_readable_golf_log(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "cli.mcap"
    assert main(["synth", "golf-teeshot", str(out), "--seed", "3", "--duration", "0.5", "--fps", "60",
                 "--no-bounce", "--cut", "0.3", "--occlusion", "0.2", "0.4", "--encoder-dropout", "0.1", "0.2"]) == 0
    assert "golf-teeshot" in capsys.readouterr().err
    reader = LogReader(out)
    topics = reader.topics()
    assert topics[T.CAMERA_IMAGE].count == 30 and topics[T.GROUNDTRUTH].count == 30
    frame = next(iter(reader.messages([T.CAMERA_IMAGE]))).decode()
    import cv2

    image = cv2.imdecode(np.frombuffer(frame.data, np.uint8), cv2.IMREAD_COLOR)
    assert image.shape == (720, 1280, 3)
    assert main(["synth", "golf-teeshot", str(out), "--frames", "3"]) == 2
    assert "--frames does not apply" in capsys.readouterr().err
    assert main(["synth", "flow-sim1", str(out), "--size", "1080p"]) == 2
    assert main(["synth", "golf-teeshot", str(out), "--occlusion", "3", "2"]) == 2
    assert "--occlusion" in capsys.readouterr().err


def test_cli_flow_sims_are_unchanged(tmp_path: Path) -> None:
    cli, direct = tmp_path / "cli.mcap", tmp_path / "direct.mcap"
    assert main(["synth", "flow-sim1", str(cli)]) == 0
    write_flow_sim(direct, FlowSimConfig(scene="flow-sim1"))
    assert _records(cli) == _records(direct)  # the same log; only the provenance's command line differs


def _records(path: Path) -> tuple[list, list]:
    from mcap.reader import make_reader

    with open(path, "rb") as fh:
        reader = make_reader(fh)
        messages = [(c.topic, m.log_time, m.data) for _, c, m in reader.iter_messages(log_time_order=False)]
    with open(path, "rb") as fh:
        metadata = [(m.name, {k: v for k, v in m.metadata.items() if k != "command_line"})
                    for m in make_reader(fh).iter_metadata()]
    return messages, metadata
