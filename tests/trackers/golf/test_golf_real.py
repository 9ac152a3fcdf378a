"""Issue 10 on real footage (skipped when ../shared/data/real is absent): one mark per clip, as a user would."""

from pathlib import Path

import numpy as np
import polars as pl
import pytest

from trackreplay.replay.cli.main import main as cli
from trackreplay.replay.core.engine import ReplayRequest, replay

ROOT = Path(__file__).resolve().parents[3]
REAL = ROOT.parent / "shared" / "data" / "real"
APPROACH = REAL / "golf_broadcast_approach" / "demo.mp4"
IRON = REAL / "golf_iron_shot_sky"


def marked_log(tmp: Path, video: Path, marks: str, encoding: str = "jpeg", source: list[str] | None = None) -> Path:
    """Record ``video`` (or the record options ``source``, e.g. an image folder) and mark it with ``marks`` rows."""
    (tmp / "marks.csv").write_text("frame,x,y,w,h\n" + marks)
    recorded = source if source is not None else ["--video", str(video), "--encoding", encoding]
    for args in (["record", str(tmp / "clip.mcap"), *recorded],
                 ["annotate", str(tmp / "clip.mcap"), "--from-csv", str(tmp / "marks.csv"), "--label", "ball",
                  "--out", str(tmp / "marked.mcap")]):
        try:
            cli(args)
        except SystemExit as exc:
            assert not exc.code
    return tmp / "marked.mcap"


