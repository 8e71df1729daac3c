"""``station budget FILE.toml``: a GUM uncertainty budget, and values judged against limits."""

from __future__ import annotations

import argparse
import json
import math

from station.commands._args import limit_value, parse_number
from station.errors import StationError

BUDGET_FILE_LIMIT = 1 << 20
"""A budget file is a few dozen lines; a mebibyte is surely the wrong file."""


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Register ``station budget``."""
    parser = subparsers.add_parser(
        "budget",
        help="evaluate a GUM uncertainty budget; judge values against limits (ISO 14253-1)",
        description=(
            "Evaluate the measurement-uncertainty budget in FILE (TOML: one [[input]] table per "
            "contribution, each with a name and one of u, half_width + distribution "
            "(rectangular, triangular, arcsine, normal), expanded + k, or readings = [...]; "
            "optional sensitivity and dof; a top-level unit, k or confidence). Prints each "
            "contribution and its share, the combined standard uncertainty u_c, the effective "
            "degrees of freedom (Welch-Satterthwaite) and U = k u_c: k as given, or Student's t "
            "at nu_eff truncated to a whole number for a confidence (GUM G.4), else 2. With "
            "limits, the acceptance zone, and each --value judged: PASS inside the limits "
            "shrunk by U, FAIL outside the limits widened by U, INDETERMINATE between (--rule "
            "simple: no guard band), with its probability of conformance. Exit 0 when every "
            "value passes (or none is given), 1 when one does not, 2 for a bad file or option."
        ),
    )
    parser.add_argument("file", metavar="FILE", help="the budget file (.toml)")
    coverage = parser.add_mutually_exclusive_group()
    coverage.add_argument("--k", metavar="K", help="coverage factor (overrides the file's)")
    coverage.add_argument(
        "--confidence",
        metavar="C",
        help="coverage probability, e.g. 0.95: k from Student's t at nu_eff (overrides the file's)",
    )
    parser.add_argument("--lsl", metavar="A", help="lower specification limit")
    parser.add_argument("--usl", metavar="B", help="upper specification limit")
    parser.add_argument(
        "--value",
        metavar="Y",
        action="append",
        default=[],
        help="a measured value to judge against the limits (repeat for more)",
    )
    parser.add_argument(
        "--rule",
        choices=("guarded", "simple"),
        default="guarded",
        help="decision rule: guarded acceptance by U (default) or simple (no guard band)",
    )
    parser.add_argument("--json", action="store_true", help="print one JSON document")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Print the budget and the decisions; 0 when every value passes, 1 when one does not."""
    from station.analysis.budget_file import parse_budget
    from station.analysis.uncertainty import (
        Outcome,
        Rule,
        acceptance_zone,
        check_confidence,
        check_coverage,
        check_limits,
        decide,
        evaluate,
    )
    from station.inputfiles import read_input_bytes
    from station.plain import plain

    k = None if args.k is None else check_coverage(parse_number(args.k, "--k"), "--k")
    confidence = None
    if args.confidence is not None:
        confidence = check_confidence(parse_number(args.confidence, "--confidence"), "--confidence")
    lsl = limit_value(args.lsl, "--lsl", "lower")
    usl = limit_value(args.usl, "--usl", "upper")
    values = [parse_number(text, "--value") for text in args.value]
    if any(value is None for value in values):
        raise StationError("--value is empty; give a number.")
    limited = lsl is not None or usl is not None
    if values and not limited:
        raise StationError("--value needs limits to be judged against; give --lsl, --usl or both.")
    if limited:
        check_limits(lsl, usl)

    data = read_input_bytes(args.file, "budget file", BUDGET_FILE_LIMIT)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise StationError(
            f"{plain(args.file)} is not UTF-8 text; give a TOML budget file."
        ) from None
    read = parse_budget(text, plain(args.file))
    if k is None and confidence is None:
        k, confidence = read.k, read.confidence
    result = evaluate(read.budget, k=k, confidence=confidence)
    rule = Rule(args.rule)
    zone = acceptance_zone(lsl, usl, result.U, rule) if limited else None
    decisions = [decide(value, lsl, usl, result, rule) for value in values]  # type: ignore[arg-type]

    if args.json:
        document = {
            **result.as_json(),
            "rule": rule.value,
            "limits": [lsl, usl] if limited else None,
            "acceptance_zone": list(zone) if zone else None,
            "decisions": [
                {
                    "value": decision.value,
                    "verdict": decision.verdict.value,
                    "p_conformance": decision.p_conformance,
                }
                for decision in decisions
            ],
        }
        print(json.dumps(document, indent=2, allow_nan=False))
    else:
        _print_text(plain(args.file), result, rule, lsl, usl, zone, decisions, limited)
    return 0 if all(d.verdict is Outcome.PASS for d in decisions) else 1


def _print_text(source, result, rule, lsl, usl, zone, decisions, limited) -> None:  # noqa: ANN001
    from station.plain import plain

    unit = f" {plain(result.unit)}" if result.unit else ""
    print(f"budget: {source}")
    width = max(len("input"), *(len(plain(line.name)) for line in result.lines))
    print(f"{'input':<{width}}  {'u':>11}  {'c':>9}  {'|c|·u':>11}  {'dof':>6}  {'share':>6}")
    for line in result.lines:
        print(
            f"{plain(line.name):<{width}}  {line.u:>11.4g}  {line.sensitivity:>9.4g}  "
            f"{line.ui:>11.4g}  {_dof(line.dof):>6}  {100 * line.share:>5.1f}%"
        )
    print(f"u_c = {result.u_c:.4g}{unit}, nu_eff = {_dof(result.nu_eff)}")
    if result.confidence is not None:
        how = (
            f"at {100 * result.confidence:g}% on {_dof(math.floor(result.nu_eff))} degrees of "
            "freedom"
            if math.isfinite(result.nu_eff)
            else f"at {100 * result.confidence:g}% (normal)"
        )
        print(f"k = {result.k:.4g} ({how}), U = {result.U:.4g}{unit}")
    else:
        print(f"k = {result.k:.4g}, U = {result.U:.4g}{unit}")
    if not limited:
        return
    shown = f"[{_limit(lsl)}, {_limit(usl)}]"
    if zone is None:
        print(
            f"limits {shown}: no value can pass by {rule.value} acceptance "
            f"(the guard bands of U = {result.U:.4g} overlap)"
        )
    else:
        print(
            f"limits {shown}, acceptance zone ({rule.value}): "
            f"[{_limit(zone[0])}, {_limit(zone[1])}]"
        )
    for decision in decisions:
        print(
            f"{decision.value:g}{unit}: {decision.verdict.value} "
            f"(probability of conformance {decision.p_conformance:.4f})"
        )


def _dof(value: float) -> str:
    return "inf" if math.isinf(value) else f"{value:.4g}"


def _limit(value: float | None) -> str:
    return "none" if value is None else f"{value:.6g}"
