"""Offline RTS smoothing (issue 13): better than the causal track, gaps filled with a std, deterministic."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import polars as pl
import pytest

from trackreplay.replay.cli.main import main
from trackreplay.replay.core.export import fill_gaps, read_trajectory, write_trajectory
from trackreplay.replay.analysis.smooth import SMOOTH_COLUMNS, smooth_trajectory
from trackreplay.replay.core.trajectory import FLOAT_COLUMNS, state_row, trajectory_table
from trackreplay.trackers.base import TrackState


def _truth(n: int = 120) -> np.ndarray:
    k = np.arange(n, dtype=float)
    return np.stack([100 + 40 * np.cos(k / 25.0), 80 + 30 * np.sin(k / 25.0)], axis=1)


def _noisy_track(gap: tuple[int, int] = (50, 60), seed: int = 0) -> tuple[pl.DataFrame, np.ndarray]:
    """A causal-looking track: noisy measurements (noise grows as confidence falls), a gap of
    ``predicted`` then ``lost`` rows, and one wrong blob."""
    rng = np.random.default_rng(seed)
    truth = _truth()
    rows = []
    for k, (x, y) in enumerate(truth):
        conf = 0.5 + 0.5 * (k % 3 == 0)
        if gap[0] <= k < gap[0] + 3:
            state = TrackState(1, x=x + 8.0 * (k - gap[0] + 1), y=y, w=5.0, h=5.0, status="predicted", confidence=0.1)
        elif gap[0] + 3 <= k < gap[1]:
            state = TrackState(1, status="lost")
        else:
            sx, sy = rng.normal(0.0, 1.5 / np.sqrt(conf), 2)
            if k == 90:
                sx += 60.0  # a wrong blob
            state = TrackState(1, x=x + sx, y=y + sy, w=5.0, h=5.0, vx=None, vy=None, status="measured", confidence=conf)
        if k == 70:
            continue  # a frame without a row at all
        rows.append(state_row("golf", k, k * 33_333_333, state))
    return trajectory_table(rows), truth


def _rmse(df: pl.DataFrame, truth: np.ndarray, frames: np.ndarray) -> float:
    d = df.filter(pl.col("frame").is_in(frames.tolist()) & pl.col("x").is_not_null()).sort("frame")
    assert d.height == len(frames)
    est = d.select("x", "y").to_numpy()
    return float(np.sqrt(np.mean(np.sum((est - truth[d["frame"].to_numpy()]) ** 2, axis=1))))


def test_rts_beats_the_causal_track_and_linear_gap_filling() -> None:
    df, truth = _noisy_track()
    out, fits = smooth_trajectory(df)
    measured = df.filter((pl.col("status") == "measured") & (pl.col("frame") != 90))["frame"].to_numpy()
    assert _rmse(out, truth, measured) < 0.6 * _rmse(df, truth, measured)
    gap = np.arange(50, 60)
    linear = fill_gaps(df.filter(pl.col("status") != "predicted"), "linear", max_gap=15)
    assert _rmse(out, truth, gap) < _rmse(linear, truth, gap)  # the arc is curved: a chord cuts it
    assert fits[0].outliers == 1 and fits[0].observations == len(measured) + 1


def test_filled_rows_are_interpolated_with_std_and_say_how() -> None:
    df, _ = _noisy_track()
    out, _ = smooth_trajectory(df)
    assert out.columns == list(SMOOTH_COLUMNS)
    assert out["frame"].to_list() == list(range(120))  # the absent frame 70 is added
    gap = out.filter(pl.col("frame").is_between(50, 59))
    assert gap["status"].to_list() == ["interpolated"] * 10
    assert gap["fill"].to_list() == ["rts_gap"] * 10
    assert gap["x_std"].is_not_null().all() and gap["y_std"].is_not_null().all()
    # the std grows towards the middle of the gap and is larger than on measured frames
    std = gap["x_std"].to_numpy()
    assert std.max() > out.filter(pl.col("frame") == 20)["x_std"][0]
    assert out.filter(pl.col("frame") == 70)["fill"][0] == "rts_gap"
    assert out.filter(pl.col("frame") == 70)["t_ns"][0] == 70 * 33_333_333
    assert out.filter(pl.col("frame") == 90)["fill"][0] == "rts_outlier"
    assert set(out["fill"].drop_nulls().to_list()) <= {"rts", "rts_gap", "rts_outlier"}


def test_long_gaps_and_track_ends_are_not_extrapolated() -> None:
    df, _ = _noisy_track(gap=(40, 80))
    out, _ = smooth_trajectory(df)
    gap = out.filter(pl.col("frame").is_between(43, 79))
    assert set(gap["status"].to_list()) == {"lost"} and gap["x"].null_count() == gap.height
    kept = out.filter(pl.col("frame").is_between(40, 42))  # the tracker's predictions before a long gap stay its own
    assert kept["status"].to_list() == ["predicted"] * 3 and kept["fill"].null_count() == 3


def test_deterministic_and_written(tmp_path) -> None:
    df, _ = _noisy_track()
    a, _ = smooth_trajectory(df)
    b, _ = smooth_trajectory(df)
    assert a.equals(b)
    write_trajectory(a, tmp_path / "s.parquet")
    back = pl.read_parquet(tmp_path / "s.parquet")
    assert back.equals(a)
    assert read_trajectory(tmp_path / "s.parquet").height == a.height  # still a ★ trajectory table


GOLDEN = Path(__file__).resolve().parents[2] / "golden"


def test_cli_smooth_and_replay_smooth_on_the_golden_flow_log(tmp_path) -> None:
    log = GOLDEN / "flow-sim1-24f.mcap"
    traj = tmp_path / "t.parquet"
    assert main(["replay", str(log), "--tracker", "flow", "--export", str(traj), "--interpolate", "none", "--quiet"]) == 0
    out = tmp_path / "s.parquet"
    assert main(["smooth", str(traj), str(log), "--out", str(out)]) == 0
    smoothed = pl.read_parquet(out)
    assert smoothed.height == 24 and smoothed["fill"].to_list() == ["rts"] * 24
    # replay --smooth (which also has the raw measurements): test_replay_smooth_uses_raw_measurements...


def test_empty_and_positionless_tracks() -> None:
    empty = trajectory_table([])
    out, fits = smooth_trajectory(empty)
    assert out.is_empty() and fits == []
    lost = trajectory_table([state_row("flow", k, k, TrackState(1, status="lost")) for k in range(3)])
    out, fits = smooth_trajectory(lost)
    assert out["status"].to_list() == ["lost"] * 3 and fits == []


def test_replay_smooth_uses_raw_measurements_and_keeps_the_digest(tmp_path) -> None:
    """replay --smooth observes the flow tracker's raw centroid (before its Kalman filter): closer
    to the truth than the causal track; asking for the observations leaves the digest alone."""
    from trackreplay.replay.core.engine import ReplayRequest, replay
    from trackreplay.replay.analysis.eval import evaluate
    from trackreplay.replay.log.groundtruth import read_groundtruth
    from trackreplay.replay.log.reader import LogReader

    log = GOLDEN / "flow-sim1-24f.mcap"
    plain = replay(ReplayRequest(log=log, tracker="flow"))
    res = replay(ReplayRequest(log=log, tracker="flow", observations=True))
    assert res.digest == plain.digest and plain.observations is None
    assert res.observations.height >= 20 and res.observations["zx"].is_not_null().all()
    smoothed, _ = smooth_trajectory(res.trajectory, observations=res.observations)
    gt = read_groundtruth(LogReader(log))
    causal = evaluate(res.trajectory, gt)[1]["centre_error"].drop_nulls().to_numpy()
    smooth = evaluate(smoothed, gt)[1]["centre_error"].drop_nulls().to_numpy()
    assert np.sqrt(np.mean(smooth**2)) < np.sqrt(np.mean(causal**2))
    out = tmp_path / "s.parquet"
    assert main(["replay", str(log), "--tracker", "flow", "--smooth", "--export", str(out), "--quiet"]) == 0
    assert pl.read_parquet(out).select("x", "y").equals(smoothed.select("x", "y"))


def _walking_group(fps: float = 24.0):
    """A group walking at constant velocity in the camera frame, raw 3-D points with the stereo
    covariance (depth noisier), a 6-frame hole: (trajectory, observations, truth)."""
    from trackreplay.replay.analysis.smooth import observations_table

    rng = np.random.default_rng(0)
    n = 60
    k = np.arange(n, dtype=float)
    truth = np.stack([-2.0 + 0.05 * k, 0.5 + 0.0 * k, 8.0 - 0.02 * k], axis=1)  # m; 1.2 m/s across, 0.48 m/s closer
    R = np.diag([0.03, 0.03, 0.15]) ** 2
    rows, obs = [], []
    for i in range(n):
        if 30 <= i < 36:
            rows.append(state_row("groups", i, int(i * 1e9 / fps), TrackState(4, x=1.0, y=1.0, w=2.0, h=2.0, status="predicted")))
            continue
        z = truth[i] + rng.multivariate_normal(np.zeros(3), R)
        X, Y, Z = (float(v) for v in z)
        rows.append(state_row("groups", i, int(i * 1e9 / fps), TrackState(4, x=1.0, y=1.0, w=2.0, h=2.0, X=X, Y=Y, Z=Z, status="measured")))
        obs.append({"tracker": "groups", "track_id": 4, "frame": i, "zX": X, "zY": Y, "zZ": Z, "rXX": R[0, 0], "rXY": 0.0,
                    "rXZ": 0.0, "rYY": R[1, 1], "rYZ": 0.0, "rZZ": R[2, 2]})
    return trajectory_table(rows), observations_table(obs), truth


def test_group_tracks_smoothed_in_3d_from_raw_points() -> None:
    """The walking group: the EKF model's RTS beats the raw points, fills the hole with a std and
    gives VX, VY, VZ in m/s."""
    fps = 24.0
    table, obs, truth = _walking_group(fps)
    out, fits = smooth_trajectory(table, observations=obs)
    assert fits[0].tracker == "groups" and fits[0].filled == 6
    P = out.select("X", "Y", "Z").to_numpy()
    raw = table.select("X", "Y", "Z").to_numpy().astype(float)
    seen = np.isfinite(raw).all(axis=1)
    assert np.sqrt(np.mean(np.sum((P - truth) ** 2, axis=1))) < 0.5 * np.sqrt(np.mean(np.sum((raw[seen] - truth[seen]) ** 2, axis=1)))
    hole = out.filter(pl.col("frame").is_between(30, 35))
    assert hole["status"].to_list() == ["interpolated"] * 6 and hole["fill"].to_list() == ["rts_gap"] * 6
    assert (hole["Z_std"].to_numpy() > 0).all()
    V = out.select("VX", "VY", "VZ").to_numpy()
    assert np.allclose(np.median(V, axis=0), [0.05 * fps, 0.0, -0.02 * fps], atol=0.15)


def test_group_smoothing_reads_the_ekf_config_the_replay_used() -> None:
    """The 3-D model's process noise is the group EKF's own at the config replayed (``configs``), not
    the defaults'; the defaults given explicitly change nothing."""
    from trackreplay.trackers.groups.config import EkfConfig, GroupsConfig

    table, obs, _ = _walking_group()
    default, default_fits = smooth_trajectory(table, observations=obs)
    same, _ = smooth_trajectory(table, observations=obs, configs={"groups": GroupsConfig()})
    assert same.equals(default)
    brisk, fits = smooth_trajectory(table, observations=obs, configs={"groups": GroupsConfig(ekf=EkfConfig(accel_sigma=0.02))})
    assert default_fits[0].q == pytest.approx(0.0015**2) and fits[0].q == pytest.approx(0.02**2)
    assert fits[0].noise.startswith("q 0.0004 (m/frame²)², R scale ")
    # more process noise: the smoothed track is less certain and its velocity follows the points' noise
    assert brisk["X_std"].mean() > 1.5 * default["X_std"].mean()
    assert brisk["VX"].std() > 3.0 * default["VX"].std()


