"""The argument parser every command shares: a usage mistake is one line, not a usage block."""

from __future__ import annotations

import argparse
from typing import NoReturn


class OneLineParser(argparse.ArgumentParser):
    """``argparse.ArgumentParser`` whose errors are one line on standard error and exit 2:
    ``station: error: MESSAGE; see station CMD --help``. The usage block argparse prints
    first would push the one sentence that matters off a small terminal. Sub-command parsers
    are of this class too (``add_subparsers`` makes them of their parent's class)."""

    help_hint: str | None = None
    """The command whose ``--help`` the error points to (else this parser's own ``prog``):
    an unknown option is reported by the top-level parser, yet belongs to the sub-command."""

    def error(self, message: str) -> NoReturn:
        """Print ``message`` as one line and exit 2 (argparse's exit code for bad usage)."""
        sentence = " ".join(message.split())
        self.exit(2, f"station: error: {sentence}; see {self.help_hint or self.prog} --help\n")


def output_name(text: str) -> str:
    """An ``-o/--output`` value: a file name, never empty (an empty one would quietly mean
    standard output)."""
    if not text.strip():
        raise argparse.ArgumentTypeError(
            "an empty name; name the file to write, or leave -o out to write to standard output"
        )
    return text
