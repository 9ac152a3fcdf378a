"""Issue 33, defect 7: ``annotate --in-place`` keeps the file's mode (600 stayed 600, not 644) and owner."""

import os
import shutil
import stat
from pathlib import Path

from trackreplay.replay.cli.main import main

GOLDEN = Path(__file__).resolve().parents[1] / "golden" / "flow-sim1-24f.mcap"


def test_annotate_in_place_keeps_mode_and_owner(tmp_path: Path) -> None:
    log = tmp_path / "log.mcap"
    shutil.copyfile(GOLDEN, log)
    for mode in (0o600, 0o640):
        os.chmod(log, mode)
        before = log.stat()
        assert main(["annotate", str(log), "--frame", "0", "--box", "10,10,20,20", "--in-place"]) == 0
        after = log.stat()
        assert after.st_ino != before.st_ino  # really replaced
        assert stat.S_IMODE(after.st_mode) == mode
        assert (after.st_uid, after.st_gid) == (before.st_uid, before.st_gid)


def test_annotate_to_a_new_file_gets_the_usual_permissions(tmp_path: Path) -> None:
    log = tmp_path / "log.mcap"
    shutil.copyfile(GOLDEN, log)
    os.chmod(log, 0o600)
    umask = os.umask(0o022)
    try:
        assert main(["annotate", str(log), "--frame", "0", "--box", "10,10,20,20", "--out", str(tmp_path / "o.mcap")]) == 0
    finally:
        os.umask(umask)
    assert stat.S_IMODE((tmp_path / "o.mcap").stat().st_mode) == 0o644
