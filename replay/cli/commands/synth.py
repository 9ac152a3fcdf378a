"""`trackreplay synth SCENE OUT.mcap`: synthetic scenes with ground truth."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

from trackreplay.replay.cli.commands.record import check_output_folder
from trackreplay.replay.cli.commands.values import non_negative_float, non_negative_int, positive_float, positive_int
from trackreplay.recorder.synth.colorpf import SCENES as COLORPF_SCENES
from trackreplay.recorder.synth.colorpf import ColorPfSceneConfig, write_colorpf_scene
from trackreplay.recorder.synth.flow_sims import SCENES as FLOW_SCENES
from trackreplay.recorder.synth.flow_sims import FlowSimConfig, write_flow_sim
from trackreplay.recorder.synth.golf.scene import CAMERA_PLACES, SCENE as GOLF_SCENE
from trackreplay.recorder.synth.golf.scene import SIZES, GolfSceneConfig, write_golf_teeshot
from trackreplay.recorder.synth.groups.scene import SCENES as GROUP_SCENES
from trackreplay.recorder.synth.texture import PHOTOS
from trackreplay.schemas.errors import TrackreplayError

# Options of one family of scenes only: (dest, flag). Their parser defaults are None so that
# giving one to the other family is caught instead of silently ignored.
_FLOW_ONLY = (("background", "--background"), ("encoding", "--encoding"), ("frames", "--frames"))
_GOLF_ONLY = (("size", "--size"), ("fps", "--fps"), ("no_bounce", "--no-bounce"), ("cut", "--cut"),
              ("occlusion", "--occlusion"), ("encoder_dropout", "--encoder-dropout"), ("duration", "--duration"),
              ("camera", "--camera"), ("exact_encoders", "--exact-encoders"))


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = sub.add_parser("synth", help="write a synthetic scene with ground truth to MCAP")
    p.add_argument("scene", choices=(*FLOW_SCENES, GOLF_SCENE, *COLORPF_SCENES, *GROUP_SCENES),
                   help="flow-sim1|2|3: the gradient-flow paper's simulations; golf-teeshot: a broadcast tee shot with PTZ encoders; "
                        "colorpf-illumination|background|approach: walkers before a fixed camera (colour PF, Tables 1-3)")
    p.add_argument("out", type=Path, help="output .mcap")
    p.add_argument("--seed", type=non_negative_int, default=0, help="seed of the procedural scene (default 0)")
    p.add_argument("--quiet", action="store_true",
                   help="no progress bar (there is none either when stderr is not a terminal)")
    flow = p.add_argument_group("flow-sim scenes")
    flow.add_argument("--background", default=None, choices=("texture", *PHOTOS),
                      help="procedural texture (default) or a photo bundled with scikit-image (the `scenes` extra)")
    flow.add_argument("--encoding", default=None, choices=("png", "jpeg", "raw"), help="image encoding (default png, lossless)")
    flow.add_argument("--frames", type=positive_int, default=None, help="number of frames, t = 0..frames-1 (paper: 51)")
    golf = p.add_argument_group("golf-teeshot (--fps and --duration also for groups-*: default 48 fps, 4 s after a 10-frame lead-in)")
    golf.add_argument("--size", default=None, choices=tuple(SIZES), help="frame size (default 720p)")
    golf.add_argument("--fps", type=positive_float, default=None, help="frame rate (golf default 30, at most 240; groups 48)")
    golf.add_argument("--duration", type=positive_float, default=None, metavar="S",
                      help="seconds to record, at most 120 (golf default: until the ball has rested for 1 s; groups: 4)")
    golf.add_argument("--camera", default=None, choices=tuple(CAMERA_PLACES), help="camera behind (default) or beside the tee")
    golf.add_argument("--no-bounce", action="store_true", default=None, help="the ball checks into the turf and rolls out, no hop")
    golf.add_argument("--cut", type=non_negative_float, default=None, metavar="AT_S", help="a camera cut / fast zoom out at this time")
    golf.add_argument("--occlusion", type=non_negative_float, nargs=2, default=None, metavar=("START_S", "END_S"),
                      help="the ball is hidden in this window (behind a tree in flight, a spectator on the ground)")
    golf.add_argument("--encoder-dropout", type=non_negative_float, nargs=2, default=None, metavar=("START_S", "END_S"),
                      help="no PTZ encoder readings in this window")
    golf.add_argument("--exact-encoders", action="store_true", default=None,
                      help="log the encoders without noise or quantisation (geometry checks)")
    p.set_defaults(func=run)
    return p


def _shows_progress(args: argparse.Namespace) -> bool:
    return not args.quiet and sys.stderr.isatty()


@contextmanager
def progress_bar(desc: str, enabled: bool) -> Iterator[Callable[[int, int], None] | None]:
    """A frame counter on stderr (tqdm) fed by a scene writer's ``progress(done, total)``; None when
    not ``enabled``. Only the bar reads the clock: what is written does not depend on it."""
    if not enabled:
        yield None
        return
    from tqdm import tqdm

    with tqdm(unit="frame", desc=desc, leave=False, file=sys.stderr) as bar:
        def progress(done: int, total: int) -> None:
            bar.total = total
            bar.update(done - bar.n)

        yield progress


def _reject(args: argparse.Namespace, options: tuple[tuple[str, str], ...], scene: str) -> None:
    for dest, flag in options:
        if getattr(args, dest) is not None:
            raise TrackreplayError(f"{flag} does not apply to scene {scene}")


def _check_photos(name: str) -> None:
    """The photos come with scikit-image, an optional extra: say which, before anything is written."""
    try:
        import skimage.data  # noqa: F401
    except ImportError:
        raise TrackreplayError(f"--background {name} is a photo bundled with scikit-image, which is not installed: "
                               "pip install 'trackreplay[scenes]' (or -e '.[scenes]' in a clone)") from None


def run(args: argparse.Namespace) -> int:
    check_output_folder(args.out)
    if args.scene in GROUP_SCENES:
        return _run_groups(args)
    if args.scene == GOLF_SCENE:
        return _run_golf(args)
    if args.scene in COLORPF_SCENES:
        return _run_colorpf(args)
    _reject(args, _GOLF_ONLY, args.scene)
    if args.background in PHOTOS:
        _check_photos(args.background)
    cfg = FlowSimConfig(
        scene=args.scene, seed=args.seed, background=args.background or "texture", encoding=args.encoding or "png",
        frames=51 if args.frames is None else args.frames,
    )
    n = write_flow_sim(args.out, cfg)
    print(f"wrote {args.out}: {args.scene}, {n} frames with ground truth", file=sys.stderr)
    return 0


def _run_golf(args: argparse.Namespace) -> int:
    _reject(args, _FLOW_ONLY, args.scene)
    width, height = SIZES[args.size or "720p"]
    cfg = GolfSceneConfig(
        seed=args.seed, width=width, height=height, fps=30.0 if args.fps is None else args.fps, duration=args.duration,
        camera=args.camera or "behind", bounce=not args.no_bounce, cut_at=args.cut,
        occlusion=None if args.occlusion is None else tuple(args.occlusion),
        encoder_dropout=None if args.encoder_dropout is None else tuple(args.encoder_dropout),
        encoder_noise=not args.exact_encoders,
    )
    cfg.validate()
    with progress_bar(GOLF_SCENE, _shows_progress(args)) as progress:
        summary = write_golf_teeshot(args.out, cfg, progress)
    print(f"wrote {args.out}: {GOLF_SCENE}, {summary.describe()}", file=sys.stderr)
    return 0


def _run_colorpf(args: argparse.Namespace) -> int:
    """Colour-PF scenes take --seed and --frames (walking frames, default 96)."""
    _reject(args, _GOLF_ONLY + (("background", "--background"), ("encoding", "--encoding")), args.scene)
    cfg = ColorPfSceneConfig(scene=args.scene, seed=args.seed, frames=96 if args.frames is None else args.frames)
    try:
        cfg.validate()
    except ValueError as err:
        raise TrackreplayError(str(err)) from None
    with progress_bar(args.scene, _shows_progress(args)) as progress:
        summary = write_colorpf_scene(args.out, cfg, progress)
    print(f"wrote {args.out}: {args.scene}, {summary.describe()}", file=sys.stderr)
    return 0


def _run_groups(args: argparse.Namespace) -> int:
    """Stereo crowds for the groups tracker (seed 003); --fps and --duration apply, the rest is the paper's rig."""
    from trackreplay.recorder.synth.groups.scene import GroupSceneConfig, write_group_scene

    _reject(args, tuple(o for o in _FLOW_ONLY + _GOLF_ONLY if o[0] not in ("fps", "duration")), args.scene)
    cfg = GroupSceneConfig(scene=args.scene, seed=args.seed, fps=48.0 if args.fps is None else args.fps,
                           duration=4.0 if args.duration is None else args.duration)
    try:
        cfg.validate()
    except ValueError as err:  # before anything is written
        raise TrackreplayError(f"synth {args.scene}: {err}") from None
    with progress_bar(args.scene, _shows_progress(args)) as progress:  # ~0.2 s a stereo frame
        summary = write_group_scene(args.out, cfg, progress)
    print(f"wrote {args.out}: {args.scene}, {summary.describe()}", file=sys.stderr)
    return 0
