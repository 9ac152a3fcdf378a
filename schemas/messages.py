"""Protobuf message classes used in logs: Foxglove's well-known schemas and ours."""

from foxglove_schemas_protobuf.CameraCalibration_pb2 import CameraCalibration
from foxglove_schemas_protobuf.CompressedImage_pb2 import CompressedImage
from foxglove_schemas_protobuf.FrameTransform_pb2 import FrameTransform
from foxglove_schemas_protobuf.RawImage_pb2 import RawImage

from trackreplay.schemas._gen.GroundPlane_pb2 import GroundPlane
from trackreplay.schemas._gen.GroundTruth_pb2 import GroundTruthFrame, GroundTruthObject
from trackreplay.schemas._gen.InitAnnotations_pb2 import InitAnnotations, InitRegion
from trackreplay.schemas._gen.LensTable_pb2 import LensEntry, LensTable
from trackreplay.schemas._gen.PtzEncoders_pb2 import PtzEncoders

__all__ = [
    "CameraCalibration",
    "CompressedImage",
    "FrameTransform",
    "GroundPlane",
    "GroundTruthFrame",
    "GroundTruthObject",
    "InitAnnotations",
    "InitRegion",
    "LensEntry",
    "LensTable",
    "PtzEncoders",
    "RawImage",
]

# Image and calibration schemas replay reads: Foxglove's (protobuf or JSON) and ROS 2's (CDR).
COMPRESSED_IMAGE_SCHEMAS = ("foxglove.CompressedImage", "sensor_msgs/msg/CompressedImage", "sensor_msgs/CompressedImage")
RAW_IMAGE_SCHEMAS = ("foxglove.RawImage", "sensor_msgs/msg/Image", "sensor_msgs/Image")
IMAGE_SCHEMAS = RAW_IMAGE_SCHEMAS + COMPRESSED_IMAGE_SCHEMAS
CALIBRATION_SCHEMAS = ("foxglove.CameraCalibration", "sensor_msgs/msg/CameraInfo", "sensor_msgs/CameraInfo")
