"""Recording inputs, one module per kind; each yields plain records (see ``base.ImageFrame``)."""

from trackreplay.recorder.sources.base import FrameClock, ImageFrame, read_timestamps
from trackreplay.recorder.sources.encoders import read_encoders, read_lens_table
from trackreplay.recorder.sources.groundtruth import GroundTruthTable, read_groundtruth
from trackreplay.recorder.sources.images import list_images, read_images
from trackreplay.recorder.sources.stereo import Calibration, CameraModel, load_calibration, read_stereo
from trackreplay.recorder.sources.video import read_video, video_clock

__all__ = [
    "Calibration",
    "CameraModel",
    "FrameClock",
    "GroundTruthTable",
    "ImageFrame",
    "list_images",
    "load_calibration",
    "read_encoders",
    "read_groundtruth",
    "read_images",
    "read_lens_table",
    "read_stereo",
    "read_timestamps",
    "read_video",
    "video_clock",
]
