"""The gauge register: which indicator was checked when, with what result, and when it is due.

A verdict on a robot is only as good as the gauges that measured it. The register is one small
JSON file in the station's data folder (``$XDG_DATA_HOME/station/gauges.json``, by default
``~/.local/share/station/gauges.json``; ``STATION_GAUGES`` names another file). Per gauge id or
serial it keeps the Type-1 checks recorded (newest last, at most :data:`HISTORY` of them) and
the calibration due date::

    {"format": "station-gauges/1",
     "gauges": {"MIT-543-0042": {"calibration_due": "2027-05-01",
                                 "certificate": {"U": 0.00004, "k": 2, "date": "2026-10-01",
                                                 "id": "C-12"},
                                 "checks": [{"date": "2026-11-29", "result": "passed",
                                             "cg": 2.1, "cgk": 1.8, "bias": 0.00002,
                                             "bias_p": 0.31, "reference": 1.0,
                                             "tolerance": 0.002, "n": 25, "sd": 0.00003,
                                             "session": "..."}],
                                 "studies": {"gauge_linearity": [{"date": "2026-11-30",
                                             "result": "acceptable", "slope": 0.0002, ...}]}}}}

The certificate (:func:`record_certificate`) and the latest check's SD (its repeatability) are
lines of every later session's measurement budget: a session records them in its header's
``gauge_checks`` snapshot when it begins (:meth:`GaugeStatus.as_json`).

Other studies of a gauge (a linearity and bias study over its travel) are kept beside its checks,
per method (:func:`record_study`); they do not decide whether a check covers the gauge.

A repeatability session names the gauge on each channel; :func:`coverage` looks each up
(passed, failed, overdue or none) so the session can record which checks covered it and its
verdict can say "gauge check passed on DATE" or warn. A check is *overdue* when the gauge's
calibration due date has passed, or when the last check is older than ``valid_days`` (the
report asks for calibration and testing "every four to six months": 183 days by default).

Writes are whole or nothing: a temporary file (created exclusively, never through a symlink)
is synced and renamed over the register, under an advisory lock so two stations on one machine
do not lose each other's check. A register that is a symlink is refused, not followed.
"""

from __future__ import annotations

import contextlib
import datetime as dt
import errno
import fcntl
import json
import math
import os
import textwrap
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

from station.errors import StationError
from station.session.durable import (
    data_home,
    make_folders,
    refuse_links_below,
    write_text_durably,
)

if TYPE_CHECKING:
    from station.analysis.gauge_check import GaugeCheck

FORMAT = "station-gauges/1"
REGISTER_ENV = "STATION_GAUGES"
#: Checks kept per gauge (the oldest are dropped).
HISTORY = 50
#: How long a passed check covers a gauge: the report's "every four to six months".
VALID_DAYS = 183

State = Literal["passed", "failed", "overdue", "none"]


def register_path(environ: Mapping[str, str] | None = None) -> Path:
    """The register file: ``STATION_GAUGES``, else ``$XDG_DATA_HOME/station/gauges.json``
    (StationError when a level of it below ``$XDG_DATA_HOME`` is a symbolic link)."""
    environ = os.environ if environ is None else environ
    if environ.get(REGISTER_ENV):
        return Path(environ[REGISTER_ENV])
    home = data_home(environ)
    return refuse_links_below(home, home / "station" / "gauges.json", "the gauge register")


def parse_date(text: str | dt.date, what: str = "date") -> dt.date:
    """A date written ``YYYY-MM-DD`` (as typed at an input step); StationError otherwise."""
    if isinstance(text, dt.date):
        return text
    try:
        return dt.date.fromisoformat(str(text).strip())
    except ValueError:
        raise StationError(f"the {what} {text!r} is not a date; write it as YYYY-MM-DD.") from None


def _refuse_symlink(path: Path) -> None:
    if path.is_symlink():
        raise StationError(
            f"the gauge register {path} is a symbolic link; station does not follow links for "
            "files it writes: replace it with the file itself."
        )


