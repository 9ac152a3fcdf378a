"""Issue 33, defect 3: a log time of 2**63 or more (a negative time written as unsigned wraps there)
is refused in one sentence naming the file, topic and message, not an internal OverflowError."""

import importlib.util
from pathlib import Path

import pytest

from trackreplay.replay.cli.main import main
from trackreplay.replay.log.info import log_info
from trackreplay.replay.log.reader import LogReader
from trackreplay.schemas.errors import LogError

GOLDEN = Path(__file__).resolve().parents[2] / "golden" / "flow-sim1-24f.mcap"
_SPEC = importlib.util.spec_from_file_location("log_mutations", GOLDEN.parents[1] / "fuzz" / "log_mutations.py")
MUTATIONS = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(MUTATIONS)


def with_time(dst: Path, log_time: int, at: int = 5) -> Path:
    """The golden flow log with message ``at`` (file order) moved to ``log_time``."""
    return MUTATIONS.rewrite(GOLDEN, dst, time=log_time, at=at, library="test")


@pytest.mark.parametrize("log_time", [2**63, 2**64 - 5], ids=["2^63", "negative-wrapped"])
def test_a_log_time_beyond_int64_is_one_sentence_naming_topic_and_message(tmp_path: Path, log_time: int, capsys) -> None:
    log = with_time(tmp_path / "t.mcap", log_time)
    with pytest.raises(LogError, match=rf"t.mcap: message \d+ on topic /camera/image has log time {log_time} ns"):
        log_info(log)
    with pytest.raises(LogError, match=rf"message 23 on topic /camera/image has log time {log_time}"):
        list(LogReader(log).messages(["/camera/image"]))
    capsys.readouterr()
    assert main(["replay", str(log), "--tracker", "flow"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "beyond the signed 64-bit range" in err[0] and "internal error" not in err[0]


def test_the_largest_int64_time_is_accepted(tmp_path: Path) -> None:
    log = with_time(tmp_path / "t.mcap", 2**63 - 1)
    assert log_info(log)["end_ns"] == 2**63 - 1
