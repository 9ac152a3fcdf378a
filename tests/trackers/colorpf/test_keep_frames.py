"""refine.keep_frames (default None, no bound): a target whose colour fades for good is kept while its
foreground region places it."""

import numpy as np

from trackreplay.schemas.records import InitRegion
from trackreplay.trackers.colorpf.config import ColorPfConfig, RefineConfig
from trackreplay.trackers.colorpf.tracker import ColorPfTracker
from trackreplay.trackers.frame import Frame

FRAMES = 110


def _changing_walker() -> tuple[list[np.ndarray], list[tuple[float, float]]]:
    """A walker (12 x 36: a red jacket over blue trousers) walks right at 0.8 px per frame over a
    grey floor; from frame 30 to 70 its colours fade towards others (a green jacket, teal trousers:
    the light on it changes), so the colour match against the reference as built sinks."""
    rng = np.random.default_rng(0)
    floor = np.clip(rng.normal(120, 6, (120, 240, 3)), 0, 255).astype(np.uint8)
    images, truth = [], []
    for i in range(FRAMES):
        image, top = floor.copy(), 40
        x0 = int(round(30.0 + 0.8 * i))
        a = min(max((i - 30) / 40.0, 0.0), 1.0)
        image[top:top + 18, x0:x0 + 12] = np.round((1 - a) * np.array([30, 30, 170]) + a * np.array([40, 150, 40]))
        image[top + 18:top + 36, x0:x0 + 12] = np.round((1 - a) * np.array([150, 60, 40]) + a * np.array([150, 150, 40]))
        images.append(image)
        truth.append((x0 + 5.5, top + 17.5))
    return images, truth


def _run(cfg: ColorPfConfig) -> tuple[list[float | None], list[str], list[float]]:
    images, truth = _changing_walker()
    mark = InitRegion(0, 0, truth[0][0], truth[0][1], 18, 44, "target")  # the walker and some floor
    tracker = ColorPfTracker(cfg, np.random.default_rng(0))
    errors, statuses, confidences = [], [], []
    for i, image in enumerate(images):
        s = tracker.step(Frame(index=i, t_ns=i * 33_333_333, image=image, all_hints=(mark,),
                               hints=(mark,) if i == 0 else ()))[0]
        errors.append(None if s.x is None else float(np.hypot(s.x - truth[i][0], s.y - truth[i][1])))
        statuses.append(s.status)
        confidences.append(s.confidence)
    return errors, statuses, confidences


def test_a_target_whose_colour_fades_is_kept_while_its_region_places_it():
    errors, statuses, confidences = _run(ColorPfConfig(calibrate=False))  # the colour's own confidence
    assert max(confidences[60:]) < 0.5  # colour no longer vouches for it ...
    assert all(e is not None and e < 3.0 for e in errors), errors  # ... but the region places it throughout
    assert "lost" not in statuses
    bounded, statuses, _ = _run(ColorPfConfig(refine=RefineConfig(keep_frames=30)))
    assert statuses[-1] == "lost" and bounded[-1] is None  # the previous default dropped it
