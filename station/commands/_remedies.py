"""How the command line words the remedy a domain error names (an option to give, a command to
run). The TUI words the same codes as keys and fields (``station/tui/remedies.py``)."""

from __future__ import annotations

from station.errors import StationError

CLI_REMEDIES: dict[str, str] = {
    "map_channel": "map one with --map, e.g. 1=x,2=y,3=z",
    "give_limits": "give --lsl/--usl or --limit CH=LSL:USL",
    "give_tolerance": "give --tolerance T, or limits on h and v in the procedure",
    "resume_session": "resume with `station capture --resume {subject}`",
    "list_ports": "see `station ports`",
    "serial_settings": "set --baud, --bytesize, --parity and --stopbits",
    "choose_sessions_folder": "give another folder with --sessions DIR",
    "choose_link_path": "choose another --link path",
    "split_channels": "run one simulator per channel (e.g. --channels x)",
    "choose_procedures_folder": "name an existing folder with --procedures",
}


CLI_FIELDS: dict[str, str] = {
    "map": "--map",
    "limits": "--limit",
    "robot": "--robot",
    "port": "--port",
    "trigger": "--trigger",
    "cycles": "--cycles",
    "placements": "--placements",
    "strokes": "--strokes",
    "resolution": "--resolution",
}
"""The option that sets each field a domain error may name."""


def cli_sentence(error: StationError) -> str:
    """A domain error as the command line says it: the option of the field it names first,
    then the sentence with the remedy in the command line's words."""
    option = CLI_FIELDS.get(error.field or "")
    sentence = error.worded(CLI_REMEDIES)
    return f"{option}: {sentence}" if option and not sentence.startswith(option) else sentence