def load_register(path: Path) -> dict[str, Any]:
    """The register's content (an empty register when the file does not exist yet)."""
    _refuse_symlink(path)
    try:
        descriptor = os.open(path, os.O_RDONLY | os.O_NOFOLLOW)
    except FileNotFoundError:
        return {"format": FORMAT, "gauges": {}}
    except OSError as error:
        raise StationError(f"cannot read the gauge register {path}: {error.strerror}.") from None
    with os.fdopen(descriptor, "rb") as stream:
        data = stream.read()
    try:
        content = json.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError):
        raise StationError(
            f"the gauge register {path} is damaged (not JSON); move it aside to start a new one."
        ) from None
    if (
        not isinstance(content, dict)
        or content.get("format") != FORMAT
        or not isinstance(content.get("gauges"), dict)
    ):
        raise StationError(
            f"the gauge register {path} is not a {FORMAT} file; move it aside to start a new one."
        )
    return content


@contextlib.contextmanager
def _locked(path: Path) -> Iterator[None]:
    lock_path = path.with_name(f".{path.name}.lock")
    _refuse_symlink(lock_path)
    descriptor = os.open(lock_path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW, 0o644)
    try:
        fcntl.flock(descriptor, fcntl.LOCK_EX)
        yield
    finally:
        os.close(descriptor)


def _write(path: Path, content: Mapping[str, Any]) -> None:
    text = json.dumps(content, indent=2, ensure_ascii=False, allow_nan=False) + "\n"
    write_text_durably(path, text, mode=0o644)


def _gauge_key(gauge: str) -> str:
    key = str(gauge).strip()
    if not key or any(not ch.isprintable() for ch in key) or len(key) > 100:
        raise StationError(
            f"gauge id {gauge!r} cannot be registered: give the gauge's id or serial number "
            "(printable, up to 100 characters)."
        )
    return key


def record_check(
    path: Path,
    gauge: str,
    study: GaugeCheck,
    *,
    when: dt.date,
    calibration_due: dt.date | str | None = None,
    session: str | None = None,
    port: Mapping[str, str] | None = None,
) -> dict[str, Any]:
    """Add a Type-1 study of ``gauge`` done on ``when`` to the register at ``path`` (created
    with its folder when missing); ``calibration_due`` updates the gauge's due date; ``port``
    (``{"url", "device"}``: the line and device channel the gauge was read on) lets a later
    session on that line find the gauge (:func:`gauges_on_ports`). Returns the entry recorded.
    StationError when the register cannot be read or written."""
    result = {"capable": "passed", "not capable": "failed"}.get(study.verdict, "no verdict")
    entry: dict[str, Any] = {
        "date": when.isoformat(),
        "result": result,
        **{k: study.as_json()[k] for k in ("cg", "cgk", "bias", "bias_p", "resolution_ratio")},
        "reference": study.reference,
        "tolerance": study.tolerance,
        "n": study.n,
        # The repeatability a later session's measurement budget takes (s on n − 1).
        "sd": study.sd,
    }
    if session:
        entry["session"] = session
    return _file(path, gauge, entry, lambda record: (record, "checks"), calibration_due, port)


def record_study(
    path: Path,
    gauge: str,
    method: str,
    entry: Mapping[str, Any],
    *,
    calibration_due: dt.date | str | None = None,
    port: Mapping[str, str] | None = None,
) -> dict[str, Any]:
    """Add a study other than a Type-1 check (``method``: the study's method, e.g.
    ``gauge_linearity``; ``entry``: its date, result and figures) of ``gauge`` to the register
    at ``path``, beside its checks (newest last, at most :data:`HISTORY` per method);
    ``calibration_due`` updates the gauge's due date, ``port`` is where it was read. Returns
    the entry recorded. StationError when the register cannot be read or written."""

    def place(record: dict[str, Any]) -> tuple[dict[str, Any], str]:
        return record.setdefault("studies", {}), method

    return _file(path, gauge, dict(entry), place, calibration_due, port)


def _file(
    path: Path,
    gauge: str,
    entry: dict[str, Any],
    place: Any,
    calibration_due: dt.date | str | None,
    port: Mapping[str, str] | None,
) -> dict[str, Any]:
    """Append ``entry`` to the list ``place(gauge's record)`` names (its holder and key), with
    the port it was read on, under the register's lock; the gauge's due date updated. A session
    filed again (``station gauges record`` after the finish filed it) replaces its own entry."""
    key = _gauge_key(gauge)
    if port:
        entry["port"] = {"url": str(port["url"]), "device": str(port["device"])}
    due = None if calibration_due in (None, "") else parse_date(calibration_due, "calibration due")
    try:
        make_folders(path.parent)
        with _locked(path):
            content = load_register(path)
            record = content["gauges"].setdefault(key, {"calibration_due": None, "checks": []})
            if due is not None:
                record["calibration_due"] = due.isoformat()
            holder, name = place(record)
            session = entry.get("session")
            kept = [e for e in holder.get(name, []) if not _same_session(e, session)]
            holder[name] = [*kept, entry][-HISTORY:]
            _write(path, content)
    except OSError as error:
        reason = error.strerror or str(error)
        if error.errno == errno.ELOOP:
            reason = "a symbolic link is in the way"
        raise StationError(f"cannot write the gauge register {path}: {reason}.") from None
    return entry