def test_replay_smooth_smooths_groups_with_the_config_it_replayed(tmp_path: Path, capsys) -> None:
    """``replay --config g.toml --smooth`` hands the smoother the config it replayed (ReplayResult.config):
    the fit's q is that config's EKF acceleration squared."""
    log = GOLDEN / "groups-crossing-320x240.mcap"
    toml = tmp_path / "g.toml"
    toml.write_text("[groups.ekf]\naccel_sigma = 0.006\n")
    out = tmp_path / "s.parquet"
    assert main(["replay", str(log), "--tracker", "groups", "--config", str(toml), "--smooth", "--export", str(out),
                 "--quiet"]) == 0
    lines = [x for x in capsys.readouterr().out.splitlines() if x.startswith("smooth groups/")]
    assert lines and all("q 3.6e-05 (m/frame²)²" in x for x in lines)


def test_golden_groups_log_smoothed_in_3d_from_its_points() -> None:
    """The group tracker's raw measurements (mean [u v d] of each group's points) reach the smoother:
    every measured group row observed in 3-D, with velocity (m/s) and position std (m)."""
    from trackreplay.replay.core.engine import ReplayRequest, replay

    res = replay(ReplayRequest(log=GOLDEN / "groups-crossing-320x240.mcap", tracker="groups", observations=True))
    obs = res.observations
    assert obs.height > 0 and obs["zZ"].is_not_null().all()
    # in the trajectory's own frame (the world, Z up: the golden log carries the rig's pose), within
    # the EKF's smoothing of the raw points; the depth, mostly along world Y here, the noisiest
    assert res.position_frame == "world"
    j = obs.join(res.trajectory, on=["track_id", "frame"])
    assert j.height == obs.height
    assert j.select(((pl.col("zX") - pl.col("X")) ** 2 + (pl.col("zY") - pl.col("Y")) ** 2
                     + (pl.col("zZ") - pl.col("Z")) ** 2).sqrt().max()).item() < 0.5
    assert (obs["rYY"] > obs["rXX"]).all() and (obs["rYY"] > obs["rZZ"]).all()
    out, fits = smooth_trajectory(res.trajectory, observations=obs)
    assert fits and all(f.tracker == "groups" for f in fits)
    rts = out.filter(pl.col("fill") == "rts")
    assert rts.height >= obs.height - sum(f.outliers for f in fits)
    assert rts.select("VX", "VY", "VZ", "X_std", "Y_std", "Z_std").null_count().sum_horizontal().item() == 0
    assert (rts["Z_std"] > 0).all() and (rts["Z_std"] < 1.0).all()


