"""Per-robot baselines (phase II): a finished, capable session's centre lines and control limits,
kept so that later sessions of the same robot test their live alarms against them.

One JSON file per robot in ``$XDG_DATA_HOME/station/baselines`` (by default
``~/.local/share/station/baselines``), named by the sanitised robot name and a short hash of the
exact name (two robots whose names sanitise alike never share a file)::

    {"format": "station-baseline/1", "robot": "KSC-7",
     "session": "<uuid>", "file": "<session file name>", "anchor": "<last line hash>",
     "date": "<session created>", "recorded": "<when the baseline was set>",
     "procedure": {"id": ..., "version": ..., "sha256": ...}, "unit": "in",
     "channels": {"x": {"center": ..., "lcl": ..., "ucl": ..., "mr_ucl": ...}, ...}}

:func:`baseline_for` is what the engine calls; the file is written whole or not at all, never
through a symbolic link.
"""

from __future__ import annotations

import hashlib
import json
import math
import re
from collections.abc import Mapping
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from station.analysis.verdict import CAPABLE, PROVISIONAL, Verdict, confidence_text
from station.errors import StationError
from station.record.source import AnalysedSession, analyse_session
from station.session.durable import (
    data_home,
    make_folders,
    refuse_links_below,
    write_text_durably,
)

FORMAT = "station-baseline/1"
_UNSAFE = re.compile(r"[^A-Za-z0-9._-]+")


def baselines_folder(environ: Mapping[str, str] | None = None) -> Path:
    """Where baselines live: ``$XDG_DATA_HOME/station/baselines``; StationError when a level
    of it below ``$XDG_DATA_HOME`` is a symbolic link."""
    home = data_home(environ)
    return refuse_links_below(home, home / "station" / "baselines", "the baselines")


def baseline_path(robot: str, folder: Path | None = None) -> Path:
    """The baseline file of ``robot`` (never a path from the name: sanitised plus a hash)."""
    safe = _UNSAFE.sub("_", robot).strip("._")[:40] or "robot"
    digest = hashlib.sha256(robot.encode("utf-8")).hexdigest()[:10]
    return (folder or baselines_folder()) / f"{safe}-{digest}.json"


def _finite(value: Any) -> float | None:
    return float(value) if isinstance(value, int | float) and math.isfinite(value) else None


def make_baseline(analysed: AnalysedSession) -> dict[str, Any]:
    """The baseline record of a session: refused (StationError, with the sentence) unless the
    session is finished, intact and CAPABLE on every channel it judges.

    CAPABLE is the decision's word (Cpk's one-sided lower bound reaches the threshold), not the
    report's point-estimate rule: a baseline's limits judge every later session of the robot,
    so it must rest on a session the readings show capable. An INCONCLUSIVE (or PROVISIONAL)
    session is refused with what would settle it (the readings needed at its Cpk), never kept
    with a flag that a later session's alarms would not show."""
    session = analysed.session
    name = session.path.name
    if not session.finished:
        raise StationError(
            f"{name} is {session.status}, not finished: a baseline needs a finished session."
        )
    if session.torn is not None:
        raise StationError(f"{name} has a torn tail: a baseline needs an intact session.")
    if analysed.report is None or analysed.report.analysis is None:
        raise StationError(f"{name}: {analysed.problem}; a baseline needs an analysed session.")
    analysis = analysed.report.analysis
    not_capable = [n for n, c in analysis.channels.items() if c.capability.capable is not True]
    if not_capable:
        raise StationError(
            f"{name} is not capable on {', '.join(not_capable)}: a baseline must be a capable "
            "session (its limits would judge later sessions)."
        )
    unsettled = [
        (str(key), channel.verdict)
        for key, channel in analysis.channels.items()
        if channel.verdict is None or channel.verdict.word != CAPABLE
    ]
    if unsettled:
        raise StationError(f"{name} {_unsettled_sentence(unsettled)}")
    channels = {}
    for key, channel in analysis.channels.items():
        chart = channel.chart
        if chart.center is None or chart.ucl is None or chart.lcl is None:
            raise StationError(f"{name}: channel {key} has no control limits to keep.")
        channels[str(key)] = {
            "center": _finite(chart.center),
            "lcl": _finite(chart.lcl),
            "ucl": _finite(chart.ucl),
            "mr_ucl": _finite(chart.dispersion.ucl),
        }
    procedure = session.header.get("procedure") or {}
    return {
        "format": FORMAT,
        "robot": session.robot,
        "session": session.session_id,
        "file": name,
        "anchor": session.last_hash,
        "date": session.created,
        "recorded": datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ"),
        "procedure": {k: procedure.get(k) for k in ("id", "version", "sha256")},
        "kind": analysed.kind,
        "unit": session.unit,
        # The gauge step the limits are written at (one decimal beyond it, as every figure).
        "resolution": session.header.get("resolution"),
        "chart": analysis.channels[next(iter(analysis.channels))].chart.type,
        "channels": channels,
    }


