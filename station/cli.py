"""The ``station`` command line: parse, call the domain, print. Nothing else lives here.

Each sub-command is a module in :mod:`station.commands` exposing ``add_parser(subparsers)``;
``add_parser`` registers the arguments and sets ``func`` (called with the parsed namespace,
returning the exit code). Command modules import heavy packages (numpy, scipy, textual) inside
their functions so that ``station --help`` and the TUI's start stay fast.
"""

from __future__ import annotations

# Only sys at import time: a Ctrl-C in the first milliseconds lands in main(), which says
# "interrupted" in one line, instead of in an import, which would print a traceback.
import sys

TYPE_CHECKING = False  # typing.TYPE_CHECKING without importing typing
if TYPE_CHECKING:
    import argparse
    from collections.abc import Sequence
    from typing import TextIO


def command_names() -> list[str]:
    """The sub-commands: one per public module of :mod:`station.commands`, sorted."""
    import pkgutil

    import station.commands as commands_package

    return sorted(
        info.name
        for info in pkgutil.iter_modules(commands_package.__path__)
        if not info.name.startswith("_")
    )


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The argument parser with every sub-command registered, or just ``only``.

    Registering one command imports only its module: the TUI and each command start without
    loading the others (``station --help`` and a mistyped command still see them all).
    """
    import importlib

    from station import __version__
    from station.commands._parser import OneLineParser

    parser = OneLineParser(
        prog="station",
        description=(
            "Acquisition station for robot calibration: repeatability, relative accuracy and "
            "linearity by the 1990 NASA/KSC statistical method. Without a command it opens the "
            "terminal user interface."
        ),
    )
    parser.add_argument("--version", action="version", version=f"station {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in [only] if only else command_names():
        importlib.import_module(f"station.commands.{name}").add_parser(subparsers)
    if only:
        parser.help_hint = f"station {only}"
    return parser


_TOP_LEVEL_FLAGS = ("-h", "--help", "--version")


_SIGNAL_KEEPING_COMMANDS = ("capture",)
"""Commands whose exit code says a stop signal came (128 + the signal), from the first
instruction to the last: they take the signals before their module loads."""


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``station`` console script; returns the process exit code."""
    arguments = sys.argv[1:] if argv is None else argv
    keeps_signals = bool(arguments) and arguments[0] in _SIGNAL_KEEPING_COMMANDS
    if keeps_signals:
        from station.commands._signals import keep_stop_signals

        keep_stop_signals()
    try:
        return _main(argv)
    except KeyboardInterrupt:
        # Ctrl-C while the command is still loading (before its own handling starts).
        _say("station: interrupted")
        return 130
    except BaseException as error:
        if not keeps_signals:
            raise
        from station.commands._signals import StoppedBySignal

        if not isinstance(error, StoppedBySignal):
            raise
        _say(f"station: {error.name}: stopped before anything was written")
        return 128 + error.signum
    finally:
        if keeps_signals and argv is not None:
            # Run in-process (the tests): give the signals back.
            from station.commands._signals import release_stop_signals

            release_stop_signals()
        elif keeps_signals:
            # The process's own command keeps them to its exit, so a signal in its last
            # instructions (the interpreter's shutdown included) is not a raw kill.
            from station.commands._signals import ignore_stop_signals_to_exit

            ignore_stop_signals_to_exit()


def _say(line: str) -> None:
    try:  # noqa: SIM105 (contextlib would be one more import in the window)
        print(line, file=sys.stderr)
    except (OSError, ValueError):
        pass


def _main(argv: Sequence[str] | None) -> int:
    from station.plain import PlainStream

    arguments = list(sys.argv[1:] if argv is None else argv)
    if not arguments or (arguments[0].startswith("-") and arguments[0] not in _TOP_LEVEL_FLAGS):
        # The bare command (or only options such as --no-mouse) opens the TUI.
        arguments = ["tui", *arguments]
    known = arguments[0] in command_names()
    parser = build_parser(only=arguments[0] if known else None)
    arguments = negative_values_attached(parser, arguments)
    if arguments[0] in _FULL_SCREEN_COMMANDS:
        return _run(parser, arguments)
    # Whatever a command prints (names, frames, file names, CSV headers), no raw control
    # character reaches the terminal: both streams pass through station.plain.
    saved = sys.stdout, sys.stderr
    sys.stdout, sys.stderr = PlainStream(sys.stdout), PlainStream(sys.stderr)
    try:
        code = _run(parser, arguments)
        try:
            sys.stdout.flush()
        except BrokenPipeError:
            pass
        except OSError as error:
            code = _output_failed(saved[1], error)
        return code
    finally:
        sys.stdout, sys.stderr = saved


def _run(parser: argparse.ArgumentParser, arguments: list[str]) -> int:
    import errno

    from station.commands._remedies import cli_sentence
    from station.errors import StationError

    args = parser.parse_args(arguments)
    try:
        return int(args.func(args) or 0)
    except StationError as error:
        print(f"station: {cli_sentence(error)}", file=sys.stderr)
        return error.exit_code
    except KeyboardInterrupt:
        print("station: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # `station read ... | head` closes the pipe early; that is not an error.
        return 0
    except OSError as error:
        if error.errno in (errno.ENOSPC, errno.EIO, errno.EDQUOT, errno.EFBIG):
            # The output itself could not be written (`> /dev/full`, a full disk).
            return _output_failed(sys.stderr, error)
        raise


def _output_failed(stderr: TextIO, error: OSError) -> int:
    import contextlib

    with contextlib.suppress(OSError, ValueError):
        print(
            f"station: cannot write the output ({error.strerror}); free some space or "
            "write it elsewhere",
            file=stderr,
            flush=True,
        )
    return 1


_FULL_SCREEN_COMMANDS = ("tui", "demo")
"""Commands that own the terminal (Textual): their text is made plain where it is shown."""

_NEGATIVE = r"^-(?:inf(?:inity)?|nan|[0-9.][0-9.eE+_-]*)$"


def negative_values_attached(parser: argparse.ArgumentParser, arguments: list[str]) -> list[str]:
    """``--lsl -1e-3`` as ``--lsl=-1e-3``: argparse takes a value starting with ``-`` for an
    option unless it looks like a plain negative number (``-1e-3`` and ``-inf`` do not), so an
    option that takes a value gets a negative-looking next word attached to it."""
    import re

    negative = re.compile(_NEGATIVE, re.IGNORECASE)
    takes_value: set[str] = set()
    for action in _all_actions(parser):
        if action.nargs is None and action.option_strings and not action.const:
            takes_value.update(s for s in action.option_strings if s.startswith("--"))
    joined: list[str] = []
    index = 0
    while index < len(arguments):
        word = arguments[index]
        following = arguments[index + 1] if index + 1 < len(arguments) else None
        if word in takes_value and following is not None and negative.match(following):
            joined.append(f"{word}={following}")
            index += 2
            continue
        joined.append(word)
        index += 1
    return joined


def _all_actions(parser: argparse.ArgumentParser) -> list[argparse.Action]:
    import argparse

    actions = list(parser._actions)
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                actions.extend(_all_actions(sub))
    return actions


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