def _same_session(entry: Any, session: str | None) -> bool:
    return bool(session) and isinstance(entry, Mapping) and entry.get("session") == session


def latest_studies(record: Mapping[str, Any] | None) -> dict[str, dict[str, Any]]:
    """The newest study of each method a register entry holds (none for a gauge with only
    Type-1 checks, or an entry from before studies were kept)."""
    studies = (record or {}).get("studies")
    if not isinstance(studies, Mapping):
        return {}
    return {
        str(method): dict(entries[-1])
        for method, entries in studies.items()
        if isinstance(entries, list) and entries and isinstance(entries[-1], Mapping)
    }


def study_sentence(method: str, entry: Mapping[str, Any]) -> str:
    """``gauge_linearity: acceptable on 2026-11-30`` (its summary, where the entry has one)."""
    name = "".join(ch if ch.isprintable() else "?" for ch in method)
    summary = entry.get("summary")
    tail = f" ({summary})" if isinstance(summary, str) and summary else ""
    return f"{name}: {entry.get('result', 'no result')} on {entry.get('date', '?')}{tail}"


@dataclass(frozen=True)
class GaugeStatus:
    """What the register says of one gauge on a given day."""

    gauge: str
    state: State
    checked: dt.date | None
    calibration_due: dt.date | None
    cg: float | None = None
    cgk: float | None = None
    reason: str = ""
    sd: float | None = None
    """The latest Type-1 check's sample SD (its repeatability), None when not recorded."""
    n: int | None = None
    """How many readings that SD is of."""
    certificate: Mapping[str, Any] | None = None
    """The gauge's calibration certificate as recorded (``{"U", "k", "date", "id"}``)."""

    @property
    def covered(self) -> bool:
        """True when a passed, current check covers the gauge."""
        return self.state == "passed"

    def sentence(self) -> str:
        """``gauge check passed on 2026-11-02`` or a warning naming what is wrong."""
        name = "".join(ch if ch.isprintable() else "?" for ch in self.gauge)
        if self.state == "passed":
            due = (
                f", calibration due {self.calibration_due.isoformat()}"
                if self.calibration_due
                else ""
            )
            return f"gauge {name}: gauge check passed on {self.checked}{due}"
        if self.state == "none":
            return f"WARNING: gauge {name}: no gauge check on record; run the gauge_check procedure"
        if self.state == "failed":
            return (
                f"WARNING: gauge {name}: its last gauge check ({self.checked}) failed"
                f"{self.reason}; the verdict rests on a gauge that is not capable"
            )
        return f"WARNING: gauge {name}: {self.reason}; check it again before trusting the verdict"

    def as_json(self) -> dict[str, Any]:
        """The status as recorded in a session (a snapshot: the register changes later)."""
        return {
            "gauge": self.gauge,
            "state": self.state,
            "checked": None if self.checked is None else self.checked.isoformat(),
            "calibration_due": None
            if self.calibration_due is None
            else self.calibration_due.isoformat(),
            "cg": self.cg,
            "cgk": self.cgk,
            "sd": self.sd,
            "n": self.n,
            "certificate": None if self.certificate is None else dict(self.certificate),
            "reason": self.reason,
            "sentence": self.sentence(),
        }


