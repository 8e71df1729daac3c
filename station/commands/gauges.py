"""``station gauges``: the gauge register (which indicator was checked when, and its result)."""

from __future__ import annotations

import argparse
import datetime as dt
import json
from pathlib import Path

from station.errors import StationError

DESCRIPTION = """\
The gauge register: per gauge id or serial, the Type-1 gauge checks recorded
(date, result, Cg, Cgk, bias) and the calibration due date. It lives in
$XDG_DATA_HOME/station/gauges.json (~/.local/share/station/gauges.json), or
the file STATION_GAUGES names.

  station gauges list [--json]           every gauge and its status today
  station gauges status ID... [--json]   passed / failed / overdue / none
  station gauges record SESSION.jsonl    file a finished gauge_check session

A check is overdue when the calibration due date has passed or the check is
older than 183 days (the report's "every four to six months").

exit codes: 0 done (status: every gauge passed); 1 status: a gauge is not
covered by a passed, current check; 2 bad input
"""


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Register ``station gauges`` and its actions."""
    parser = subparsers.add_parser(
        "gauges",
        help="the gauge register: gauge checks per gauge id, calibration due dates",
        description=DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    actions = parser.add_subparsers(dest="gauges_command", metavar="ACTION", required=True)
    listing = actions.add_parser("list", help="every gauge in the register and its status")
    listing.add_argument("--json", action="store_true", help="print one JSON document")
    listing.set_defaults(func=run_list)
    status = actions.add_parser("status", help="the status of the gauges named")
    status.add_argument("gauges", nargs="+", metavar="ID", help="gauge id or serial")
    status.add_argument("--json", action="store_true", help="print one JSON document")
    status.set_defaults(func=run_status)
    record = actions.add_parser("record", help="file a finished gauge_check session")
    record.add_argument("session", metavar="SESSION.jsonl", help="a gauge_check session file")
    record.set_defaults(func=run_record)
    for action in (listing, status, record):
        action.add_argument("--register", metavar="FILE", help="another register file")


def _register(args: argparse.Namespace) -> Path:
    from station.session.gauge_register import register_path

    return Path(args.register) if args.register else register_path()


def _print(statuses: list, as_json: bool, path: Path) -> None:
    if as_json:
        document = {"register": str(path), "gauges": [s.as_json() for s in statuses]}
        print(json.dumps(document, indent=2))
        return
    print(f"gauge register: {path}")
    if not statuses:
        print("no gauges recorded yet: run the gauge_check procedure, then `station gauges record`")
    for status in statuses:
        print(status.sentence())


def run_list(args: argparse.Namespace) -> int:
    """Print every gauge of the register with its status today."""
    from station.session.gauge_register import load_register, register_rows

    path = _register(args)
    _print(register_rows(load_register(path), dt.date.today()), args.json, path)
    return 0


def run_status(args: argparse.Namespace) -> int:
    """Print the named gauges' status; exit 1 unless every one is covered."""
    from station.session.gauge_register import all_covered, gauge_status, load_register

    path = _register(args)
    register = load_register(path)
    statuses = [gauge_status(register, gauge, dt.date.today()) for gauge in args.gauges]
    _print(statuses, args.json, path)
    return 0 if all_covered({s.gauge: s for s in statuses}) else 1


def run_record(args: argparse.Namespace) -> int:
    """Analyse a gauge_check session and file its study under the gauge id typed in it."""
    from station.session.method_reports import gauge_check_from_session, record_gauge_check
    from station.session.model import load_session
    from station.verdicts import session_analysis

    session = load_session(Path(args.session), recover=False)
    kind = session_analysis(session)
    if kind != "gauge_check":
        raise StationError(
            f"{args.session} is a {kind} session, not a gauge check; record gauge_check sessions."
        )
    if not session.finished:
        raise StationError(f"{args.session} is not finished; finish it before recording it.")
    study = gauge_check_from_session(session)
    path = _register(args)
    entry = record_gauge_check(session, study, register=path)
    print(
        f"recorded in {path}: gauge check {entry['result']} on {entry['date']} "
        f"(Cg {study.cg if study.cg is None else round(study.cg, 2)}, "
        f"Cgk {study.cgk if study.cgk is None else round(study.cgk, 2)})"
    )
    return 0
