"""``python -m trackreplay``: the command line."""

from trackreplay.replay.cli import main

raise SystemExit(main())