def test_a_trajectory_of_another_log_is_refused(tmp_path: Path, capsys) -> None:
    """smooth takes frame times and camera poses from the log: a trajectory whose frames are at
    other times there (replayed from another log) is refused instead of smoothed with them."""
    log = Path(__file__).resolve().parents[2] / "golden" / "flow-sim1-24f.mcap"
    traj, other = tmp_path / "t.parquet", tmp_path / "other.parquet"
    assert main(["replay", str(log), "--tracker", "flow", "--quiet", "--export", str(traj)]) == 0
    assert main(["smooth", str(traj), str(log), "--out", str(tmp_path / "s.parquet")]) == 0
    write_trajectory(read_trajectory(traj).with_columns(pl.col("t_ns") + 1_000_000), other)
    capsys.readouterr()
    assert main(["smooth", str(other), str(log), "--out", str(tmp_path / "s2.parquet")]) == 2
    assert "it was not replayed from this log" in capsys.readouterr().err
    assert not (tmp_path / "s2.parquet").exists()


def test_a_wrong_output_suffix_is_refused_before_any_work(tmp_path: Path, capsys) -> None:
    """`smooth --out x.json` once smoothed the whole log first, then suggested .txt, which smooth refuses."""
    log = GOLDEN / "flow-sim1-24f.mcap"
    for name in ("s.json", "s.txt"):
        assert main(["smooth", str(tmp_path / "missing.parquet"), str(log), "--out", str(tmp_path / name)]) == 2
        err = capsys.readouterr().err.strip()  # about the suffix, not the missing input: checked first
        assert err == (f"trackreplay: error: {tmp_path / name}: a smoothed trajectory is written as .parquet or .csv "
                       "(it has std and fill columns, which MOTChallenge .txt cannot hold)")


