"""``station gauges``: the gauge register (which indicator was checked when, and its result)."""

from __future__ import annotations

import argparse
import datetime as dt
import json
from pathlib import Path

from station.errors import StationError

DESCRIPTION = """\
The gauge register: per gauge id or serial, the Type-1 gauge checks recorded
(date, result, Cg, Cgk, bias), the other studies of the gauge (a linearity and
bias study over its travel, a Gage R&R) and the calibration due date. It lives in
$XDG_DATA_HOME/station/gauges.json (~/.local/share/station/gauges.json), or
the file STATION_GAUGES names.

  station gauges list [--json]           every gauge and its status today
  station gauges status ID... [--json]   passed / failed / overdue / none
  station gauges record SESSION.jsonl    file a finished gauge_check,
                                         gauge_linearity or gage_rr session
  station gauges certificate ID --U U --k K [--date D] [--number N]
                                         record the gauge's calibration
                                         certificate: U at k is a line of
                                         every later session's budget

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
    record = actions.add_parser(
        "record", help="file a finished gauge study (gauge_check, gauge_linearity, gage_rr) session"
    )
    record.add_argument(
        "session",
        metavar="SESSION.jsonl",
        help="a gauge_check, gauge_linearity or gage_rr session file",
    )
    record.set_defaults(func=run_record)
    certificate = actions.add_parser(
        "certificate",
        help="record a gauge's calibration certificate (U at k) for the measurement budget",
    )
    certificate.add_argument("gauge", metavar="ID", help="gauge id or serial")
    certificate.add_argument(
        "--U", dest="expanded", required=True, metavar="U", help="the certificate's expanded U"
    )
    certificate.add_argument("--k", required=True, metavar="K", help="its coverage factor")
    certificate.add_argument("--date", metavar="YYYY-MM-DD", help="the certificate's date")
    certificate.add_argument("--number", metavar="N", help="the certificate's number")
    certificate.set_defaults(func=run_certificate)
    for action in (listing, status, record, certificate):
        action.add_argument("--register", metavar="FILE", help="another register file")


def _register(args: argparse.Namespace) -> Path:
    from station.session.gauge_register import register_path

    return Path(args.register) if args.register else register_path()


def _print(statuses: list, as_json: bool, path: Path, register: dict) -> None:
    from station.session.gauge_register import latest_studies, study_sentence

    records = register.get("gauges") or {}
    if as_json:
        gauges = [
            {**s.as_json(), "studies": latest_studies(records.get(s.gauge))} for s in statuses
        ]
        print(json.dumps({"register": str(path), "gauges": gauges}, indent=2))
        return
    print(f"gauge register: {path}")
    if not statuses:
        print("no gauges recorded yet: run the gauge_check procedure, then `station gauges record`")
    for status in statuses:
        print(status.sentence())
        for method, entry in latest_studies(records.get(status.gauge)).items():
            print(f"  {study_sentence(method, entry)}")


def run_list(args: argparse.Namespace) -> int:
    """Print every gauge of the register with its status today."""
    from station.session.gauge_register import load_register, register_rows

    path = _register(args)
    register = load_register(path)
    _print(register_rows(register, dt.date.today()), args.json, path, register)
    return 0


def run_status(args: argparse.Namespace) -> int:
    """Print the named gauges' status; exit 1 unless every one is covered."""
    from station.session.gauge_register import all_covered, gauge_status, load_register

    path = _register(args)
    register = load_register(path)
    statuses = [gauge_status(register, gauge, dt.date.today()) for gauge in args.gauges]
    _print(statuses, args.json, path, register)
    return 0 if all_covered({s.gauge: s for s in statuses}) else 1


def run_record(args: argparse.Namespace) -> int:
    """File a finished gauge study session (its method says how) in the gauge register."""
    from station.methods import method_of, methods, session_method
    from station.session.model import load_session

    session = load_session(Path(args.session), recover=False)
    method = method_of(session_method(session))
    if not method.files_in_register:
        studies = ", ".join(m.name for m in methods().values() if m.files_in_register)
        raise StationError(
            f"{args.session} is a {method.name} session, which files nothing in the gauge "
            f"register; record a gauge study ({studies}) session."
        )
    if not session.finished:
        raise StationError(f"{args.session} is not finished; finish it before recording it.")
    for sentence in method.file_in_register(Path(args.session), _register(args)):
        print(sentence)
    return 0


def run_certificate(args: argparse.Namespace) -> int:
    """Record a gauge's calibration certificate (U at k) in the register."""
    from station.commands._args import parse_number
    from station.plain import plain
    from station.session.gauge_register import record_certificate

    expanded = parse_number(args.expanded, "--U")
    k = parse_number(args.k, "--k")
    if expanded is None or k is None:
        raise StationError("--U and --k each need a number.")
    path = _register(args)
    entry = record_certificate(
        path, args.gauge, expanded=expanded, k=k, date=args.date, certificate_id=args.number
    )
    print(
        f"gauge {plain(args.gauge)}: certificate U = {entry['U']:g} at k = {entry['k']:g} "
        f"recorded in {path}; sessions begun from now carry u = U/k = "
        f"{entry['U'] / entry['k']:.4g} in their measurement budget"
    )
    return 0