def gauge_status(
    register: Mapping[str, Any], gauge: str, today: dt.date, *, valid_days: int = VALID_DAYS
) -> GaugeStatus:
    """The state of ``gauge`` on ``today`` in a loaded register (:func:`load_register`):
    ``none`` (never checked), ``failed`` (its last check did not pass), ``overdue`` (its
    calibration due date has passed, or its last check is older than ``valid_days``) or
    ``passed``."""
    record = register.get("gauges", {}).get(str(gauge).strip())
    certificate = certificate_of(record)
    if not record or not record.get("checks"):
        return GaugeStatus(str(gauge), "none", None, None, certificate=certificate)
    last = record["checks"][-1]
    checked = parse_date(last["date"], "check date")
    due = record.get("calibration_due")
    due_date = None if not due else parse_date(due, "calibration due date")
    sd, n = check_repeatability(last)
    common = {
        "cg": last.get("cg"),
        "cgk": last.get("cgk"),
        "sd": sd,
        "n": n,
        "certificate": certificate,
    }
    if last.get("result") != "passed":
        cg, cgk = last.get("cg"), last.get("cgk")
        detail = (
            f" (Cg {cg:.2f}, Cgk {cgk:.2f})"
            if isinstance(cg, int | float) and isinstance(cgk, int | float)
            else " (no verdict)"
        )
        return GaugeStatus(str(gauge), "failed", checked, due_date, reason=detail, **common)
    if due_date is not None and due_date < today:
        return GaugeStatus(
            str(gauge),
            "overdue",
            checked,
            due_date,
            reason=f"calibration was due on {due_date.isoformat()}",
            **common,
        )
    age = (today - checked).days
    if age > valid_days:
        return GaugeStatus(
            str(gauge),
            "overdue",
            checked,
            due_date,
            reason=f"its last check ({checked.isoformat()}) is {age} days old (over {valid_days})",
            **common,
        )
    return GaugeStatus(str(gauge), "passed", checked, due_date, **common)


def _positive(value: Any) -> float | None:
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    return float(value) if math.isfinite(value) and value > 0 else None


def check_repeatability(check: Mapping[str, Any]) -> tuple[float | None, int | None]:
    """A Type-1 check entry's repeatability: its sample SD and count. An entry from before the
    SD was recorded gives it back from Cg and the tolerance (Cg = 0.2·T / 6s, the check's own
    formula, :mod:`station.analysis.gauge_check`); (None, None) when neither is there."""
    n = check.get("n")
    count = n if isinstance(n, int) and not isinstance(n, bool) and n >= 2 else None
    if count is None:
        return None, None
    sd = check.get("sd")
    if isinstance(sd, int | float) and not isinstance(sd, bool) and math.isfinite(sd) and sd >= 0:
        return float(sd), count
    cg, tolerance = _positive(check.get("cg")), _positive(check.get("tolerance"))
    if cg is None or tolerance is None:
        return None, None
    # Deferred: the register is read by commands that need no numpy.
    from station.analysis.gauge_check import PERCENT_OF_TOLERANCE, SPREAD_SIGMAS

    return (PERCENT_OF_TOLERANCE / 100 * tolerance) / (SPREAD_SIGMAS * cg), count


def certificate_of(record: Mapping[str, Any] | None) -> dict[str, Any] | None:
    """A gauge's calibration certificate as the register holds it (``{"U", "k", "date",
    "id"}``), None when none is recorded or its U and k are not usable numbers."""
    found = (record or {}).get("certificate")
    if not isinstance(found, Mapping):
        return None
    expanded, k = found.get("U"), _positive(found.get("k"))
    if isinstance(expanded, bool) or not isinstance(expanded, int | float) or k is None:
        return None
    if not (math.isfinite(expanded) and expanded >= 0):
        return None
    return {
        "U": float(expanded),
        "k": k,
        "date": found.get("date"),
        "id": found.get("id"),
    }


def record_certificate(
    path: Path,
    gauge: str,
    *,
    expanded: float,
    k: float,
    date: dt.date | str | None = None,
    certificate_id: str | None = None,
    calibration_due: dt.date | str | None = None,
) -> dict[str, Any]:
    """Record ``gauge``'s calibration certificate in the register at ``path``: its expanded
    uncertainty ``expanded`` at coverage ``k`` (the budget's certificate line is U/k), the
    date and number of the certificate; it replaces the one recorded before. StationError on
    a U that is negative or not finite, a k that is not above 0, or a register that cannot be
    written."""
    from station.analysis.uncertainty import check_coverage

    if isinstance(expanded, bool) or not isinstance(expanded, int | float):
        raise StationError(f"the certificate's U must be a number, not {expanded!r}.")
    if not (math.isfinite(expanded) and expanded >= 0):
        raise StationError(
            f"the certificate's U must be a finite number 0 or more, not {expanded!r}."
        )
    entry: dict[str, Any] = {
        "U": float(expanded),
        "k": check_coverage(k, "the certificate's k"),
        "date": None if date in (None, "") else parse_date(date, "certificate date").isoformat(),
        "id": None if not certificate_id else str(certificate_id),
    }
    key = _gauge_key(gauge)
    due = None if calibration_due in (None, "") else parse_date(calibration_due, "calibration due")
    try:
        make_folders(path.parent)
        with _locked(path):
            content = load_register(path)
            record = content["gauges"].setdefault(key, {"calibration_due": None, "checks": []})
            record["certificate"] = entry
            if due is not None:
                record["calibration_due"] = due.isoformat()
            _write(path, content)
    except OSError as error:
        raise StationError(
            f"cannot write the gauge register {path}: {error.strerror or error}."
        ) from None
    return entry