def test_replay_smooth_refuses_interpolate(tmp_path: Path, capsys) -> None:
    """`replay --smooth --interpolate cubic` silently smoothed instead: the two fill gaps differently."""
    out = tmp_path / "t.parquet"
    for method in ("cubic", "linear", "none"):
        assert main(["replay", str(tmp_path / "missing.mcap"), "--smooth", "--interpolate", method,
                     "--export", str(out), "--quiet"]) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith(f"trackreplay: error: --interpolate {method} and --smooth exclude each other") and "\n" not in err
    assert not out.exists()


def test_a_filled_group_rows_velocity_is_its_positions_rate() -> None:
    """A review: group tracks' filled rows got vx, vy interpolated on their own while x, y moved linearly."""
    import numpy as np

    from trackreplay.replay.analysis.smooth import _interp, _interp_rate

    f = np.arange(8, dtype=float)
    x = np.array([0.0, np.nan, np.nan, np.nan, 40.0, 41.0, np.nan, 45.0])
    fill = ~np.isfinite(x)
    assert np.allclose(_interp(f, x, fill)[fill], [10.0, 20.0, 30.0, 43.0])
    assert np.allclose(_interp_rate(f, x, fill)[fill], [10.0, 10.0, 10.0, 2.0])  # the slope of the very line drawn


