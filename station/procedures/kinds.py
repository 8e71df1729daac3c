"""What a procedure file is validated against: what each step kind may hold (its
:class:`StepSchema`) and what each calibration method needs of a procedure
(:class:`AnalysisNeeds`).

The step kinds' schemas are data here (the engine's handlers register theirs too, so a site's
step kind is validated all the same); the methods live above this package
(:mod:`station.methods`), which tells the loader their needs through :func:`use_methods`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from station.extensions import STEP_KINDS, site_extensions
from station.procedures.model import ID_PATTERN


@dataclass(frozen=True)
class StepSchema:
    """What a step kind may hold in a procedure file, beyond ``id``, ``kind``, ``title`` and
    ``text``: its own ``keys``, and which shared parts apply (so the loader validates a kind it
    has never seen the code of)."""

    keys: tuple[str, ...] = ()
    channels: bool = False
    """``channels`` (default: all the procedure's)."""
    counts: bool = False
    """``min``/``target`` and a ``prompt`` (cycle or stroke counts)."""
    fields: bool = False
    """``fields`` typed by the operator."""
    direction: bool = False
    """``direction_channel``: the channel tracking the position along a stream."""
    block: bool = False
    """A block of inner ``steps`` repeated ``target`` times (no nesting)."""
    zero_window: bool = False
    """``readings``, ``settle`` and ``still``: a zero taken as the mean of several readings."""
    parts: bool = False
    """One reading of each of ``target`` numbered parts, in a random order drawn afresh each
    time the step comes (a Gage R&R appraiser's trial)."""

    @property
    def allowed(self) -> tuple[str, ...]:
        """Every key a step of this kind may have beyond the common ones."""
        shared = (
            (("channels",) if self.channels else ())
            + (("min", "target", "prompt") if self.counts else ())
            + (("fields",) if self.fields else ())
            + (("direction_channel",) if self.direction else ())
            + (("label", "min", "target", "prompt", "steps") if self.block else ())
            + (("readings", "settle", "still") if self.zero_window else ())
        )
        return tuple(dict.fromkeys(shared + self.keys))


_STEP_SCHEMAS: dict[str, StepSchema] = {
    "check": StepSchema(),
    "input": StepSchema(fields=True),
    "zero": StepSchema(channels=True, zero_window=True),
    "capture": StepSchema(channels=True),
    "cycles": StepSchema(channels=True, counts=True),
    "parts": StepSchema(channels=True, counts=True, parts=True),
    "stroke": StepSchema(channels=True, counts=True, direction=True),
    "repeat": StepSchema(block=True),
}


@dataclass(frozen=True)
class AnalysisNeeds:
    """What a procedure must hold for a method: a step of a kind with ``facet`` (e.g.
    ``direction`` for streamed strokes, ``block`` for placements), inside a repeat block when
    ``facet_in_block``; these ``channels``; and input steps with the number fields ``numbers``
    plus ``more_numbers`` others (a gain schedule's position ``q`` and one field per gain).
    ``facet_words`` and ``numbers_words`` say what is missing when a file lacks it."""

    facet: str | None = None
    facet_words: str = ""
    channels: tuple[str, ...] = ()
    facet_in_block: bool = False
    numbers: tuple[str, ...] = ()
    more_numbers: int = 0
    numbers_words: str = ""
    limits: bool = True
    """Whether the kind's verdict judges the session's spec limits (a gauge check judges
    against its reference and tolerance, a gain schedule judges nothing): a set-up screen
    asks for limits only when it does."""
    implied: bool = False
    """A procedure that declares no ``analysis`` is judged by the first method (in the
    catalog's order) whose needs are ``implied`` and that its steps and channels meet (a
    stroke step: linearity; a repeat block over x, y, z: relative accuracy)."""


_NEEDS: Callable[[str], AnalysisNeeds | None] | None = None
_NAMES: Callable[[], tuple[str, ...]] | None = None


def use_methods(
    needs: Callable[[str], AnalysisNeeds | None], names: Callable[[], tuple[str, ...]]
) -> None:
    """Let procedure files declare the methods ``names()`` lists, each holding what
    ``needs(name)`` says (None: no such method). Called once by :mod:`station.methods`, which
    sits above this package: the methods are known here only through it."""
    global _NEEDS, _NAMES
    _NEEDS, _NAMES = needs, names


def _methods() -> tuple[Callable[[str], AnalysisNeeds | None], Callable[[], tuple[str, ...]]]:
    if _NEEDS is None or _NAMES is None:
        # A programming error, not an operator's: whatever loads procedure files imports
        # station.methods first (every front end and the engine do).
        raise RuntimeError("no methods are known: import station.methods before loading procedures")
    return _NEEDS, _NAMES


def step_schema(kind: str) -> StepSchema:
    """What a step of kind ``kind`` may hold (KeyError for an unknown kind)."""
    if kind in _STEP_SCHEMAS:
        return _STEP_SCHEMAS[kind]
    return _site_step_schemas()[kind]


def step_kinds() -> tuple[str, ...]:
    """The step kinds a procedure file may use: the built-in ones, then a site's."""
    return tuple(dict.fromkeys([*_STEP_SCHEMAS, *_site_step_schemas()]))


def _site_step_schemas() -> dict[str, StepSchema]:
    """The schemas of the step kinds a site's installed packages offer (their handlers'
    ``kind`` and ``schema``; the handlers themselves are the engine's business)."""
    found: dict[str, StepSchema] = {}
    for handler in site_extensions(STEP_KINDS).loaded:
        kind, schema = getattr(handler, "kind", None), getattr(handler, "schema", None)
        if isinstance(kind, str) and ID_PATTERN.match(kind) and isinstance(schema, StepSchema):
            found.setdefault(kind, schema)
    return found


def analysis_needs(kind: str) -> AnalysisNeeds:
    """What a procedure declaring ``analysis = kind`` must hold (KeyError for an unknown kind)."""
    found = _methods()[0](kind)
    if found is None:
        raise KeyError(kind)
    return found


def analysis_kinds() -> tuple[str, ...]:
    """The methods a procedure file may declare (``analysis = NAME``), the default first."""
    return _methods()[1]()
