import numpy as np
import pytest

from trackreplay.schemas.records import InitRegion
from trackreplay.trackers.appearance.color import to_ycbcr
from trackreplay.trackers.appearance.lut import ColourLut
from trackreplay.trackers.foreground.blobs import measure_blobs
from trackreplay.trackers.foreground.silhouette import crop_pixels
from trackreplay.trackers.golf.config import LutConfig
from trackreplay.trackers.golf.lut import build_luts, region_samples
from trackreplay.trackers.golf.silhouette import lut_silhouette, named_silhouette

CONTEXT_PX = 64.0 * 720 / 1080  # the smallest search region on these 720-line images


def crop_ycc(image, box):
    return crop_pixels(image, box, to_ycbcr)


def disc_mask(shape, centre, radius):
    ys, xs = np.mgrid[0 : shape[0], 0 : shape[1]]
    return (xs - centre[0]) ** 2 + (ys - centre[1]) ** 2 <= radius**2


@pytest.fixture(scope="module")
def marked(backdrop, draw_ball):
    img = backdrop()
    img = draw_ball(img, (400.0, 150.0), 6.0)  # over sky
    img = draw_ball(img, (900.0, 560.0), 6.0)  # over grass
    regions = (InitRegion(0, 0, 400.0, 150.0, 14, 14, "ball"), InitRegion(0, 0, 900.0, 560.0, 14, 14, "ball"))
    return img, regions


def test_unlabelled_boxes_are_sorted_into_sky_and_ground(marked):
    img, regions = marked
    cfg = LutConfig()
    assert region_samples(img, regions[0], cfg, CONTEXT_PX).name == "sky"
    assert region_samples(img, regions[1], cfg, CONTEXT_PX).name == "ground"
    luts = build_luts([(img, regions)], cfg)
    assert luts.names == ("sky", "ground")
    assert luts.luts["sky"].table.shape == (256, 256, 256) and luts.luts["sky"].table.dtype == bool
    assert luts.start_names(img, regions[0]) == ("sky", "sky")


@pytest.mark.parametrize("where, name", [((640.0, 200.0), "sky"), ((300.0, 600.0), "ground")])
def test_silhouette_of_a_new_ball_in_the_search_region(marked, where, name, backdrop, draw_ball):
    """A ball at a place the LUT never saw is segmented; the background around it is not."""
    img, regions = marked
    luts = build_luts([(img, regions)], LutConfig())
    frame = draw_ball(backdrop(seed=7), where, 5.0)
    box = np.array([where[0] - 40, where[1] - 30, 80, 60])
    sil, ycc = lut_silhouette(frame, box, luts, "")
    offset = tuple(sil.offset)
    assert offset == (int(where[0] - 40), int(where[1] - 30))
    assert sil.lut_name == name and ycc.shape == (60, 80, 3)
    assert sil.lut_scores[sil.lut_names.index(name)] > 0.9
    mask = sil.mask
    assert mask.dtype == np.uint8 and mask.shape == (60, 80)
    truth = disc_mask(mask.shape, (where[0] - offset[0], where[1] - offset[1]), 4.0)  # the disc's solid core
    assert mask[truth].mean() > 0.95
    far = ~disc_mask(mask.shape, (where[0] - offset[0], where[1] - offset[1]), 7.0)
    assert mask[far].mean() < 0.002


def test_switch_follows_the_region_with_hysteresis(marked, backdrop):
    img, regions = marked
    cfg = LutConfig()
    luts = build_luts([(img, regions)], cfg)
    frame = backdrop(seed=3)
    ycc, _ = crop_ycc(frame, np.array([600, 250, 80, 80]))  # all sky
    assert luts.choose(ycc[..., 0], "ground")[0] == "sky"
    ycc, _ = crop_ycc(frame, np.array([600, 420, 80, 80]))  # all grass
    assert luts.choose(ycc[..., 0], "sky")[0] == "ground"
    # Slide a box over the horizon: where the two scores are within the margin, the current LUT stays.
    close = 0
    for top in range(300, 361):
        ycc, _ = crop_ycc(frame, np.array([600, top, 80, 80]))
        _, scores = luts.choose(ycc[..., 0], "")
        if abs(scores[0] - scores[1]) < cfg.switch_margin:
            close += 1
            assert luts.choose(ycc[..., 0], "sky")[0] == "sky"
            assert luts.choose(ycc[..., 0], "ground")[0] == "ground"
    assert close > 0


def test_labels_override_the_colour_guess(marked):
    img, regions = marked
    relabelled = (InitRegion(0, 0, 400.0, 150.0, 14, 14, "ball ground"),)
    assert region_samples(img, relabelled[0], LutConfig(), CONTEXT_PX).name == "ground"


def test_scores_from_luminance_counts_are_the_labels_counted(marked, backdrop):
    img, regions = marked
    luts = build_luts([(img, regions)], LutConfig())
    frame = backdrop(seed=3)
    for top in range(0, 700, 37):
        ycc, _ = crop_ycc(frame, np.array([600, top, 80 + top % 7, 60]))
        flat = ycc[..., 0].ravel()
        per_lut = np.bincount(luts.luminance_labels()[flat], minlength=2)  # the plain form
        _, scores = luts.choose(ycc[..., 0], "")
        assert scores.tolist() == [float(per_lut[0] / flat.size), float(per_lut[1] / flat.size)]


class OneColourLuts:
    """Both LUTs say "ball" for one (Y, Cb, Cr) colour only (what ``named_silhouette`` asks of a GolfLuts)."""

    def __init__(self, colour, config):
        table = np.zeros((256, 256, 256), bool)
        table[colour] = True
        self.table, self.config = ColourLut(table), config

    def lut(self, name):
        return self.table


@pytest.mark.parametrize("name, pieces", [("sky", 1), ("ground", 9)])
def test_the_sky_silhouette_joins_the_pieces_of_one_ball(name, pieces):
    """A small ball over sky passes the sky LUT on scattered core pixels (a pixel in four here, 1 px
    apart): the sky's silhouette is closed into one blob the ball's size; the ground's is left as
    the LUT gives it (clutter beside a ball on the ground would join it)."""
    ycc = np.full((21, 21, 3), (150, 160, 110), np.uint8)
    ycc[6:11:2, 6:11:2] = (240, 128, 128)  # 9 ball pixels on a 5x5 lattice
    mask = named_silhouette(ycc, OneColourLuts((240, 128, 128), LutConfig()), name)
    blobs = measure_blobs(mask, moments=False)
    assert len(blobs.area) == pieces
    assert blobs.area.sum() == (25 if name == "sky" else 9)
    off = named_silhouette(ycc, OneColourLuts((240, 128, 128), LutConfig(sky_close_px=0)), "sky")
    assert len(measure_blobs(off, moments=False).area) == 9


def test_a_negative_closing_is_refused():
    with pytest.raises(ValueError, match="sky_close_px"):
        LutConfig(sky_close_px=-1)