@pytest.mark.parametrize("tracker, rows", [("colorpf", 240), ("flow", 120), ("groups", 400)])
def test_batched_smoother_gives_the_filterpy_smoothers_results(tracker: str, rows: int, benchmark_module) -> None:
    """Issue 33: every track and grid point at once (replay/analysis/rts.py, rts_space.py) gives what the
    per-track filterpy smoother gave, on tracks of different lengths with gaps, absent frames and
    wrong blobs: the same grid point, outliers, fills and statuses, positions within 1e-9."""
    bench = benchmark_module("bench_smooth")
    table = bench.synthetic_trajectory(rows, tracker, tracks=3, seed=5)
    old, old_fits = bench.run_reference(table)
    new, new_fits = smooth_trajectory(table)
    agreement = bench.compare(old, new, old_fits, new_fits)
    assert agreement["fits_equal"] and agreement["other_columns_equal"]
    assert agreement["max_abs_diff_position"] <= 1e-9 and agreement["max_abs_diff_any_column"] <= 1e-8
    assert agreement["max_abs_diff_log_likelihood"] <= 1e-8
    assert sum(f.outliers for f in new_fits) > 0 and new["fill"].to_list().count("rts_gap") > 0  # the cases are exercised


@pytest.mark.parametrize("name", ["flow", "colorpf", "golf", "groups"])
def test_golden_trajectories_smooth_as_with_filterpy(name: str, benchmark_module) -> None:
    bench = benchmark_module("bench_smooth")
    table = pl.read_parquet(GOLDEN / f"{name}.trajectory.parquet")
    old, old_fits = bench.run_reference(table)
    new, new_fits = smooth_trajectory(table)
    agreement = bench.compare(old, new, old_fits, new_fits)
    assert agreement["fits_equal"] and agreement["other_columns_equal"]
    # two implementations' rounding: on the golf golden's calibrated confidences vx_std/vy_std (~0.09)
    # differ by 1.1e-9, a relative 1e-8
    assert agreement["max_abs_diff_any_column"] <= 1e-8


def test_a_track_smooths_the_same_alone_or_beside_longer_ones() -> None:
    """Tracks are filtered side by side in lanes, a shorter one padded: the padding changes nothing."""
    df, _ = _noisy_track()
    other, _ = _noisy_track(gap=(20, 25), seed=3)
    longer = pl.concat([other, other.with_columns(pl.col("frame") + 120, pl.col("t_ns") + 120 * 33_333_333)])
    both = pl.concat([df, longer.with_columns(pl.lit(2, dtype=pl.Int64).alias("track_id"))])
    alone, fits_alone = smooth_trajectory(df)
    together, fits = smooth_trajectory(both)
    mine = together.filter(pl.col("track_id") == 1)
    assert fits[0] == fits_alone[0]
    assert np.abs(mine.select("x", "y", "vx", "vy").to_numpy() - alone.select("x", "y", "vx", "vy").to_numpy()).max() < 1e-9
    assert mine.select("status", "fill").equals(alone.select("status", "fill"))


def test_lanes_put_tracks_of_similar_length_together() -> None:
    from trackreplay.replay.analysis.smooth import _lanes

    lanes = _lanes([10, 1000, 600, 400, 9, 5], width=8)
    assert lanes == [[1, 2], [3], [0, 4, 5]]  # longest first; none padded to more than twice its length
    assert _lanes([5] * 5, width=2) == [[0, 1], [2, 3], [4]]


@pytest.mark.parametrize("tracker", ["flow", "groups"])
def test_spans_by_offsets_are_the_spans_by_joins(tracker: str, benchmark_module) -> None:
    """Issue 33: the tracks' spans built from numpy offsets and one gather of the rows (no join holding
    the table twice) are the joins' frames: absent frames inside a span, lost rows before and after it,
    a track never positioned, and a frame given twice (then the joins themselves)."""
    from trackreplay.replay.analysis import smooth

    bench = benchmark_module("bench_smooth")
    df = bench.synthetic_trajectory(3000, tracker, tracks=5, seed=3)
    first = pl.col("frame") < pl.col("frame").min().over("track_id") + 4
    last = pl.col("frame") > pl.col("frame").max().over("track_id") - 3
    df = df.with_columns(pl.when(first | last).then(pl.lit("lost")).otherwise(pl.col("status")).alias("status"))
    never = df.filter(pl.col("track_id") == 5).with_columns(pl.lit(9).cast(df["track_id"].dtype).alias("track_id"),
                                                            pl.lit("lost").alias("status"))
    column = "x" if tracker == "flow" else "X"
    positioned = pl.col(column).is_not_null() & (pl.col("status") != "lost")
    for table in (pl.concat([df, never]), pl.concat([df, df.head(1)])):
        table = smooth._sorted(table.select(smooth.COLUMNS))
        got = smooth._spans(table, positioned)
        want = smooth._spans_join(table.with_columns(pl.struct("tracker", "track_id").rle_id().alias("_tid")), positioned)
        assert got.full.schema == want.full.schema and got.full.equals(want.full, null_equal=True)
        assert np.array_equal(got.starts, want.starts)
        assert got.outside.equals(want.outside, null_equal=True) and got.bare.equals(want.bare, null_equal=True)
        assert got.outside.height >= 25 and got.full["x"].null_count() > 0  # both cases are exercised
    assert got.bare.height == 0 and smooth._spans(smooth._sorted(pl.concat([df, never]).select(smooth.COLUMNS)),
                                                  positioned).bare.height == never.height


