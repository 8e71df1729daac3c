"""``station procedures``: the procedures installed, with title, version and report section."""

from __future__ import annotations

import argparse


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Register ``station procedures``."""
    parser = subparsers.add_parser(
        "procedures",
        help="list the installed procedures",
        description=(
            "List the procedures station knows: the built-in ones and those in the folders named "
            "by --procedures or STATION_PROCEDURES (os.pathsep-separated). A site's procedure "
            "with the same id as a built-in one wins, and the listing says so. Exit 1 when a "
            "procedure file fails to load (its error is printed)."
        ),
    )
    parser.add_argument(
        "--procedures",
        metavar="DIR",
        action="append",
        default=[],
        help="a folder of the site's own procedures (repeatable)",
    )
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Print one line per procedure, then the notes; 1 when a file failed to load."""
    import station.methods  # noqa: F401 - procedure files name the methods
    from station.procedures import discover_procedures

    catalog = discover_procedures(args.procedures)
    rows = [("ID", "TITLE", "VERSION", "SECTION", "ORIGIN", "FILE")]
    for procedure in catalog.procedures:
        rows.append(
            (
                procedure.id,
                procedure.title,
                procedure.version,
                f"§{procedure.report_section}",
                catalog.origin(procedure.id),
                str(procedure.path),
            )
        )
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]) - 1)]
    for row in rows:
        cells = [cell.ljust(width) for cell, width in zip(row, widths, strict=False)]
        print("  ".join([*cells, row[-1]]))
    for note in catalog.notes:
        print(f"note: {note}")
    return 1 if catalog.errors else 0
