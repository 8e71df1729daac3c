"""The calibration methods: the station's own, listed in :data:`BUILT_IN`, then a site's, offered
by its installed packages under the ``station.methods`` entry-point group
(:mod:`station.extensions`).

Importing this module tells the procedure loader (:mod:`station.procedures`, below) what each
method needs of a procedure file, so that ``analysis = NAME`` is checked when a file loads.
"""

from __future__ import annotations

from functools import lru_cache

from station.errors import StationError
from station.extensions import METHODS, SiteExtensions, site_extensions
from station.methods.contract import Method
from station.methods.gage_rr import METHOD as GAGE_RR
from station.methods.gain_schedule import METHOD as GAIN_SCHEDULE
from station.methods.gauge_check import METHOD as GAUGE_CHECK
from station.methods.gauge_linearity import METHOD as GAUGE_LINEARITY
from station.methods.joint_troubleshooting import METHOD as JOINT_TROUBLESHOOTING
from station.methods.linearity import METHOD as LINEARITY
from station.methods.pose_characteristics import METHOD as POSE_CHARACTERISTICS
from station.methods.positioning import METHOD as POSITIONING
from station.methods.relative_accuracy import METHOD as RELATIVE_ACCURACY
from station.methods.repeatability import METHOD as REPEATABILITY
from station.methods.stabilisation import METHOD as STABILISATION
from station.procedures import AnalysisNeeds, discover_procedures, use_methods
from station.session.model import Session

BUILT_IN: tuple[Method, ...] = (
    REPEATABILITY,
    RELATIVE_ACCURACY,
    LINEARITY,
    GAUGE_CHECK,
    GAUGE_LINEARITY,
    GAGE_RR,
    JOINT_TROUBLESHOOTING,
    GAIN_SCHEDULE,
    POSITIONING,
    POSE_CHARACTERISTICS,
    STABILISATION,
)
"""The station's own methods; the first is the default (a procedure that declares none and
whose steps imply none)."""


def methods() -> dict[str, Method]:
    """Every method by name: the built-in ones, then a site's (which cannot replace one)."""
    return _methods(site_extensions(METHODS))


@lru_cache(maxsize=4)
def _methods(site: SiteExtensions) -> dict[str, Method]:
    found = {method.name: method for method in BUILT_IN}
    for method in site.loaded:
        if isinstance(method, Method) and method.name not in found:
            found[method.name] = method
    return found


def method_of(name: str) -> Method:
    """The method called ``name``; StationError naming the known ones."""
    known = methods()
    try:
        return known[name]
    except KeyError:
        failed = site_extensions(METHODS).failed
        problems = f" ({'; '.join(failed)})" if failed else ""
        raise StationError(
            f"no method {name!r}; known methods: {', '.join(known)}{problems}"
        ) from None


def names() -> tuple[str, ...]:
    """The methods' names, the default first."""
    return tuple(methods())


def _needs(name: str) -> AnalysisNeeds | None:
    method = methods().get(name)
    return None if method is None else method.needs


use_methods(_needs, names)


def session_method(session: Session) -> str:
    """The method that judges a session: the one its header records for its procedure; else
    that of the same procedure file (id and sha256) where this machine has it; else the first
    method that recognises what the session holds (files written before the header recorded
    it), else the default."""
    recorded = session.header["procedure"]
    known = methods()
    if recorded.get("analysis") in known:
        return str(recorded["analysis"])
    try:
        catalog = discover_procedures()
        procedure = next(
            (
                p
                for p in catalog.procedures
                if p.id == recorded.get("id") and p.sha256 == recorded.get("sha256")
            ),
            None,
        )
    except StationError:  # a STATION_PROCEDURES folder that is gone: judge by the content
        procedure = None
    if procedure is not None:
        return procedure.analysis
    for method in known.values():
        if method.recognises(session):
            return method.name
    return BUILT_IN[0].name