def test_a_sorted_table_is_not_copied_and_an_unsorted_one_is_sorted(benchmark_module) -> None:
    from trackreplay.replay.analysis import smooth

    df = benchmark_module("bench_smooth").synthetic_trajectory(600, "flow", tracks=3, seed=1).select(smooth.COLUMNS)
    ordered = df.sort(smooth.KEYS)
    assert smooth._sorted(ordered) is ordered
    shuffled = ordered.sample(fraction=1.0, shuffle=True, seed=0)
    assert smooth._sorted(shuffled).equals(ordered, null_equal=True)
    tied = pl.concat([ordered.head(2), ordered.head(1)])  # a repeated key: a stable sort
    assert smooth._sorted(tied).equals(tied.sort(smooth.KEYS, maintain_order=True), null_equal=True)


def test_log_context_builds_each_frames_camera_when_asked() -> None:
    """Issue 33: the cameras of a PTZ log are kept as each frame's pan, tilt, zoom and focus (32 bytes a
    frame) and built when asked: the same cameras, in the same order, as building every one up front."""
    from trackreplay.replay.analysis.smooth import log_context
    from trackreplay.replay.log.frames import FrameTopics, PtzInterpolator, _ptz_stream
    from trackreplay.replay.log.reader import LogReader
    from trackreplay.schemas.records import LensTable
    from trackreplay.trackers.geometry.ptz import PtzCamera

    log = GOLDEN / "golf-teeshot-640x360.mcap"
    times, cameras = log_context(log)
    reader = LogReader(log)
    topics = FrameTopics.detect(reader)
    lens = LensTable.from_pb(reader.first(topics.lens))
    ptz = PtzInterpolator(_ptz_stream(reader, topics.ptz, None), 100_000_000)
    eager = {i: PtzCamera.from_reading(p, lens) for i in sorted(times, key=times.__getitem__) if (p := ptz.at(times[i]))}
    assert len(eager) == len(cameras) == 60 and list(cameras) == list(eager)
    for frame, cam in eager.items():
        got = cameras[frame]
        assert (got.pan, got.tilt, got.intrinsics) == (cam.pan, cam.tilt, cam.intrinsics)
        assert np.array_equal(got.position, cam.position) and np.array_equal(got.R, cam.R)
        assert frame in cameras and cameras.get(np.int64(frame)) is not None
    assert cameras.get(10_000) is None and 10_000 not in cameras and "0" not in cameras
    with pytest.raises(KeyError):
        cameras[-1]


def _many_flow_tracks() -> pl.DataFrame:
    """Eight tracks on the golden flow log's frames (its frame times): shifted copies of its track, some
    with lost runs and absent frames, one only predicted (nothing to smooth)."""
    base = read_trajectory(GOLDEN / "flow.trajectory.parquet")
    tracks = []
    for k in range(8):
        t = base.with_columns(pl.lit(k + 1, dtype=pl.Int64).alias("track_id"), pl.col("x") + 7.0 * k, pl.col("y") - 3.0 * k)
        if k % 3 == 1:  # a lost run (no position)
            lost = pl.col("frame").is_between(8, 12)
            t = t.with_columns(pl.when(lost).then(pl.lit("lost")).otherwise(pl.col("status")).alias("status"),
                               *(pl.when(lost).then(None).otherwise(pl.col(c)).alias(c) for c in FLOAT_COLUMNS))
        if k % 3 == 2:
            t = t.filter(pl.col("frame") != 5)
        if k == 7:
            t = t.with_columns(pl.lit("predicted").alias("status"))
        tracks.append(t)
    return pl.concat(tracks)


