"""``python -m trackreplay``: the command line."""

from trackreplay.replay.cli.main import main

raise SystemExit(main())
