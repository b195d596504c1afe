"""The `solas-mi` command line. Each stage owns its sub-commands (`<stage>/commands.py`, a
`register(subparsers)` each); this module only composes them, turns user errors into one line on
stderr and exit status 2 (and a library's warning into one line, without its source line), and makes SIGTERM an interruption like Ctrl-C, so that temporary files
and folders are removed and no output is left half-written (exit status 130 / 143)."""

from __future__ import annotations

import argparse
import signal
import sys
import threading
import warnings

from .errors import SolasError
from .interrupts import raise_outside_imports

DESCRIPTION = (
    "Physically based lens simulation: PSFs ray-traced through a real lens, images degraded with "
    "them or rendered through the lens in Mitsuba 3, and the result measured."
)


class DefaultsFormatter(argparse.HelpFormatter):
    """Help that states every option's default: "(default: X)" is added where the text does not already
    say its default and there is one (not for flags, whose default is off, nor for options without one)."""

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        default = action.default
        if (
            "default" in text.lower()
            or default in (None, False, argparse.SUPPRESS)
            or not action.option_strings
            or isinstance(action, argparse._StoreTrueAction)
        ):
            return text
        shown = ",".join(map(str, default)) if isinstance(default, (list, tuple)) else default
        return f"{text} (default: {str(shown).replace('%', '%%')})"


class Parser(argparse.ArgumentParser):
    """argparse, with a usage error on one line that says where the usage is, and the defaults in every
    help text (sub-commands inherit both)."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("formatter_class", DefaultsFormatter)
        super().__init__(*args, **kwargs)

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


# the stages whose `<stage>/commands.py` register the sub-commands, in the order of the data: lens → PSFs →
# convolution; lens → scene → render; irradiance → sensor → image processor; images → metrics; checks
AREAS = (
    "optics",
    "psf",
    "convolution",
    "render",
    "sensor",
    "isp",
    "metrics",
    "analysis",
    "validation",
    "batch",
    "experiments",
)
# a command that a later stage adds to: analysis its sub-commands to `lens`, the image processor --isp to `camera`
EXTENDED_BY = {"lens": "analysis", "camera": "isp"}


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The parser of every sub-command, or, given the `command` about to run, of the stages up to the one that
    registers it (and that extends it: `EXTENDED_BY`): a command does not import the stages after its own
    (measured: `psf-grid` starts 0.2 s sooner). A name no stage registers gets every stage's, as does None."""
    from importlib import import_module

    from . import __version__

    parser = Parser(prog="solas-mi", description=DESCRIPTION)
    parser.add_argument("--version", action="version", version=f"solas-mi {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for area in AREAS:
        import_module(f".{area}.commands", __package__).register(sub)
        if command in sub.choices and AREAS.index(area) >= AREAS.index(EXTENDED_BY.get(command, area)):
            break
    return parser


def _command(argv: list[str] | None) -> str | None:
    """The sub-command named by the arguments (the first one, unless it is an option), or None."""
    args = sys.argv[1:] if argv is None else argv
    return args[0] if args and not args[0].startswith("-") else None


def iter_commands(parser: argparse.ArgumentParser, path: tuple[str, ...] = ()):
    """(command path, parser) for `parser` and every sub-command below it, in the order of the help
    (the CLI reference of the documentation and the help tests walk it)."""
    yield path, parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from iter_commands(sub, (*path, name))


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised where the program is so that every `finally` and context manager runs."""


_SIGNALLED: list[int] = []  # the signals this run received: a library (a scene's plugin) may report one as its error


def _stop(signum, frame) -> None:
    _SIGNALLED.append(signum)
    raise_outside_imports(Terminated() if signum == signal.SIGTERM else KeyboardInterrupt(), frame)


def _handlers() -> dict:
    """Our handlers for SIGTERM and (unless it is ignored, as in a background job) SIGINT; the former ones."""
    if threading.current_thread() is not threading.main_thread():
        return {}
    ours = [signal.SIGTERM] + [signal.SIGINT] * (signal.getsignal(signal.SIGINT) is signal.default_int_handler)
    return {sig: signal.signal(sig, _stop) for sig in ours}


def main(argv: list[str] | None = None) -> int:
    _SIGNALLED.clear()
    previous = _handlers()  # from the start: building the parser imports the stages' commands
    args = argparse.Namespace(command=None)
    shown = warnings.showwarning
    warnings.showwarning = lambda message, *where, **more: print(
        f"{_prog(args.command)}: warning: {message}", file=sys.stderr
    )
    try:
        args = build_parser(_command(argv)).parse_args(argv)
        return int(args.run(args) or 0)
    except SolasError as exc:
        if _SIGNALLED:  # the interruption surfaced inside a library as its error
            return _stopped(args.command)
        print(f"{_prog(args.command)}: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # the reader of stdout has gone (`| head`): stop quietly, as Unix tools do
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141
    except KeyboardInterrupt as exc:
        return _stopped(args.command, isinstance(exc, Terminated))
    finally:
        warnings.showwarning = shown
        for sig, handler in previous.items():
            if handler is not None:  # None: set outside Python, not ours to restore
                signal.signal(sig, handler)


def _prog(command: str | None) -> str:
    """How messages name the program: solas-mi and its command (none yet while the parser is built)."""
    return f"solas-mi {command}" if command else "solas-mi"


def _stopped(command: str | None, terminated: bool = False) -> int:
    terminated = terminated or signal.SIGTERM in _SIGNALLED
    how = "terminated" if terminated else "interrupted"
    print(f"\n{_prog(command)}: {how}; no output was left half-written", file=sys.stderr)
    return 143 if terminated else 130


if __name__ == "__main__":
    sys.exit(main())