def _unsettled_sentence(unsettled: list[tuple[str, Verdict | None]]) -> str:
    """Why a session capable by the report's rule is no baseline yet, and what would settle it:
    ``is INCONCLUSIVE on x (Cpk 1.17, Bissell 95% bounds 0.90 to 1.44 straddle 1): ...``."""
    parts, settle = [], []
    for channel, verdict in unsettled:
        if verdict is None:
            parts.append(f"{channel} (no verdict)")
            continue
        if verdict.word == PROVISIONAL:
            parts.append(f"{channel} ({verdict.label} readings)")
            settle.append(f"{verdict.min_n - verdict.n} more readings on {channel}")
            continue
        level = f"Bissell {confidence_text(verdict.confidence)}"
        lower = "undefined" if verdict.lower is None else f"{verdict.lower:.2f}"
        upper = "undefined" if verdict.upper is None else f"{verdict.upper:.2f}"
        parts.append(
            f"{channel} ({verdict.word}: Cpk {verdict.cpk_text}, {level} bounds {lower} to "
            f"{upper} straddle {verdict.threshold:g})"
        )
        if verdict.readings_needed is not None:
            settle.append(f"{verdict.readings_needed} readings on {channel}")
    settled = (
        f"a session of {' and '.join(settle)} (at this Cpk) would settle it; capture one and "
        "set that as the baseline"
        if settle
        else "no count of readings would settle it at this Cpk"
    )
    return (
        f"is not shown CAPABLE on {'; '.join(parts)}: a baseline's limits judge every later "
        "session, so it must be a session the readings show capable (the lower bound reaching "
        f"the threshold), not only by the report's rule; {settled}."
    )


def store_baseline(robot: str, session_path: str | Path) -> dict[str, Any]:
    """Record the session at ``session_path`` as ``robot``'s baseline and return the record.
    Refused when the session is of another robot, unfinished, torn or not capable."""
    analysed = analyse_session(session_path)
    if analysed.session.robot != robot:
        raise StationError(
            f"{Path(session_path).name} is a session of robot {analysed.session.robot!r}, "
            f"not {robot!r}; give a session of {robot!r}."
        )
    record = make_baseline(analysed)
    path = baseline_path(robot)
    text = json.dumps(record, indent=2, ensure_ascii=False) + "\n"
    try:
        make_folders(path.parent)
        if path.is_symlink():
            raise StationError(
                f"{path} is a symbolic link; remove it, then set the baseline again."
            )
        write_text_durably(path, text, mode=0o644)
    except OSError as error:
        raise StationError(f"cannot write the baseline {path}: {error.strerror}") from None
    return record


def clear_baseline(robot: str) -> bool:
    """Remove ``robot``'s baseline; False when it had none."""
    path = baseline_path(robot)
    if not path.exists() and not path.is_symlink():
        return False
    path.unlink()
    return True


def baseline_for(robot: str) -> dict[str, Any] | None:
    """``robot``'s baseline record (see the module), or None when it has none.

    ``record["channels"]`` maps each channel to ``{"center", "lcl", "ucl", "mr_ucl"}``: the
    fixed limits live alarms test against; ``session``, ``anchor`` and ``date`` say which
    session they came from (for the new session's header). Raises StationError, naming the
    file, when it is damaged or belongs to another name.
    """
    path = baseline_path(robot)
    if not path.exists():
        return None
    if path.is_symlink() or not path.is_file():
        raise StationError(f"{path} is not a plain file; remove it and set the baseline again.")
    try:
        record = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
        raise StationError(
            f"the baseline {path} cannot be read ({error}); clear it with "
            f"`station baseline ROBOT --clear` and set it again."
        ) from None
    channels = record.get("channels") if isinstance(record, dict) else None
    if (
        not isinstance(record, dict)
        or record.get("format") != FORMAT
        or record.get("robot") != robot
        or not isinstance(channels, dict)
        or not all(
            isinstance(spec, dict) and all(k in spec for k in ("center", "lcl", "ucl", "mr_ucl"))
            for spec in channels.values()
        )
    ):
        raise StationError(
            f"the baseline {path} is not a station baseline of robot {robot!r}; clear it with "
            "`station baseline ROBOT --clear` and set it again."
        )
    return record


def header_baseline(robot: str, procedure: str, unit: str) -> dict[str, Any] | None:
    """``robot``'s baseline as a new session's header records it (the phase II limits its live
    alarms test against, and which session they came from), or None when it has none for this
    procedure and unit (a baseline of another procedure or unit says nothing here)."""
    record = baseline_for(robot)
    recorded = record.get("procedure") if record is not None else None
    recorded_id = recorded.get("id") if isinstance(recorded, dict) else recorded
    if record is None or recorded_id != procedure or record.get("unit") != unit:
        return None
    anchor = str(record.get("anchor") or "")
    source = f"baseline of session {record.get('session')} ({record.get('date')})"
    return {
        "source": source,
        "session": record.get("session"),
        "anchor": anchor,
        "limits": {
            channel: {"center": spec["center"], "ucl": spec["ucl"], "lcl": spec["lcl"]}
            for channel, spec in record["channels"].items()
        },
    }
