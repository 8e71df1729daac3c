"""The set-up remembered between sessions: a small per-user TOML file.

``$XDG_CONFIG_HOME/station/settings.toml`` (``~/.config/station/`` when the variable is unset)
keeps the last new session's robot, operator, port, protocol, channel map and trigger, so the
technician does not type them again each time (issue 13). The set-up screen shows them as
pre-filled values and says where they came from; a resume never reads them (a resumed session
keeps what its own file recorded). The file is written whole or not at all, never through a
link, and a damaged file is ignored with a sentence rather than stopping the program.

Format::

    # written by station: the last set-up, offered as pre-filled values
    [last]
    robot = "R1"
    operator = "jdoe"
    port = "/dev/ttyUSB0"
    protocol = "mitutoyo"
    channel_map = "1=x,2=y,3=z"
    trigger = "poll"
"""

from __future__ import annotations

import json
import tomllib
from dataclasses import asdict, dataclass, fields
from pathlib import Path

from station.errors import StationError
from station.session.durable import make_folders, write_text_durably
from station.session.signing import config_folder

SETTINGS_FILE_NAME = "settings.toml"
MAX_VALUE_LENGTH = 500
"""Longer values in the file are ignored (a file edited by hand or damaged)."""


@dataclass(frozen=True)
class RememberedSetup:
    """The last set-up's line and names; empty strings are not remembered."""

    robot: str = ""
    operator: str = ""
    port: str = ""
    protocol: str = ""
    channel_map: str = ""
    trigger: str = ""

    def filled(self) -> dict[str, str]:
        """The remembered values that are not empty, by field name."""
        return {key: value for key, value in asdict(self).items() if value}


def settings_path() -> Path:
    """Where the settings file lives."""
    return config_folder() / SETTINGS_FILE_NAME


def load_remembered(path: Path | None = None) -> tuple[RememberedSetup, str]:
    """The remembered set-up and, when the file could not be read, a sentence saying why
    (the set-up is then empty). A missing file is no fault."""
    try:
        path = path or settings_path()
    except StationError as error:
        return RememberedSetup(), f"{error.message}; nothing was pre-filled"
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        return RememberedSetup(), ""
    except (OSError, UnicodeDecodeError) as error:
        return RememberedSetup(), f"{path} could not be read ({error}); nothing was pre-filled"
    try:
        table = tomllib.loads(text).get("last", {})
    except tomllib.TOMLDecodeError as error:
        return RememberedSetup(), f"{path} is not valid TOML ({error}); nothing was pre-filled"
    if not isinstance(table, dict):
        return RememberedSetup(), f"{path}: [last] is not a table; nothing was pre-filled"
    values = {}
    for field in fields(RememberedSetup):
        value = table.get(field.name)
        if isinstance(value, str) and len(value) <= MAX_VALUE_LENGTH:
            values[field.name] = value
    return RememberedSetup(**values), ""


def save_remembered(setup: RememberedSetup, path: Path | None = None) -> None:
    """Write ``setup`` (whole or not at all, never through a link). OSError or StationError
    when it cannot be written; the caller says so and carries on."""
    path = path or settings_path()
    make_folders(path.parent)
    lines = ["# written by station: the last set-up, offered as pre-filled values", "[last]"]
    for key, value in asdict(setup).items():
        # A JSON string is a valid TOML basic string (same escapes, \\uXXXX for controls).
        lines.append(f"{key} = {json.dumps(value, ensure_ascii=False)}")
    write_text_durably(path, "\n".join(lines) + "\n")
