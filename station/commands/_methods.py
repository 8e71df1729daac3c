"""``station analyze --procedure gauge_check | joint_troubleshooting | gain_schedule``: the
analyses of the rest of the report's method, on a CSV table or a session file."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from station.commands._args import parse_number
from station.errors import StationError
from station.plain import plain


def _gauge_check(args: argparse.Namespace, source: Any, path: Path) -> tuple[Any, dict, list]:
    from station.analysis.gauge_check import gauge_check
    from station.session.method_reports import gauge_check_from_session

    reference = parse_number(args.reference, "--reference")
    tolerance = parse_number(args.tolerance, "--tolerance")
    resolution = parse_number(args.resolution, "--resolution")
    if tolerance is not None and not tolerance > 0:
        raise StationError(f"--tolerance {args.tolerance!r} must be greater than 0.")
    if hasattr(source, "session"):
        study = gauge_check_from_session(source.session)
        if reference is not None or tolerance is not None or resolution is not None:
            study = gauge_check(
                source.channels[next(iter(source.channels))],
                study.reference if reference is None else reference,
                study.tolerance if tolerance is None else tolerance,
                resolution=study.resolution if resolution is None else resolution,
                unit=study.unit,
            )
    else:
        if reference is None or tolerance is None:
            raise StationError(
                "--procedure gauge_check on a CSV needs --reference X_M (the reference's size) "
                "and --tolerance T (the tolerance the gauge will judge)."
            )
        channels = source.channels
        if len(channels) != 1:
            raise StationError(
                f"{path}: a gauge-check table has one column of readings; it has "
                f"{', '.join(channels)}."
            )
        values = next(iter(channels.values()))
        study = gauge_check(values, reference, tolerance, resolution=resolution, unit=args.unit)
    document = {"procedure": "gauge_check", "gauge_check": study.as_json()}
    return study, document, study.lines()


def run_method(args: argparse.Namespace, source: Any, procedure: str, path: Path) -> int:
    """Analyse ``source`` (a ``TableSource`` or a ``SessionSource``) as ``procedure`` and print
    the JSON document or the text report; the exit code."""
    from station.session import method_reports as reports

    if procedure != "gauge_check" and (args.reference is not None or args.tolerance is not None):
        raise StationError(
            f"--reference and --tolerance belong to gauge_check, not {procedure}; "
            "drop them or choose --procedure gauge_check."
        )
    is_session = hasattr(source, "session")
    if procedure == "gauge_check":
        result, document, lines = _gauge_check(args, source, path)
        title = f"GAUGE CHECK REPORT ON {plain(path.name)}"
    elif procedure == "joint_troubleshooting":
        if is_session:
            result = reports.joints_from_session(source.session)
        else:
            from station.analysis.joints import analyze_joints

            joints, readings, levers = reports.table_joint_inputs(source.table)
            result = analyze_joints(joints, readings, lever_arms=levers)
        document = {"procedure": procedure, **result.as_json()}
        lines = reports.joints_lines(result, args.unit or getattr(source.config, "unit", ""))
        title = f"PER-JOINT TROUBLESHOOTING REPORT ON {plain(path.name)}"
    else:
        if is_session:
            result = reports.gain_schedule_from_session(source.session)
        else:
            from station.analysis.gain_schedule import fit_schedule
            from station.session.tables import require_columns

            table = source.table
            q = require_columns(table, ("q",), "a gains table")["q"]
            gains = {n: v for n, v in table.channels.items() if n.lower() != "q"}
            if not gains:
                raise StationError(f"{path}: no gain columns beside q; add one per gain.")
            result = fit_schedule(q, gains)
        document = reports.gain_schedule_document(result, path.name)
        lines = reports.gain_schedule_lines(result)
        title = f"GAIN SCHEDULE REPORT ON {plain(path.name)}"
    if args.json:
        print(json.dumps(document, indent=2, allow_nan=False))
    else:
        notes = [plain(note) for note in getattr(source, "notes", ())]
        print("\n".join([title, *notes, "", *lines]))
    if args.fail_if_incapable and procedure == "gauge_check" and result.capable is not True:
        print(f"station: the gauge check failed ({result.verdict})", file=sys.stderr)
        return 1
    return 0
