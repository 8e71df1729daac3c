"""A session as CSV: tidy (a row per cycle and channel, rejected ones marked) or wide, the
table ``station analyze --procedure NAME`` reads back for the session's method, with exactly
the readings its analysis takes (:meth:`station.methods.Method.write_wide`: linearity's
``stroke,s,h,v``, relative accuracy's ``cycle,placement,x,y,z[,px,py,pz]``, a gauge linearity
study's ``cycle,reference,value``; by default ``cycle,t`` and one column per channel).

``#`` lines of a wide table name the session, its last hash and each rejected cycle with its
reason (``station analyze`` lists those cycles as excluded).
"""

from __future__ import annotations

from typing import TextIO

from station.methods import method_of, session_method
from station.plain import PlainStream
from station.session.export import export_csv
from station.session.model import Session

LAYOUTS = ("tidy", "wide")


def default_layout(session: Session) -> str:
    """The layout ``station export`` writes unless told: the session's method's."""
    return method_of(session_method(session)).export_layout


def export_table(session: Session, out: TextIO, layout: str = "tidy") -> int:
    """Write ``session`` as CSV in ``layout`` (``tidy`` or ``wide``, see the module); return
    the data rows. Control characters from outside (a channel name, a unit, a reject reason)
    are written visible, whichever method writes the rows."""
    if layout == "tidy":
        return export_csv(session, out)
    if layout != "wide":
        raise ValueError(f"unknown CSV layout {layout!r}")
    return method_of(session_method(session)).write_wide(session, PlainStream(out))
