"""Topics chosen by name, glob or re:REGEX, with exclusions (`filter`, `cat`)."""

import pytest

from trackreplay.replay.log.topic_select import select_topics
from trackreplay.schemas.errors import TrackreplayError

PRESENT = ["/camera/image", "/camera/calibration", "/stereo/left/image", "/stereo/right/image", "/ptz/encoders"]


@pytest.mark.parametrize("include, exclude, expected", [
    ([], [], sorted(PRESENT)),
    (["/ptz/encoders"], [], ["/ptz/encoders"]),
    (["ptz/encoders"], [], ["/ptz/encoders"]),  # without the leading slash
    (["camera/*"], [], ["/camera/calibration", "/camera/image"]),
    (["/stereo/*/image"], [], ["/stereo/left/image", "/stereo/right/image"]),
    (["re:/(camera|stereo/left)/image"], [], ["/camera/image", "/stereo/left/image"]),
    ([], ["*/image"], ["/camera/calibration", "/ptz/encoders"]),
    (["camera/*"], ["/camera/calibration"], ["/camera/image"]),
])
def test_patterns(include, exclude, expected) -> None:
    assert select_topics(PRESENT, include, exclude, "x.mcap") == expected


@pytest.mark.parametrize("include, exclude, message", [
    (["/nope"], [], r"x\.mcap has no topic /nope; topics present: /camera/calibration, "),
    (["lidar/*"], [], r"x\.mcap has no topic matching 'lidar/\*'"),
    ([], ["/nope"], r"x\.mcap has no topic /nope to exclude"),
    (["re:("], [], r"topic pattern 're:\(' is not a valid regular expression"),
    (["/ptz/encoders"], ["ptz/*"], r"x\.mcap: no topic is left once 'ptz/\*' are excluded"),
])
def test_refusals_name_the_pattern(include, exclude, message) -> None:
    with pytest.raises(TrackreplayError, match=message) as err:
        select_topics(PRESENT, include, exclude, "x.mcap")
    assert err.value.exit_code == 2
