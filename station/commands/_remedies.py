"""How the command line words the remedy a domain error names (an option to give, a command to
run). The TUI words the same codes as keys and fields (``station/tui/remedies.py``)."""

from __future__ import annotations

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
