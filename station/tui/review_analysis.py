"""The analysis of a saved session, as ``station analyze FILE`` and the live runner compute it.

The settings come from the session header through the runner's ``analysis_config`` (the one
place that turns a header into an analysis configuration); rejected cycles are left out.
"""

from __future__ import annotations

from typing import Any


def analyze_session(session: Any) -> Any:
    """The ``Analysis`` of a loaded session (``station.session.model.Session``), or None when
    it has no accepted cycle yet."""
    from station.analysis.summary import analyze
    from station.runner import analysis_config

    channels = {name: values for name, values in session.channel_values().items() if len(values)}
    if not channels:
        return None
    return analyze(
        channels, analysis_config(session.header), excluded_cycles=session.excluded_cycles
    )
