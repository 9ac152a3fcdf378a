"""Default topic names of the log contract (docs/architecture.md §3 Log contract)."""

CAMERA_IMAGE = "/camera/image"
CAMERA_CALIBRATION = "/camera/calibration"
CAMERA_GROUND_PLANE = "/camera/ground_plane"
STEREO_LEFT_IMAGE = "/stereo/left/image"
STEREO_RIGHT_IMAGE = "/stereo/right/image"
STEREO_LEFT_CALIBRATION = "/stereo/left/calibration"
STEREO_RIGHT_CALIBRATION = "/stereo/right/calibration"
STEREO_POSE = "/stereo/pose"  # foxglove.FrameTransform: the left camera in a world frame (Z up)
PTZ_ENCODERS = "/ptz/encoders"
PTZ_LENS_TABLE = "/ptz/lens_table"
GROUNDTRUTH = "/groundtruth/objects"
ANNOTATIONS_INIT = "/annotations/init"