def coverage(
    gauges: Mapping[str, str],
    today: dt.date,
    *,
    path: Path | None = None,
    valid_days: int = VALID_DAYS,
) -> dict[str, GaugeStatus]:
    """Per channel the status of the gauge on it (``{"x": "MIT-0042", ...}``) on ``today``,
    from the register at ``path`` (default :func:`register_path`). A channel without a gauge id
    is ``none``."""
    register = load_register(path or register_path())
    return {
        channel: gauge_status(register, gauge, today, valid_days=valid_days)
        if str(gauge).strip()
        else GaugeStatus("(not named)", "none", None, None)
        for channel, gauge in gauges.items()
    }


def coverage_lines(statuses: Mapping[str, GaugeStatus | Mapping[str, Any]]) -> list[str]:
    """The verdict's lines on the gauges: one per channel, from :func:`coverage` or from the
    snapshot a session recorded (``GaugeStatus.as_json()``); a line saying there are no gauge
    ids when the session named none."""
    if not statuses:
        return [
            "WARNING: the session names no gauges, so no gauge check covers it; "
            "run the gauge_check procedure and name the gauges at set-up"
        ]
    lines = []
    for channel, status in statuses.items():
        sentence = status.sentence() if isinstance(status, GaugeStatus) else status["sentence"]
        lines.append(f"{channel}: {sentence}")
    return lines


def session_gauges(header: Mapping[str, Any]) -> dict[str, str]:
    """The gauge id on each channel as a session header records it (``"gauges": {"x":
    "MIT-0042", ...}``); empty when the session names none."""
    recorded = header.get("gauges") or {}
    if not isinstance(recorded, Mapping):
        return {}
    return {str(channel): str(gauge) for channel, gauge in recorded.items()}


def verdict_lines(
    header: Mapping[str, Any],
    today: dt.date,
    *,
    path: Path | None = None,
    valid_days: int = VALID_DAYS,
) -> list[str]:
    """The gauge lines of a repeatability session's verdict: from the snapshot its header
    recorded at the start (``"gauge_checks": {channel: GaugeStatus.as_json()}``), else looked up
    now in the register for the gauges the header names (``"gauges"``); a warning when it names
    none. A damaged register is a warning line, never a lost verdict."""
    recorded = header.get("gauge_checks")
    if isinstance(recorded, Mapping) and all(
        isinstance(v, Mapping) and "sentence" in v for v in recorded.values()
    ):
        return coverage_lines(recorded)
    gauges = session_gauges(header)
    if not gauges:
        return coverage_lines({})
    try:
        return coverage_lines(coverage(gauges, today, path=path, valid_days=valid_days))
    except StationError as error:
        return [f"WARNING: the gauge register cannot be read ({error.message})"]


def all_covered(statuses: Mapping[str, GaugeStatus | Mapping[str, Any]]) -> bool:
    """True when every channel's gauge has a passed, current check (and there is at least one):
    the condition for a verdict that rests on checked gauges."""
    if not statuses:
        return False
    return all(
        (s.state if isinstance(s, GaugeStatus) else s.get("state")) == "passed"
        for s in statuses.values()
    )


def register_rows(register: Mapping[str, Any], today: dt.date) -> list[GaugeStatus]:
    """Every gauge in a loaded register with its status on ``today``, by id."""
    return [gauge_status(register, gauge, today) for gauge in sorted(register.get("gauges", {}))]