@pytest.mark.parametrize("order", ["canonical", "shuffled"])
@pytest.mark.parametrize("suffix", [".parquet", ".csv"])
@pytest.mark.parametrize("case", ["flow", "groups", "flow-long", "groups-long"])
def test_smooth_command_in_pieces_writes_the_whole_tables_output(tmp_path: Path, monkeypatch, capsys, case: str,
                                                                  suffix: str, order: str) -> None:
    """Issue 33: `smooth` on a Parquet trajectory in canonical order reads it once from its start, a few rows
    at a time (a track across several reads), and smooths and writes a few whole tracks at a time; the printed
    fits and the written table are the whole table's (compared with the path that reads it whole). A file in
    another order is read whole. ``…-long``: every track is a long one (``LONG_ROWS``), smoothed in two
    passes and written in pieces of a few frames (``smooth_long``)."""
    import functools

    from trackreplay.replay.analysis import smooth_long
    from trackreplay.replay.cli.commands import smooth as command

    long = case.endswith("-long")
    case = case.split("-")[0]
    longs: list[int] = []
    if long:
        monkeypatch.setattr(smooth_long, "LONG_ROWS", 6)
        monkeypatch.setattr(smooth_long, "PIECE_FRAMES", 5)
        pieces_of = smooth_long.LongTrack.pieces
        monkeypatch.setattr(smooth_long.LongTrack, "pieces", lambda self, *a: (longs.append(1) or p
                                                                                for p in pieces_of(self, *a)))

    log = GOLDEN / ("flow-sim1-24f.mcap" if case == "flow" else "groups-crossing-320x240.mcap")
    traj = tmp_path / "t.parquet"
    table = _many_flow_tracks() if case == "flow" else read_trajectory(GOLDEN / "groups.trajectory.parquet")
    if order == "shuffled":
        table = table.sample(fraction=1.0, shuffle=True, seed=4)
    table.write_parquet(traj)
    pieces: list[int] = []
    reader = command._tracks_and_long_pieces
    monkeypatch.setattr(command, "_tracks_and_long_pieces", lambda *a: (pieces.append(0 if p is None else p.height)
                                                                        or (k, p) for k, p in
                                                                        functools.partial(reader, batch=7)(*a)))
    monkeypatch.setattr(command, "SMOOTH_ROWS", 30 if case == "flow" else 1)  # a track or two a piece
    capsys.readouterr()
    assert main(["smooth", str(traj), str(log), "--out", str(tmp_path / f"a{suffix}")]) == 0
    streamed = capsys.readouterr().out
    if order == "canonical":
        assert len(pieces) >= 2 and sum(pieces) == table.height
        assert len(longs) >= (5 if long else 0)  # (long tracks cut in pieces of 5 frames)
    else:
        assert len(pieces) <= 1  # refused at its first rows out of order: read whole
    monkeypatch.setattr(command, "smooth_in_pieces", lambda *a, **k: None)  # the whole table
    assert main(["smooth", str(traj), str(log), "--out", str(tmp_path / f"b{suffix}")]) == 0
    whole = capsys.readouterr().out
    assert streamed.replace(f"a{suffix}", f"b{suffix}") == whole and whole.count("smooth ") >= 2
    a, b = tmp_path / f"a{suffix}", tmp_path / f"b{suffix}"
    if suffix == ".csv":
        assert a.read_bytes() == b.read_bytes()
    else:
        assert pl.read_parquet(a).equals(pl.read_parquet(b), null_equal=True)
        assert pl.read_parquet(a).schema == pl.read_parquet(b).schema
    assert not list(tmp_path.glob("*.partial*"))


