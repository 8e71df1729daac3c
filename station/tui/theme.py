"""How the station reads without colour: the verdict and alarm styles, and the themes.

Under ``NO_COLOR`` Textual turns every colour into a grey of the same luminance, so "bold red"
on a dark background became grey 237 on 234 (issue 13): the verdict vanished. The verdict and
alarm styles here therefore carry their meaning in text attributes (bold, reverse video,
underline) and, without colour, name no colour at all; and the app draws no colour at all
under ``NO_COLOR`` (``StationApp.get_line_filters``: the terminal's own foreground and
background, issue 26), so the attributes are what is left, and they read.
``STATION_THEME=high-contrast`` picks a black-and-white theme with the same attributes for a
washed-out screen in a bright workshop.

Front ends import ``VERDICT_STYLES`` and ``ALARM_STYLES`` from here; :func:`apply_palette`
fills them in place when the app starts, so every screen agrees.
"""

from __future__ import annotations

import os

from textual.theme import Theme

HIGH_CONTRAST = "station-high-contrast"

HIGH_CONTRAST_THEME = Theme(
    name=HIGH_CONTRAST,
    primary="#ffffff",
    secondary="#ffffff",
    accent="#ffff00",
    foreground="#ffffff",
    background="#000000",
    surface="#000000",
    panel="#000000",
    boost="#000000",
    warning="#ffff00",
    error="#ff5555",
    success="#55ff55",
    dark=True,
    variables={
        "text-muted": "#ffffff",
        "block-cursor-background": "#ffffff",
        "block-cursor-foreground": "#000000",
        "block-cursor-text-style": "bold",
        "input-selection-background": "#ffffff 50%",
        "footer-key-foreground": "#ffff00",
        "border": "#ffffff",
        "border-blurred": "#808080",
    },
)

_COLOUR_VERDICTS = {
    "CAPABLE": "bold green",
    "NOT CAPABLE": "bold reverse red",
    "UNDEFINED": "bold underline yellow",
    "PROVISIONAL": "bold underline yellow",
    # A gauge study's own verdict, styled as the capability words it stands beside.
    "ACCEPTABLE": "bold green",
    "NOT ACCEPTABLE": "bold reverse red",
    "INCONCLUSIVE": "bold underline yellow",
}
_PLAIN_VERDICTS = {
    "CAPABLE": "bold",
    "NOT CAPABLE": "bold reverse",
    "UNDEFINED": "bold underline",
    "PROVISIONAL": "bold underline",
    "ACCEPTABLE": "bold",
    "NOT ACCEPTABLE": "bold reverse",
    "INCONCLUSIVE": "bold underline",
}
_COLOUR_ALARMS = {"head": "bold reverse red", "line": "bold red", "none": ""}
_PLAIN_ALARMS = {"head": "bold reverse", "line": "bold", "none": ""}

VERDICT_STYLES: dict[str, str] = dict(_COLOUR_VERDICTS)
"""Verdict word -> rich style: always bold, NOT CAPABLE in reverse video, UNDEFINED underlined."""
ALARM_STYLES: dict[str, str] = dict(_COLOUR_ALARMS)
"""``head`` (the alarm log's count), ``line`` (one alarm), ``none`` ("alarms: none")."""


def wanted_theme() -> str | None:
    """The theme ``STATION_THEME`` asks for (``high-contrast``), or None for Textual's own."""
    name = os.environ.get("STATION_THEME", "").strip().lower()
    return HIGH_CONTRAST if name in ("high-contrast", "high_contrast", HIGH_CONTRAST) else None


def apply_palette(*, colour: bool) -> None:
    """Fill the verdict and alarm styles for a screen with or without colour (in place, so
    modules that imported the dictionaries see the change)."""
    VERDICT_STYLES.clear()
    VERDICT_STYLES.update(_COLOUR_VERDICTS if colour else _PLAIN_VERDICTS)
    ALARM_STYLES.clear()
    ALARM_STYLES.update(_COLOUR_ALARMS if colour else _PLAIN_ALARMS)
