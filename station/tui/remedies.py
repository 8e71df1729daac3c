"""How the TUI words the remedy a domain error names: a field to fill, a key to press. The
command line words the same codes as options (``station/commands/_remedies.py``)."""

from __future__ import annotations

from station.errors import StationError

TUI_REMEDIES: dict[str, str] = {
    "map_channel": "map one in the Channel map field, e.g. 1=x,2=y,3=z",
    "give_limits": "type limits in the set-up's limits fields",
    "give_tolerance": "give limits on h and v in the set-up",
    "resume_session": "free space, then resume it from the home screen (R)",
    "list_ports": "the Port list shows the ports this machine has",
    "serial_settings": "choose the line's settings in the set-up (a pseudo-terminal takes 8N1)",
    "choose_sessions_folder": "start station with another sessions folder",
    "choose_link_path": "choose another link path",
    "split_channels": "give each simulated gauge its own port",
    "choose_procedures_folder": "start station with an existing procedures folder",
}


def explained(error: StationError) -> str:
    """The error's sentence with its remedy in the TUI's words."""
    return error.worded(TUI_REMEDIES)