def test_smooth_in_pieces_refuses_another_logs_trajectory_in_the_same_words(tmp_path: Path, monkeypatch, capsys) -> None:
    """Each piece's frames are compared with the log's before it is smoothed: the whole table's sentence (its
    first frame, how many disagree), nothing printed, no output file; a trajectory defect is named before a
    log's, as reading the whole table names them."""
    from trackreplay.replay.cli.commands import smooth as command

    monkeypatch.setattr(command, "SMOOTH_ROWS", 30)
    log = GOLDEN / "flow-sim1-24f.mcap"
    other, broken = tmp_path / "other.parquet", tmp_path / "broken.parquet"
    tracks = _many_flow_tracks()
    # tracks 3 on: 1 ms later (another log); a few frames of track 5 2 ms later still
    shifted = tracks.with_columns(pl.when(pl.col("track_id") >= 3).then(pl.col("t_ns") + 1_000_000)
                                  .otherwise(pl.col("t_ns")).alias("t_ns"))
    shifted = shifted.with_columns(pl.when((pl.col("track_id") == 5) & (pl.col("frame") < 4)).then(pl.col("t_ns") + 1_000_000)
                                   .otherwise(pl.col("t_ns")).alias("t_ns"))
    write_trajectory(shifted, other)
    write_trajectory(tracks.with_columns(pl.when(pl.col("track_id") == 6).then(pl.lit("gone")).otherwise(pl.col("status"))
                                         .alias("status")), broken)
    real = command.smooth_in_pieces
    said = []
    for whole in (False, True):
        monkeypatch.setattr(command, "smooth_in_pieces", (lambda *a, **k: None) if whole else real)
        capsys.readouterr()
        assert main(["smooth", str(other), str(log), "--out", str(tmp_path / "s.parquet")]) == 2
        said.append(capsys.readouterr())
        assert not list(tmp_path.glob("s.parquet*"))
        assert main(["smooth", str(broken), str(tmp_path / "missing.mcap"), "--out", str(tmp_path / "s.parquet")]) == 2
        said.append(capsys.readouterr())
    assert said[0] == said[2] and said[0].out == "" and "it was not replayed from this log" in said[0].err
    assert said[1] == said[3] and "'gone'" in said[1].err


@pytest.mark.parametrize("as_dict", [False, True])
def test_a_pieces_frame_mismatches_by_search_are_the_joins(as_dict: bool) -> None:
    """`smooth` compares each piece with the log's frame times by a search in the log's sorted frames: the
    rows frame_time_mismatches finds by a join (missing frames, other times, untimed statuses, null times)."""
    from trackreplay.replay.analysis.smooth import FrameTimes
    from trackreplay.replay.cli.commands.smooth import piece_mismatches
    from trackreplay.replay.core.trajectory import frame_time_mismatches

    rng = np.random.default_rng(6)
    n = 400
    frames = rng.integers(0, 120, n)
    table = pl.DataFrame({"frame": frames, "t_ns": frames * 10 + (rng.random(n) < 0.1),
                          "status": rng.choice(["measured", "lost", "predicted", "interpolated"], n)})
    table = table.with_columns(pl.when(pl.Series(rng.random(n) < 0.05)).then(None).otherwise(pl.col("t_ns")).alias("t_ns"))
    logged = rng.permutation(np.arange(0, 110))  # some frames missing, in no order
    times = dict(zip(logged.tolist(), (logged * 10).tolist())) if as_dict else FrameTimes(logged, logged * 10)
    want = frame_time_mismatches(table, pl.DataFrame({"frame": logged, "t_ns": logged * 10}), missing=True)
    got = piece_mismatches(table, times)
    assert want.height > 10 and got.equals(want, null_equal=True)


@pytest.mark.parametrize("tracker", ["flow", "groups"])
def test_tracks_smoothed_in_spilled_pieces_are_the_tables_in_memory(tracker: str, benchmark_module, monkeypatch) -> None:
    """Issue 33: a long track's RTS pass a piece at a time, its filtered states in a temporary file and each
    piece written straight into the track's rows, smooths the same table to the bit as keeping the pass in
    memory: one long track (Python floats) and several of different lengths (a lane), gaps and outliers."""
    from trackreplay.replay.analysis import rts

    bench = benchmark_module("bench_smooth")
    monkeypatch.setattr(rts, "SCAN_FRAMES", 100)
    spilled, spill = [], rts._Spill
    for tracks in (1, 3):
        table = bench.synthetic_trajectory(1200, tracker, tracks=tracks, seed=7)
        monkeypatch.setattr(rts, "SPILL_FRAMES", 200)  # every lane of more than two pieces spills
        calls: list[int] = []
        monkeypatch.setattr(rts, "_Spill", lambda: calls.append(1) or spill())
        got, fits = smooth_trajectory(table)
        monkeypatch.setattr(rts, "SPILL_FRAMES", 10**9)
        want, want_fits = smooth_trajectory(table)
        assert calls and got.equals(want, null_equal=True) and fits == want_fits
        assert got["fill"].is_in(["rts_gap"]).any() and got["fill"].is_in(["rts_outlier"]).any()
        spilled.append(len(calls))
    assert spilled[0] >= 2  # the track was smoothed again without its outliers, spilled both times
