"""The ``station`` command line: parse, call the domain, print. Nothing else lives here.

Each sub-command is a module in :mod:`station.commands` exposing ``add_parser(subparsers)``;
``add_parser`` registers the arguments and sets ``func`` (called with the parsed namespace,
returning the exit code). Command modules import heavy packages (numpy, scipy, textual) inside
their functions so that ``station --help`` and the TUI's start stay fast.
"""

from __future__ import annotations

import argparse
import importlib
import pkgutil
import sys
from collections.abc import Sequence

from station import __version__
from station.commands._remedies import CLI_REMEDIES
from station.errors import StationError


def command_names() -> list[str]:
    """The sub-commands: one per public module of :mod:`station.commands`, sorted."""
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
    parser = argparse.ArgumentParser(
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
    return parser


_TOP_LEVEL_FLAGS = ("-h", "--help", "--version")


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``station`` console script; returns the process exit code."""
    arguments = list(sys.argv[1:] if argv is None else argv)
    if not arguments or (arguments[0].startswith("-") and arguments[0] not in _TOP_LEVEL_FLAGS):
        # The bare command (or only options such as --no-mouse) opens the TUI.
        arguments = ["tui", *arguments]
    known = arguments[0] in command_names()
    parser = build_parser(only=arguments[0] if known else None)
    args = parser.parse_args(arguments)
    try:
        return int(args.func(args) or 0)
    except StationError as error:
        print(f"station: {error.worded(CLI_REMEDIES)}", file=sys.stderr)
        return error.exit_code
    except KeyboardInterrupt:
        print("station: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # `station read ... | head` closes the pipe early; that is not an error.
        return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
