"""Issue 33, defect 6: ``--connect`` with a URL that is not a Rerun viewer's is refused in one
sentence naming the schemes accepted (it was an internal error from the SDK)."""

from pathlib import Path

import pytest
import rerun.blueprint as rrb

from trackreplay.replay.cli.main import main
from trackreplay.replay.views.rerun_sink import RerunSink
from trackreplay.schemas.errors import TrackreplayError

GOLDEN = Path(__file__).resolve().parents[2] / "golden" / "flow-sim1-24f.mcap"


@pytest.mark.parametrize("url", ["http://127.0.0.1:9876/proxy", "file:///tmp/x.rrd", "127.0.0.1:9876", "rerun+http://"])
def test_connect_with_a_non_rerun_url_names_the_schemes(url: str, capsys) -> None:
    with pytest.raises(SystemExit) as done:
        main(["replay", str(GOLDEN), "--tracker", "flow", "--connect", url])
    assert done.value.code == 2
    err = capsys.readouterr().err
    assert f"{url!r} is not a Rerun viewer URL; one starts with rerun://, rerun+http://, rerun+https://" in err
    assert "internal error" not in err


def test_the_sink_itself_refuses_it(tmp_path: Path) -> None:
    with pytest.raises(TrackreplayError, match="rerun\\+http://"):
        RerunSink(None, "r", rrb.Blueprint(), connect="http://127.0.0.1:9876/proxy")
