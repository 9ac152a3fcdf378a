"""Looking again along the fitted flight (replay.flight_rescan): the matched filter on pictures with
known answers, and end to end on a synthetic tee shot with ground truth."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import cv2
import numpy as np
import polars as pl
import pytest

from trackreplay.replay.cli.main import main
from trackreplay.replay.analysis.flight_rescan import ExpectedBall, RescanConfig, ball_template, exposed, look
from trackreplay.replay.log.groundtruth import read_groundtruth
from trackreplay.replay.log.reader import LogReader

pytestmark = pytest.mark.slow  # minutes of synthetic scenes: run by `pytest -m slow` (CI runs both)

IDENTITY = np.eye(3)
SIZE = 160


def _sky(seed: int, puffs: list[tuple[int, int]]) -> np.ndarray:
    """Sensor noise (sigma 1.5) on a level sky, with bright static cloud puffs (+40, 5 px) at ``puffs``."""
    rng = np.random.default_rng(seed)
    sky = 90.0 + rng.normal(0.0, 1.5, (SIZE, SIZE))
    for x, y in puffs:
        cv2.circle(sky, (x, y), 2, 130.0, -1)
    return sky


def _with_ball(sky: np.ndarray, centre: tuple[float, float], path: np.ndarray, diameter: float, contrast: float) -> np.ndarray:
    """``sky`` with the ball's smear added: the template (weights summing to 1) scaled to ``contrast`` levels at a still ball's peak."""
    template = ball_template(diameter, path)
    still = ball_template(diameter, np.zeros((1, 2))).max()
    half = template.shape[0] // 2
    out = sky.copy()
    cx, cy = int(round(centre[0])), int(round(centre[1]))
    out[cy - half:cy + half + 1, cx - half:cx + half + 1] += template * (contrast / still)
    return out


def _u8(image: np.ndarray) -> np.ndarray:
    return np.clip(np.round(image), 0, 255).astype(np.uint8)


def _ball(centre, path, diameter=3.0) -> ExpectedBall:
    return ExpectedBall(0, np.array(centre, float), np.asarray(path, float), diameter, 0.0)


PATH = np.stack([np.linspace(-15.0, 15.0, 33), np.linspace(-6.0, 6.0, 33)], axis=1)  # 32 px a frame


def test_template_sums_to_one_and_is_centred_on_its_path() -> None:
    for diameter, path in ((1.0, np.zeros((1, 2))), (3.0, np.zeros((1, 2))), (4.0, exposed(PATH, 0.5)), (2.0, PATH)):
        t = ball_template(diameter, path)
        assert t.dtype == np.float32 and abs(float(t.sum()) - 1.0) < 1e-5
        half = t.shape[0] // 2
        ys, xs = np.mgrid[:t.shape[0], :t.shape[1]]
        centroid = np.array([(t * xs).sum(), (t * ys).sum()]) - half
        assert np.hypot(*(centroid - path.mean(axis=0))) < 0.3
    assert ball_template(4.0, exposed(PATH, 0.5)).shape[0] < ball_template(4.0, PATH).shape[0]  # half the smear


def test_a_faint_streak_is_found_where_the_flight_puts_it() -> None:
    """A ball 32 levels above the sky at a still ball's peak, smeared over 16 px: at most +7 levels in
    any pixel, as much as the noise's own peaks over the crop; the template over its whole length finds it."""
    puffs = [(40, 40), (120, 50), (60, 120), (110, 115)]
    truth = (80.0, 80.0)
    here = _u8(_with_ball(_sky(1, puffs), truth, exposed(PATH, 0.5), 3.0, 32.0))
    # the world behind it: the same clouds, the ball elsewhere
    before = _u8(_with_ball(_sky(2, puffs), (48.0, 67.0), exposed(PATH, 0.5), 3.0, 32.0))
    after = _u8(_with_ball(_sky(3, puffs), (112.0, 93.0), exposed(PATH, 0.5), 3.0, 32.0))
    cfg = RescanConfig()
    seen = look(here, _ball((81.5, 79.0), PATH), cfg, 1.0, [(before, IDENTITY), (after, IDENTITY)])
    assert seen is not None and np.hypot(*(seen.point - truth)) < 1.5
    assert seen.snr >= cfg.min_snr and seen.new_snr >= cfg.min_new_snr and seen.exposure == pytest.approx(0.5)
    # nothing there: no sighting
    empty = _u8(_sky(4, puffs))
    assert look(empty, _ball((81.5, 79.0), PATH), cfg, 1.0, [(before, IDENTITY), (after, IDENTITY)]) is None
    # no frame showing the world behind it: the question is not asked
    assert look(here, _ball((81.5, 79.0), PATH), cfg, 1.0, []) is None
    # a fit unsure of the place: not asked either
    unsure = dataclasses.replace(_ball((81.5, 79.0), PATH), sigma=2.0)
    assert look(here, unsure, cfg, 1.0, [(before, IDENTITY), (after, IDENTITY)]) is None


