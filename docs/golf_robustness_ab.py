"""Which change moved a variant of docs/golf_robustness.py: the variants named, replayed with the path
from the mark switched off (``Validator.seed_at`` a no-op, trackers/golf/validate.py) and as shipped.

    python docs/golf_robustness_ab.py                      # the three variants its 2026-12-07 re-run names
    python docs/golf_robustness_ab.py "approach:half resolution" ...

Each variant is made, recorded, marked and replayed exactly as golf_robustness.py does (its ``run``); the
switch reaches the CLI it runs through a ``sitecustomize`` module put first on that process's path.
Prints one line per variant and setting (measured share, within 5 px, confident wrong).
"""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import golf_robustness as robustness  # noqa: E402

DEFAULT = ("iron:mark 3 frames late", "approach:soft focus", "approach:sensor noise")
NO_SEED = """from trackreplay.trackers.golf.validate import Validator
Validator.seed_at = lambda self, index, point: None
"""


def main(argv: list[str]) -> int:
    wanted = [tuple(a.split(":", 1)) for a in (argv or DEFAULT)]
    base_path = robustness.REPO_ENV["PYTHONPATH"]
    decoded = {}
    with tempfile.TemporaryDirectory() as td:
        patch = Path(td) / "patch"
        patch.mkdir()
        (patch / "sitecustomize.py").write_text(NO_SEED)
        for setting, path in (("path from the mark off", f"{patch}:{base_path}"), ("as shipped", base_path)):
            robustness.REPO_ENV["PYTHONPATH"] = path
            for clip, variant in wanted:
                if clip not in decoded:
                    decoded[clip] = robustness.decoded(robustness.CLIPS[clip][0])
                row = robustness.run(clip, variant, *decoded[clip], Path(td))
                print(json.dumps({"setting": setting, **{k: row[k] for k in ("clip", "variant", "measured", "within_5px",
                                                                              "confident_wrong")}}), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
