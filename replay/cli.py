"""The ``trackreplay`` command: one entry point, one module per verb."""

from __future__ import annotations

import argparse
import errno
import importlib
import shlex
import signal
import sys
import traceback

import trackreplay
from trackreplay.recorder.interrupts import interrupt
from trackreplay.recorder.provenance import command_line
from trackreplay.schemas.errors import OutputError, TrackreplayError

# Exit statuses (docs/exit_codes.md). TrackreplayError subclasses carry their own (2, 3, 5, ...).
INTERNAL_ERROR = 70  # EX_SOFTWARE: a bug; the message asks for a report
OUT_OF_MEMORY = 6
INTERRUPTED = 130  # Ctrl-C
TERMINATED = 143  # SIGTERM
NO_SPACE = {errno.ENOSPC, errno.EDQUOT, errno.EFBIG}


class Terminated(KeyboardInterrupt):
    """SIGTERM, handled like Ctrl-C: writers finish what they hold as a valid file."""


def _terminate(signum, frame) -> None:
    interrupt(Terminated())  # raised now, or once the log write under way is complete


def _interrupted(signum, frame) -> None:
    interrupt(KeyboardInterrupt())  # Ctrl-C, likewise

# Verb modules in help order; each has add_parser(subparsers) and run(args).
VERBS = ("record", "synth", "info", "recover", "annotate", "frame", "filter", "replay_cmd", "config_cmd", "batch", "diff", "export", "smooth", "flight", "eval_cmd", "overlay", "bench", "demo")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="trackreplay",
        description="Record camera/PTZ/stereo logs to MCAP, replay trackers deterministically, inspect in Rerun.",
    )
    parser.add_argument("--version", action="version", version=f"trackreplay {trackreplay.__version__}")
    parser.add_argument("--debug", action="store_true", help="print the traceback of an unexpected error")
    sub = parser.add_subparsers(dest="verb", required=True, metavar="VERB")
    for name in VERBS:
        importlib.import_module(f"trackreplay.replay.commands.{name}").add_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run one verb; every failure becomes one sentence on stderr and a documented exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    previous = (signal.signal(signal.SIGTERM, _terminate), signal.signal(signal.SIGINT, _interrupted)) if _main_thread() else None
    # Logs written by this verb record the command line in their provenance.
    token = command_line.set(shlex.join(["trackreplay", *(sys.argv[1:] if argv is None else argv)]))
    try:
        return int(args.func(args) or 0)
    except TrackreplayError as err:
        print(f"trackreplay: error: {err}", file=sys.stderr)
        return err.exit_code
    except Terminated:
        print("trackreplay: terminated (SIGTERM)", file=sys.stderr)
        return TERMINATED
    except KeyboardInterrupt:
        print("trackreplay: interrupted", file=sys.stderr)
        return INTERRUPTED
    except BrokenPipeError:
        return 0
    except OSError as err:
        # An OSError that no verb anticipated: still one sentence naming the file.
        where = f" {err.filename}" if err.filename else ""
        if err.errno in NO_SPACE:
            print(f"trackreplay: error: cannot write{where} ({err.strerror})", file=sys.stderr)
        else:
            print(f"trackreplay: error: cannot access{where} ({err.strerror or err})", file=sys.stderr)
        _debug(args)
        return OutputError.exit_code
    except MemoryError:
        print("trackreplay: error: out of memory", file=sys.stderr)
        return OUT_OF_MEMORY
    except Exception as err:  # a bug: say so in one sentence; the traceback only when asked
        print(f"trackreplay: internal error: {type(err).__name__}: {err}; this is a bug, please report it with "
              f"the command line and the output of --debug", file=sys.stderr)
        _debug(args)
        return INTERNAL_ERROR
    finally:
        command_line.reset(token)
        if previous is not None:
            signal.signal(signal.SIGTERM, previous[0])
            signal.signal(signal.SIGINT, previous[1])


def _main_thread() -> bool:
    import threading

    return threading.current_thread() is threading.main_thread()


def _debug(args: argparse.Namespace) -> None:
    if getattr(args, "debug", False):
        traceback.print_exc()


if __name__ == "__main__":
    sys.exit(main())
