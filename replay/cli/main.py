"""The ``trackreplay`` command: one entry point, one module per verb."""

from __future__ import annotations

import argparse
import errno
import importlib
import os
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


class StdoutGuard:
    """``sys.stdout`` that goes quiet, without an error, once its reader has closed the pipe
    (``trackreplay diff A B | head -1``): the verb runs on and its own exit status is kept."""

    def __init__(self, stream) -> None:
        self.stream = stream
        self.pipe_closed = False

    def write(self, text: str) -> int:
        if not self.pipe_closed:
            try:
                return self.stream.write(text)
            except BrokenPipeError:
                self.close_pipe()
        return len(text)

    def flush(self) -> None:
        if not self.pipe_closed:
            try:
                self.stream.flush()
            except BrokenPipeError:
                self.close_pipe()

    def close_pipe(self) -> None:
        self.pipe_closed = True
        # The stream still holds what it could not write: aim its descriptor at /dev/null so the
        # interpreter's flush at exit succeeds instead of changing the exit status to 120.
        try:
            fd = self.stream.fileno()
        except (OSError, ValueError, AttributeError):
            return
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, fd)
        os.close(devnull)

    def __getattr__(self, name: str):
        return getattr(self.stream, name)


def _detail(err: BaseException) -> str:
    """``: what was kept`` when the interrupted verb said so (batch), else nothing."""
    return f": {err}" if str(err) else ""

# Verb modules in help order; each has add_parser(subparsers) and run(args).
VERBS = ("record", "synth", "info", "cat", "recover", "annotate", "frame", "filter", "merge", "replay_cmd", "config_cmd", "batch", "evaluate", "diff", "export", "smooth", "flight", "eval_cmd", "overlay", "bench", "demo")


# The libraries' own log lines (Rerun's Rust logger; Ray's start-up warnings, e.g. its token
# authentication notice) stay off the terminal unless --debug: the verbs say what matters in one sentence.
QUIET_LOGGERS = ("ray._private.authentication",)


def _quiet_libraries() -> dict[str, int]:
    """Silence them in this process; returns the logger levels to restore (main also runs inside tests).

    ``RUST_LOG`` (unless the user set one) stays set for the process: Rerun's Rust logger reads it once,
    at its first event, which may come at exit (a viewer connection given up on) after main returned."""
    import logging

    os.environ.setdefault("RUST_LOG", "off")
    levels = {name: logging.getLogger(name).level for name in QUIET_LOGGERS}
    for name in QUIET_LOGGERS:
        logging.getLogger(name).setLevel(logging.ERROR)
    return levels


def _restore_loggers(levels: dict[str, int]) -> None:
    import logging

    for name, level in levels.items():
        logging.getLogger(name).setLevel(level)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="trackreplay",
        description="Record camera/PTZ/stereo logs to MCAP, replay trackers deterministically, inspect in Rerun.",
    )
    parser.add_argument("--version", action="version", version=f"trackreplay {trackreplay.__version__}")
    parser.add_argument("--debug", action="store_true", help="print the traceback of an unexpected error")
    sub = parser.add_subparsers(dest="verb", required=True, metavar="VERB")
    for name in VERBS:
        importlib.import_module(f"trackreplay.replay.cli.commands.{name}").add_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run one verb; every failure becomes one sentence on stderr and a documented exit status."""
    # before parsing: an argument's check may import Rerun, whose logger reads RUST_LOG once
    quieted = None if "--debug" in (sys.argv[1:] if argv is None else argv) else _quiet_libraries()
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except BaseException:  # --help, a usage error (argparse exits)
        if quieted is not None:
            _restore_loggers(quieted)
        raise
    previous = (signal.signal(signal.SIGTERM, _terminate), signal.signal(signal.SIGINT, _interrupted)) if _main_thread() else None
    # Logs written by this verb record the command line in their provenance.
    token = command_line.set(shlex.join(["trackreplay", *(sys.argv[1:] if argv is None else argv)]))
    stdout = sys.stdout
    sys.stdout = guard = StdoutGuard(stdout)
    try:
        return int(args.func(args) or 0)
    except TrackreplayError as err:
        print(f"trackreplay: error: {err}", file=sys.stderr)
        return err.exit_code
    except Terminated as err:
        print(f"trackreplay: terminated (SIGTERM){_detail(err)}", file=sys.stderr)
        return TERMINATED
    except KeyboardInterrupt as err:
        print(f"trackreplay: interrupted{_detail(err)}", file=sys.stderr)
        return INTERRUPTED
    except OSError as err:
        if isinstance(err, BrokenPipeError) and err.filename is None:
            guard.close_pipe()  # stdout's reader went away outside the guard: the status is unknown, but not 0
            print("trackreplay: error: cannot write the output: its reader closed the pipe", file=sys.stderr)
            return OutputError.exit_code
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
        sys.stdout = stdout
        if quieted is not None:
            _restore_loggers(quieted)
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
