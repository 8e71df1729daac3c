"""The hostile corpus: text an attacker or a broken device puts where the station shows text.

Every command and every screen is fed the same strings (issue 12): Rich/Textual markup that
would crash a screen or become a live action, terminal escapes (OSC title, CSI clear, colour),
BEL, a C1 control, a bidi override, and a 100,000-character name. :func:`raw_controls` finds
what must never reach a terminal.
"""

from __future__ import annotations

import re
from datetime import UTC, datetime
from pathlib import Path

MARKUP_CLOSE = "[/]"
MARKUP_BRACKETS = "KR16 [cell 3]"
MARKUP_CLICK = "[@click=app.quit]press[/]"
MARKUP_LINK = "[link=https://evil.example]site[/link]"
OSC_TITLE = "\x1b]0;pwned\x07"
CSI_CLEAR = "\x1b[2J\x1b[H"
COLOUR = "\x1b[31mred\x1b[0m"
BELL = "ding\x07"
C1_CSI = "c1\x9b31m"
BIDI = "abc\u202edcba\u2066"
LONG = "R" * 100_000

CORPUS: dict[str, str] = {
    "markup close": MARKUP_CLOSE,
    "markup brackets": MARKUP_BRACKETS,
    "markup click": MARKUP_CLICK,
    "markup link": MARKUP_LINK,
    "osc title": OSC_TITLE,
    "csi clear": CSI_CLEAR,
    "colour": COLOUR,
    "bell": BELL,
    "c1": C1_CSI,
    "bidi": BIDI,
    "long": LONG,
}
SHORT_HOSTILE = " ".join(text for name, text in CORPUS.items() if name != "long")
"""Every short hostile string in one line (a robot name, a note, a title)."""

_RAW = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f\u202a-\u202e\u2066-\u2069]")


def raw_controls(text: str) -> list[str]:
    """The control characters and bidi overrides in ``text`` (tab and newline allowed)."""
    return sorted(set(_RAW.findall(text)))


def hostile_session(folder: Path, *, robot: str = SHORT_HOSTILE, cycles: int = 30) -> Path:
    """A finished repeatability session whose header, notes and reject reason are hostile."""
    from session.conftest import reading_fields, session_header_fields

    from station.session.journal import SessionWriter

    header = session_header_fields(robot=robot, operator=SHORT_HOSTILE)
    moment = datetime(2026, 11, 23, 12, 0, 0, tzinfo=UTC)
    with SessionWriter.create(folder, header, now=moment) as writer:
        for cycle in range(1, cycles + 1):
            writer.append("reading", **reading_fields(cycle))
        writer.append("reject", cycle=2, reason=SHORT_HOSTILE)
        writer.append("note", text=SHORT_HOSTILE)
        writer.append("finish", verdict="capable")
    return writer.path


def hostile_running_session(folder: Path, robot: str = SHORT_HOSTILE) -> Path:
    """An unfinished session (offered on the home screen's resume list) with a hostile robot."""
    from session.conftest import reading_fields, session_header_fields

    from station.session.journal import SessionWriter

    header = session_header_fields(robot=robot, operator=SHORT_HOSTILE)
    with SessionWriter.create(folder, header) as writer:
        for cycle in range(1, 4):
            writer.append("reading", **reading_fields(cycle))
    return writer.path


def toml_string(text: str) -> str:
    """``text`` as a TOML basic string: controls and non-ASCII as ``\\uXXXX`` escapes."""
    out = []
    for char in text:
        if char in '"\\':
            out.append("\\" + char)
        elif ord(char) < 0x20 or ord(char) >= 0x7F:
            out.append(f"\\u{ord(char):04x}")
        else:
            out.append(char)
    return '"' + "".join(out) + '"'


HOSTILE_PROCEDURE = (
    'id = "hostile"\n'
    f"title = {toml_string(SHORT_HOSTILE)}\n"
    'version = "1"\n'
    'report_section = "2.6"\n'
    'channels = ["x", "y", "z"]\n'
    'unit = "in"\n'
    "resolution = 0.0001\n"
    "[cycles]\nmin = 2\ntarget = 3\n"
    "[limits]\ntolerance = 0.002\n"
    "[[steps]]\n"
    'id = "look"\nkind = "check"\n'
    f"title = {toml_string(SHORT_HOSTILE)}\n"
    f"text = {toml_string(SHORT_HOSTILE)}\n"
    '[[steps]]\nid = "cycles"\nkind = "cycles"\ntitle = "Cycles"\ntext = "Run the cycles."\n'
)
"""A procedure file whose title and step texts are the hostile line (TOML escapes)."""