def test_a_static_cloud_puff_in_the_gate_is_not_the_ball() -> None:
    """A ball-sized bright puff right where the flight puts the ball, in every frame: it stands out of
    its local background (the top-hat alone would take it) but not out of the world behind it."""
    puffs = [(80, 80), (30, 120)]
    here, before, after = (_u8(_sky(s, puffs)) for s in (5, 6, 7))
    cfg = RescanConfig()
    ball = _ball((80.0, 80.0), np.zeros((33, 2)))
    assert look(here, ball, dataclasses.replace(cfg, min_new_snr=-1e9), 1.0, [(before, IDENTITY), (after, IDENTITY)]) is not None
    assert look(here, ball, cfg, 1.0, [(before, IDENTITY), (after, IDENTITY)]) is None


def test_the_gate_is_not_fooled_by_something_brighter_just_outside() -> None:
    """A bright moving blob 9 px from the fitted place (outside a 5 px gate): its flank inside the
    gate is no local maximum, so nothing is found."""
    here = _u8(_with_ball(_sky(8, []), (89.0, 80.0), np.zeros((1, 2)), 4.0, 80.0))
    before, after = _u8(_sky(9, [])), _u8(_sky(10, []))
    assert look(here, _ball((80.0, 80.0), np.zeros((33, 2))), RescanConfig(), 1.0, [(before, IDENTITY), (after, IDENTITY)]) is None


@pytest.fixture(scope="module")
def rescanned(golf_short: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, Path]:
    out = tmp_path_factory.mktemp("rescan")
    traj, found = out / "t.parquet", out / "r.parquet"
    assert main(["replay", str(golf_short), "--tracker", "golf", "--export", str(traj), "--interpolate", "none", "--quiet"]) == 0
    assert main(["flight", str(traj), str(golf_short), "--rescan", str(found)]) == 0
    return traj, found, golf_short


def test_rescan_end_to_end_finds_only_the_ball(rescanned, capsys) -> None:
    traj, found, log = rescanned
    before, after = pl.read_parquet(traj), pl.read_parquet(found)
    truth = read_groundtruth(LogReader(log)).filter(pl.col("id") == 1).select("frame", pl.col("x").alias("tx"),
                                                                               pl.col("y").alias("ty"), "visible")
    new = after.filter(pl.col("fill") == "rescan").join(truth, on="frame", how="left")
    assert new.height > 0, "the short tee shot has frames the tracker missed and the flight finds"
    assert new["status"].unique().to_list() == ["measured"]
    assert new["visible"].all(), "a frame found where the ball cannot be seen"
    error = ((new["x"] - new["tx"]) ** 2 + (new["y"] - new["ty"]) ** 2).sqrt()
    assert float(error.max()) < 5.0
    assert new["w"].is_null().all() and new["dx"].is_not_null().all()  # a line of sight, no measured size
    # the tracker's own measurements are untouched, and no frame was measured before that is now found
    kept = after.filter(pl.col("fill").is_null())
    measured = before.filter(pl.col("status") == "measured")
    assert kept.filter(pl.col("status") == "measured").drop("fill").equals(measured)
    assert not set(new["frame"].to_list()) & set(measured["frame"].to_list())


def test_rescan_is_deterministic(rescanned, tmp_path) -> None:
    traj, found, log = rescanned
    again = tmp_path / "again.parquet"
    assert main(["flight", str(traj), str(log), "--rescan", str(again)]) == 0
    assert pl.read_parquet(again).equals(pl.read_parquet(found))


def test_rescan_refuses_a_bad_suffix_before_fitting(rescanned, tmp_path, capsys) -> None:
    traj, _, log = rescanned
    assert main(["flight", str(traj), str(log), "--rescan", str(tmp_path / "r.txt")]) == 2
    assert "--rescan" in capsys.readouterr().err


def test_rescan_frames_have_their_own_lines_of_sight_in_the_3d_view(rescanned, tmp_path) -> None:
    import rerun.chunk as rc

    traj, found, log = rescanned
    rrd = tmp_path / "flight.rrd"
    assert main(["flight", str(traj), str(log), "--rescan", str(tmp_path / "r.parquet"), "--rrd", str(rrd)]) == 0
    paths = {str(chunk.entity_path) for chunk in rc.RrdReader(str(rrd)).stream()}
    assert {"/flight/lines_of_sight", "/flight/lines_of_sight_rescan", "/flight/path", "/flight/ball"} <= paths
    plain = tmp_path / "plain.rrd"
    assert main(["flight", str(traj), str(log), "--rrd", str(plain)]) == 0
    assert "/flight/lines_of_sight_rescan" not in {str(chunk.entity_path) for chunk in rc.RrdReader(str(plain)).stream()}