def gauges_on_ports(register: Mapping[str, Any], ports: Any) -> dict[str, str]:
    """Per station channel, the gauge whose newest check was read on the same line and device
    channel (a session header's ``instruments.ports``: ``[{"url", "map": {device: channel}}]``).
    A line named by ``/dev/serial/by-id/...`` or a device server's address keeps its name
    from one day to the next; ``/dev/ttyUSB0`` may not, so name the gauge when in doubt."""
    newest: dict[tuple[str, str], tuple[str, str]] = {}
    for gauge, record in (register.get("gauges") or {}).items():
        for check in (record or {}).get("checks") or ():
            port = check.get("port") if isinstance(check, Mapping) else None
            if not isinstance(port, Mapping):
                continue
            key = (str(port.get("url")), str(port.get("device")))
            date = str(check.get("date") or "")
            if key not in newest or newest[key][0] <= date:
                newest[key] = (date, str(gauge))
    found: dict[str, str] = {}
    for port in ports or ():
        if not isinstance(port, Mapping):
            continue
        for device, channel in dict(port.get("map") or {}).items():
            hit = newest.get((str(port.get("url")), str(device)))
            if hit is not None:
                found.setdefault(str(channel), hit[1])
    return found


def coverage_fields(
    fields: Mapping[str, Any],
    today: dt.date | None = None,
    *,
    path: Path | None = None,
) -> dict[str, Any]:
    """What a new session's header records of its gauges (given the header's other fields):
    ``gauges``, the gauge on each channel (named at set-up, else the one the register last saw
    on its line and device channel), and ``gauge_checks``, each channel's
    :meth:`GaugeStatus.as_json` on ``today``. A register that cannot be read is recorded as
    a warning on every channel: the session starts all the same."""
    today = today or dt.date.today()
    channels = [str(c) for c in fields.get("channels") or ()]
    named = session_gauges(fields)
    try:
        register = load_register(path or register_path())
        ports = (fields.get("instruments") or {}).get("ports") or ()
        gauges = {**gauges_on_ports(register, ports), **named}
        gauges = {channel: gauges[channel] for channel in channels if channel in gauges}
        statuses = {
            channel: gauge_status(register, gauges[channel], today).as_json()
            if channel in gauges
            else {
                **GaugeStatus("(not named)", "none", None, None).as_json(),
                "sentence": "WARNING: no gauge check covers this channel (no gauge named, and "
                "none checked on its line in the gauge register); run the gauge_check procedure",
            }
            for channel in channels
        }
    except StationError as error:
        warning = f"WARNING: the gauge register cannot be read ({error.message})"
        gauges = named
        statuses = {channel: {"state": "unknown", "sentence": warning} for channel in channels}
    return {"gauges": gauges, "gauge_checks": statuses}


def gauge_block(
    header: Mapping[str, Any] | None, width: int = 80, today: dt.date | None = None
) -> tuple[tuple[str, ...], ...]:
    """The report block of the gauge checks a session recorded at its start (its header's
    ``gauge_checks``): which check covers each gauge, or a warning, wrapped to ``width``. No
    block for a CSV table (``header`` None) or a file from before the gauge register."""
    if header is None or "gauge_checks" not in header:
        return ()
    lines = [
        wrapped
        for line in verdict_lines(header, today or dt.date.today())
        for wrapped in textwrap.wrap(
            line, width=max(width, 40), initial_indent="  ", subsequent_indent="      "
        )
    ]
    return (("GAUGE CHECKS (the gauge register when the session began)", *lines),)


def port_of(header: Mapping[str, Any], channel: str) -> dict[str, str] | None:
    """The line and device channel ``channel`` was read on, as a session's header records its
    instruments (``{"url", "device"}``), or None when it records none."""
    for recorded in (header.get("instruments") or {}).get("ports") or ():
        for device, mapped in dict(recorded.get("map") or {}).items():
            if mapped == channel:
                return {"url": str(recorded.get("url")), "device": str(device)}
    return None


def filed_line(session_id: str, path: Path | None = None) -> str:
    """Where a gauge-check session stands in the register: ``gauge register: G-1, passed on
    DATE (this session)``, or that it is not filed (yet), or that the register cannot be read."""
    try:
        register = load_register(path or register_path())
    except StationError as error:
        return f"gauge register: cannot be read ({error.message})"
    for gauge, record in (register.get("gauges") or {}).items():
        for check in (record or {}).get("checks") or ():
            if isinstance(check, Mapping) and check.get("session") == session_id:
                name = "".join(ch if ch.isprintable() else "?" for ch in str(gauge))
                return f"gauge register: {name}, {check.get('result')} on {check.get('date')}"
    return "gauge register: this check is not filed (a finished session files itself)"
