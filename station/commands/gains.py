"""``station gains fit FILE.csv``: the gain schedule of the report's §4.3, fitted and exported."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

from station.commands._output import write_output_file
from station.errors import StationError
from station.plain import plain

if TYPE_CHECKING:
    from station.analysis.gain_schedule import GainFit, GainSchedule

POSITION_COLUMN = "q"
PLOT_WIDTH = 72
PLOT_HEIGHT = 14

DESCRIPTION = """\
Fit each PID gain as a polynomial of the joint position, K(q) = a0 + a1 q + ...
+ an q^n (the report's section 4.3), from gains tuned at a few positions along
the path. FILE is a CSV table: a column q (the joint position) and one column
per gain (e.g. kp, ki, kd), one row per tuned position; '#' lines are comments.

The fit is least squares in the Chebyshev basis on q scaled to [-1, 1] (well
conditioned at any order); the plain coefficients a0..an on q are computed for
the export only. --order auto (the default) chooses the order by AICc, or by
the leave-one-out error with --criterion loo (one-standard-error rule); both
are printed for every order. A warning is printed when the order approaches the
number of positions or the curve swings beyond the tuned gains between them
(Runge oscillation).

exit codes:
  0  fitted (warnings, if any, are printed)
  2  bad input: missing file, no q column, repeated positions, an order the
     positions cannot fix
"""


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Register ``station gains`` and its ``fit`` sub-command."""
    parser = subparsers.add_parser(
        "gains",
        help="gain schedule (report 4.3): fit PID gains as polynomials of joint position",
        description="Gain schedules of the report's Part IV. Run `station gains fit -h`.",
    )
    actions = parser.add_subparsers(dest="gains_command", metavar="ACTION", required=True)
    fit = actions.add_parser(
        "fit",
        help="fit K(q) per gain from a CSV of tuned gains",
        description=DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    fit.add_argument("file", metavar="FILE.csv", help="CSV with a column q and one per gain")
    fit.add_argument(
        "--order",
        default="auto",
        metavar="N|auto",
        help="polynomial order, or auto (default) to choose it from the data",
    )
    fit.add_argument(
        "--criterion",
        choices=("aicc", "loo"),
        default="aicc",
        help="how auto chooses: aicc (default) or loo (leave-one-out, one-SE rule)",
    )
    fit.add_argument("--json", action="store_true", help="print one JSON document")
    fit.add_argument(
        "--c",
        dest="c_out",
        metavar="OUT.h",
        help="also write the coefficients as a C header (arrays a0..an per gain)",
    )
    fit.add_argument("--no-plot", action="store_true", help="text report without the plots")
    fit.set_defaults(func=run)


def parse_order(text: str) -> int | str:
    """``auto`` or a whole number 0 or more, as ``--order`` takes it."""
    if text.strip().lower() == "auto":
        return "auto"
    try:
        order = int(text)
    except ValueError:
        raise StationError(f"--order {text!r} is not a whole number or auto.") from None
    if order < 0:
        raise StationError(f"--order must be 0 or more, not {order}.")
    return order


def read_gains(path: Path) -> tuple[Any, dict[str, Any]]:
    """The positions (column q) and the gain columns of a gains CSV."""
    from station.session.tables import read_table, require_columns

    table = read_table(path)
    position = require_columns(table, (POSITION_COLUMN,), "a gains table")[POSITION_COLUMN]
    gains = {
        name: values for name, values in table.channels.items() if name.lower() != POSITION_COLUMN
    }
    if not gains:
        raise StationError(
            f"{path}: no gain columns beside q; add one column per gain (e.g. q,kp,ki,kd)."
        )
    return position, gains


def gains_document(schedule: GainSchedule, source: str) -> dict[str, Any]:
    """The JSON document of ``station gains fit --json``."""
    return {"source": source, **schedule.as_json()}


def _number(value: float | None, digits: int = 6) -> str:
    return "n/a" if value is None else f"{value:.{digits}g}"


def text_plot(fit: GainFit, width: int = PLOT_WIDTH, height: int = PLOT_HEIGHT) -> list[str]:
    """K(q) drawn between and beyond the tuned points (``o``): where a high order oscillates
    shows between the positions, not at them. Plain text, no colour."""
    import numpy as np
    import plotext as plt

    low, high = fit.domain
    grid = np.linspace(low, high, 4 * width)
    plt.clear_figure()
    plt.plotsize(width, height)
    plt.theme("clear")
    plt.plot(grid.tolist(), fit.evaluate(grid).tolist(), marker="dot", label="fit")
    plt.scatter(list(fit.positions), list(fit.gains), marker="o", label="tuned")
    plt.title(f"{fit.name}(q), order {fit.order}")
    plt.xlabel("q")
    text = plt.uncolorize(plt.build())
    plt.clear_figure()
    return [line.rstrip() for line in text.splitlines()]


def format_fit(fit: GainFit, *, plot: bool = True) -> list[str]:
    """One gain's report: order and how chosen, the scores per order, coefficients, residuals,
    warnings and the plot."""
    name = plain(fit.name)
    lines = [
        f"GAIN {name}: order {fit.order} ({fit.chosen_by}), "
        f"leave-one-out RMSE {_number(fit.loo_rmse)}, RMSE {_number(fit.rmse)}",
    ]
    if len(fit.scores) > 1:
        lines.append("  order   LOO RMSE       AICc")
        for score in fit.scores:
            mark = "  <" if score.order == fit.order else ""
            aicc = "n/a" if score.aicc is None else f"{score.aicc:.2f}"
            lines.append(f"  {score.order:5d}   {_number(score.loo_rmse):<12} {aicc:>8}{mark}")
    lines.append(f"  K(q) = a0 + a1 q + ... on q in [{fit.domain[0]:g}, {fit.domain[1]:g}]:")
    lines.extend(f"    a{i} = {c:+.10e}" for i, c in enumerate(fit.coefficients))
    lines.append("  position       tuned      fitted    residual")
    lines.extend(
        f"  {q:>8g}  {k:>10.6g}  {f:>10.6g}  {r:>+10.3g}"
        for q, k, f, r in zip(fit.positions, fit.gains, fit.fitted, fit.residuals, strict=True)
    )
    lines.extend(f"  WARNING: {warning}" for warning in fit.warnings)
    if plot:
        lines.extend(text_plot(fit))
    return lines


def write_c_header(text: str, target: Path, source: Path) -> None:
    """Write ``text`` to ``target`` in full or not at all (the commands' one output writer:
    never through a symlink, never over the input file; an existing header is replaced)."""
    write_output_file(
        target, lambda handle: handle.write(text), force=True, source=source, mode=0o644
    )


def run(args: argparse.Namespace) -> int:
    """Fit the schedule of FILE and print it (text or JSON); write the C header with --c."""
    from station.analysis.gain_schedule import c_header, fit_schedule

    path = Path(args.file)
    order = parse_order(args.order)
    positions, gains = read_gains(path)
    schedule = fit_schedule(positions, gains, order, criterion=args.criterion)  # type: ignore[arg-type]
    if args.c_out:
        write_c_header(c_header(schedule, source=path.name), Path(args.c_out), path)
    if args.json:
        print(json.dumps(gains_document(schedule, path.name), indent=2, allow_nan=False))
        return 0
    print(f"GAIN SCHEDULE FROM {plain(path.name)}: {len(schedule.positions)} positions")
    for fit in schedule.fits.values():
        print()
        print("\n".join(format_fit(fit, plot=not args.no_plot)))
    if args.c_out:
        print(f"\nC header written to {plain(str(args.c_out))}")
    return 0