def test_a_place_the_neighbours_did_not_see_is_not_asked() -> None:
    """Neighbours that saw nothing of the crop (their picture ends before it) would make 'the world
    behind the ball' a constant 255, and a static puff would then stand out of it: not asked."""
    puffs = [(80, 80)]
    here, before, after = (_u8(_sky(s, puffs)) for s in (11, 12, 13))
    ball = _ball((80.0, 80.0), np.zeros((33, 2)))
    away = np.array([[1.0, 0.0, 1000.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])  # their pixels land far off this picture
    cfg = RescanConfig(min_new_snr=-1e9)  # even with the world test off, the place must be seen by min_world frames
    assert look(here, ball, cfg, 1.0, [(before, away), (after, away)]) is None
    assert look(here, ball, cfg, 1.0, [(before, IDENTITY), (after, away)]) is None  # one of two: too few
    assert look(here, ball, cfg, 1.0, [(before, IDENTITY), (after, IDENTITY)]) is not None  # (the puff itself is there)


def test_one_grey_level_on_a_flat_sky_is_no_ball() -> None:
    """On a perfectly flat (clipped, compressed) sky the response's spread is 0: a single level of
    difference must not become any number of sigmas."""
    flat = np.full((SIZE, SIZE), 200, np.uint8)
    here = flat.copy()
    here[80, 80] = 201
    ball = _ball((80.0, 80.0), np.zeros((33, 2)))
    assert look(here, ball, RescanConfig(), 1.0, [(flat, IDENTITY), (flat.copy(), IDENTITY)]) is None


def _damaged_copy(src: Path, dst: Path, frame: int) -> None:
    """``src`` with the picture of ``frame`` replaced by bytes that decode as nothing."""
    from foxglove_schemas_protobuf.CompressedImage_pb2 import CompressedImage
    from mcap.reader import make_reader
    from mcap.writer import Writer

    with open(src, "rb") as fin, open(dst, "wb") as fout:
        writer, schemas, channels, k = Writer(fout), {}, {}, 0
        writer.start()
        for schema, channel, message in make_reader(fin).iter_messages(log_time_order=True):
            if schema.id not in schemas:
                schemas[schema.id] = writer.register_schema(schema.name, schema.encoding, schema.data)
            if channel.id not in channels:
                channels[channel.id] = writer.register_channel(channel.topic, channel.message_encoding, schemas[schema.id], channel.metadata)
            data = message.data
            if channel.topic == "/camera/image":
                if k == frame:
                    image = CompressedImage()
                    image.ParseFromString(data)
                    image.data = b"\xff\xd8 not a picture"
                    data = image.SerializeToString()
                k += 1
            writer.add_message(channels[channel.id], message.log_time, data, message.publish_time, message.sequence)
        writer.finish()


def test_a_damaged_picture_is_skipped_and_named(rescanned, tmp_path, capsys) -> None:
    traj, found, log = rescanned
    first = int(pl.read_parquet(found).filter(pl.col("fill") == "rescan")["frame"].min())
    damaged = tmp_path / "damaged.mcap"
    _damaged_copy(log, damaged, first)
    out = tmp_path / "r.parquet"
    capsys.readouterr()
    assert main(["flight", str(traj), str(damaged), "--rescan", str(out)]) == 0
    err = capsys.readouterr().err
    assert f"frame {first} not searched" in err and "message" in err
    again = pl.read_parquet(out)
    assert first not in again.filter(pl.col("fill") == "rescan")["frame"].to_list()


def test_a_second_rescan_keeps_what_the_first_found_and_other_tracks_alone(rescanned, tmp_path) -> None:
    traj, found, log = rescanned
    # another tracker's track 1 in the same table: untouched, and no row of it taken as the ball's
    other = pl.read_parquet(traj).with_columns(tracker=pl.lit("colorpf"), x=pl.col("x") + 300.0)
    mixed = tmp_path / "mixed.parquet"
    pl.concat([pl.read_parquet(found), other.with_columns(fill=pl.lit(None, pl.String))]).write_parquet(mixed)
    out = tmp_path / "again.parquet"
    assert main(["flight", str(mixed), str(log), "--rescan", str(out), "--track", "1"]) == 0
    again = pl.read_parquet(out)
    first = pl.read_parquet(found).filter(pl.col("fill") == "rescan")["frame"].to_list()
    rescan_rows = again.filter(pl.col("fill") == "rescan")
    assert set(first) <= set(rescan_rows["frame"].to_list())  # still marked as found, not as the tracker's own
    assert rescan_rows["tracker"].unique().to_list() == ["golf"]
    assert again.filter(pl.col("tracker") == "colorpf").drop("fill").equals(other.sort("frame"))