def against(traj: pl.DataFrame, ref: pl.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    j = ref.join(traj.select("frame", pl.col("x").alias("tx"), pl.col("y").alias("ty"), "status"), on="frame", how="left")
    measured = (j["status"] == "measured").fill_null(False).to_numpy()
    d = np.hypot(j["tx"].to_numpy().astype(float) - j["x"].to_numpy(), j["ty"].to_numpy().astype(float) - j["y"].to_numpy())
    return measured, d


@pytest.mark.skipif(not APPROACH.is_file(), reason="../shared/data/real/golf_broadcast_approach is absent")
def test_broadcast_approach_one_mark_at_frame_20(tmp_path):
    log = marked_log(tmp_path, APPROACH, "20,312,200,8,8\n")
    traj = replay(ReplayRequest(log=log, tracker="golf")).trajectory
    ref = pl.read_csv(ROOT / "docs" / "data" / "golf_broadcast_reference.csv", comment_prefix="#")
    measured, d = against(traj, ref)
    assert measured.mean() >= 0.8  # issue 10: >= 80 % of frames 12-206 measured
    assert (d[measured] <= 5).mean() >= 0.9  # ... and >= 90 % of those within 5 px
    assert not (d[measured] > 25).any()  # no confident wrong rows


@pytest.mark.skipif(not APPROACH.is_file(), reason="../shared/data/real/golf_broadcast_approach is absent")
@pytest.mark.parametrize("mark, encoding", [("12,343,177,6,6\n", "jpeg"), ("20,313,201,6,6\n", "png")])
def test_broadcast_approach_the_empty_cup_is_never_measured(tmp_path, mark, encoding):
    """Two reviews: one mark at 12 measured pieces of the empty cup's liner on 213-219 and 224 (up to
    31 px off); the clip recorded losslessly (PNG) measured the liner on 219-233. The ball rolls over
    the liner from 208 and is in the hole from 217 (docs/golf_real.md): nothing is measured there
    (the liner was beside the ball before the loss: seen_before). (Today nothing from 207 on either.)"""
    log = marked_log(tmp_path, APPROACH, mark, encoding)
    traj = replay(ReplayRequest(log=log, tracker="golf")).trajectory
    assert not (traj.filter(pl.col("frame") >= 217)["status"] == "measured").any()
    ref = pl.read_csv(ROOT / "docs" / "data" / "golf_broadcast_reference.csv", comment_prefix="#")
    measured, d = against(traj, ref)
    assert measured.mean() >= 0.8 and not (d[measured] > 25).any()


@pytest.mark.skipif(not (IRON / "vid1.mp4").is_file(), reason="../shared/data/real/golf_iron_shot_sky is absent")
def test_iron_shot_into_the_sky_one_mark_at_launch(tmp_path):
    log = marked_log(tmp_path, IRON / "vid1.mp4", "458,593,1016,22,22\n")
    traj = replay(ReplayRequest(log=log, tracker="golf")).trajectory
    measured, d = against(traj, pl.read_csv(IRON / "reference.csv"))
    launch = pl.read_csv(IRON / "reference.csv")["frame"].to_numpy() <= 490
    assert measured[launch].sum() >= launch.sum() - 1 and (d[launch & measured] <= 5).all()  # launch and tree line held
    assert (measured & (d <= 5)).mean() >= 0.95  # issue 10: >= 95 % of the reference frames measured within 5 px
    assert not (d[measured] > 25).any()  # no confident wrong row
    assert not (traj.filter(pl.col("frame") >= 612)["status"] == "measured").any()  # gone out of the top: never measured


@pytest.mark.skipif(not (IRON / "vid1.mp4").is_file(), reason="../shared/data/real/golf_iron_shot_sky is absent")
def test_iron_shot_turned_on_its_side_is_still_followed(tmp_path):
    """A review: the iron shot turned to 1280x720 lost the ball two frames after launch, the pixel
    settings scaled by the frame's height (720) for a ball sized as in a 1280-line frame. The marked
    ball's own size now widens them (GolfConfig.reference_ball_px). Frames 440-639 only, for time."""
    import cv2

    frames = tmp_path / "frames"
    frames.mkdir()
    capture = cv2.VideoCapture(str(IRON / "vid1.mp4"))
    for _ in range(440):  # read, not seeked: a seek may land elsewhere with some FFmpeg builds and shift the reference
        assert capture.grab()
    for i in range(200):
        ok, image = capture.read()
        assert ok
        cv2.imwrite(str(frames / f"{i:04d}.jpg"), cv2.rotate(image, cv2.ROTATE_90_CLOCKWISE), [cv2.IMWRITE_JPEG_QUALITY, 95])
    # frame 458, the box turned with the picture
    log = marked_log(tmp_path, frames, "18,242,593,22,22\n", source=["--images", str(frames), "--fps", "60", "--quiet"])
    traj = replay(ReplayRequest(log=log, tracker="golf")).trajectory
    ref = pl.read_csv(IRON / "reference.csv")  # turned: x' = 1279 - y, y' = x; frames from 440
    turned = ref.select((pl.col("frame") - 440).alias("frame"), (1279 - pl.col("y")).alias("x"), pl.col("x").alias("y"))
    measured, d = against(traj, turned)
    assert (measured & (d <= 5)).mean() >= 0.9 and not (d[measured] > 25).any()
    assert not (traj.filter(pl.col("frame") >= 612 - 440)["status"] == "measured").any()


@pytest.mark.skipif(not APPROACH.is_file(), reason="../shared/data/real/golf_broadcast_approach is absent")
def test_broadcast_approach_at_three_quarter_resolution_does_not_follow_pieces_of_the_ball(tmp_path):
    """docs/golf_robustness.md: the clip resized to 0.75 marked pieces of the ball (a highlight, a
    rim: blobs of 1-5 px of a ball of 40-250 px), the targets followed them down and specks by the hole were
    `measured` after the drop (15 of 19 rows; 80 % within 5 px). A smaller blob now moves the target
    area at half the rate (blobs.target_shrink_rate)."""
    import cv2

    frames = tmp_path / "frames"
    frames.mkdir()
    capture = cv2.VideoCapture(str(APPROACH))
    k = 0
    while True:
        ok, image = capture.read()
        if not ok:
            break
        small = cv2.resize(image, (round(image.shape[1] * 0.75), round(image.shape[0] * 0.75)), interpolation=cv2.INTER_AREA)
        cv2.imwrite(str(frames / f"{k:05d}.jpg"), small, [cv2.IMWRITE_JPEG_QUALITY, 95])
        k += 1
    log = marked_log(tmp_path, frames, "20,234,150,6,6\n", source=["--images", str(frames), "--fps", "30", "--quiet"])
    traj = replay(ReplayRequest(log=log, tracker="golf")).trajectory
    ref = pl.read_csv(ROOT / "docs" / "data" / "golf_broadcast_reference.csv", comment_prefix="#")
    ref = ref.with_columns(((pl.col("x") + 0.5) * 0.75 - 0.5), ((pl.col("y") + 0.5) * 0.75 - 0.5))
    measured, d = against(traj.filter(pl.col("frame") >= 20), ref.filter(pl.col("frame") >= 20))
    assert (measured & (d <= 3.75)).mean() >= 0.9 and not (d[measured] > 18.75).any()
    assert not (traj.filter(pl.col("frame") >= 217)["status"] == "measured").any()
