"""What every method's wide CSV export shares: the ``#`` lines naming the session and its
rejected cycles, and numbers written with every digit the session holds.

A wide table is the table ``station analyze --procedure NAME`` reads back for the method, with
exactly the readings its analysis takes (:meth:`station.methods.Method.write_wide`); the tidy
layout, a row per reading, is :func:`station.session.export.export_csv`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from station.session.export import one_line
from station.session.model import Session

if TYPE_CHECKING:
    from _typeshed import SupportsWrite


def number(value: float) -> str:
    """``value`` as a CSV cell: repr keeps every digit the session holds (no rounding)."""
    return repr(float(value))


def export_comments(session: Session, out: SupportsWrite[str]) -> None:
    """``#`` lines naming the session and its rejected cycles (readers skip them; ``station
    analyze`` lists those cycles as excluded)."""
    name, procedure, unit = (
        one_line(v) for v in (session.path.name, session.procedure_id, session.unit)
    )
    out.write(
        f"# station export of {name}: procedure {procedure}, unit {unit}, "
        f"last line hash {session.last_hash}\n"
    )
    for cycle, reason in sorted(session.rejected.items()):
        out.write(f"# rejected cycle {cycle} (left out): {one_line(reason)}\n")
