"""`trackreplay frame LOG N --out f.png`: one frame as a PNG with a pixel grid, to read box coordinates off.

A terminal cannot take a click: open the PNG, read the ball's or target's top-left corner and size
from the grid (labels are image pixels, x right, y down, (0, 0) the top-left pixel's corner), and
pass them to ``trackreplay annotate LOG --frame N --box x,y,w,h``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import cv2
import numpy as np

from trackreplay.schemas.errors import LogError, OutputError, TrackreplayError

from trackreplay.replay.cli.commands.values import non_negative_int, positive_int
from trackreplay.replay.log.decode import decode_image
from trackreplay.replay.log.frames import choose_image_topic, require_image_topic
from trackreplay.replay.log.reader import LogReader


def frame_image(reader: LogReader, topic: str, index: int) -> np.ndarray:
    """The decoded image number ``index`` (0-based) of ``topic``."""
    count = reader.topics()[topic].count
    if not 0 <= index < count:
        raise LogError(f"{reader.path} has no frame {index} on {topic} (it has {count} frames)")
    for item in reader.messages([topic]):
        if item.index == index:
            return decode_image(item.decode(), item.schema, f"{reader.path}: topic {topic} message {index}")[0]
    raise LogError(f"{reader.path}: frame {index} on {topic} is lost (damaged chunk)")


def image_topic(reader: LogReader, topic: str | None) -> str:
    if topic is None:
        return choose_image_topic(reader)
    require_image_topic(reader, topic)
    return topic


def draw_grid(image: np.ndarray, step: int, scale: int) -> np.ndarray:
    """``image`` enlarged ``scale`` times (nearest, so pixels stay square) with grid lines every
    ``step`` pixels, labelled with their pixel coordinate along the top and left margins."""
    bgr = cv2.cvtColor(image, cv2.COLOR_GRAY2BGR) if image.ndim == 2 else image
    h, w = bgr.shape[:2]
    big = cv2.resize(bgr, (w * scale, h * scale), interpolation=cv2.INTER_NEAREST)
    margin_top, margin_left = 16, 8 * len(str(max(w, h))) + 6
    out = np.full((h * scale + margin_top, w * scale + margin_left, 3), 255, np.uint8)
    out[margin_top:, margin_left:] = big
    font, size = cv2.FONT_HERSHEY_PLAIN, 0.8
    for x in range(0, w + 1, step):
        u = margin_left + x * scale
        major = x % (5 * step) == 0
        out[margin_top:, min(u, out.shape[1] - 1)] = (0, 255, 255) if major else (0, 160, 255)
        if major or step * scale >= 40:
            cv2.putText(out, str(x), (u + 2, margin_top - 4), font, size, (0, 0, 0), 1, cv2.LINE_AA)
    for y in range(0, h + 1, step):
        v = margin_top + y * scale
        major = y % (5 * step) == 0
        out[min(v, out.shape[0] - 1), margin_left:] = (0, 255, 255) if major else (0, 160, 255)
        if major or step * scale >= 40:
            cv2.putText(out, str(y), (2, v + 10), font, size, (0, 0, 0), 1, cv2.LINE_AA)
    return out


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = sub.add_parser("frame", help="write frame N as a PNG with a pixel grid (to read boxes for annotate)")
    p.add_argument("log", type=Path)
    p.add_argument("index", type=non_negative_int, metavar="N", help="frame number, 0-based (as annotate --frame)")
    p.add_argument("--out", type=Path, required=True, help="PNG to write")
    p.add_argument("--image-topic", help="image topic (default: as replay chooses it)")
    p.add_argument("--grid", type=positive_int, default=0, help="grid spacing in image pixels (default: about 16 lines across)")
    p.add_argument("--scale", type=positive_int, default=0, help="enlargement (default 2 below 800 px wide, else 1)")
    p.add_argument("--plain", action="store_true", help="the frame's pixels only, no grid")
    p.set_defaults(func=run)
    return p


MAX_PICTURE_PX = 2**28  # the decode limit of docs/exit_codes.md, for what we draw too


def run(args: argparse.Namespace) -> int:
    reader = LogReader(args.log)
    topic = image_topic(reader, args.image_topic)
    image = frame_image(reader, topic, args.index)
    h, w = image.shape[:2]
    if args.plain:
        picture = image
    else:
        step = args.grid or max(5, int(round(max(w, h) / 16 / 5)) * 5)
        scale = args.scale or (2 if w < 800 else 1)
        if w * h * scale * scale > MAX_PICTURE_PX:
            raise TrackreplayError(f"--scale {scale} would make a {w * scale}x{h * scale} picture; at most "
                                   f"{MAX_PICTURE_PX} pixels (2^28)")
        picture = draw_grid(image, step, scale)
    if args.out.suffix.lower() != ".png":
        raise TrackreplayError(f"--out {args.out} must end in .png")
    if not args.out.parent.is_dir():
        raise OutputError(f"cannot write {args.out}: folder {args.out.parent} does not exist")
    if not cv2.imwrite(str(args.out), picture):
        raise OutputError(f"cannot write {args.out}")
    print(f"wrote {args.out}: frame {args.index} of {topic}, {w}x{h} px"
          + ("" if args.plain else f", grid every {step} px, shown x{scale}"))
    return 0
