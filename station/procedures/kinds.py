"""The registries a procedure file is validated against: what each step kind may hold (its
:class:`StepSchema`) and what each analysis kind needs of a procedure (:class:`AnalysisNeeds`).
The step-handler and analysis-kind registries add to them, so a kind the loader has never seen
the code of is validated all the same."""

from __future__ import annotations

from dataclasses import dataclass

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
    implies_analysis: str | None = None
    """The analysis kind a procedure holding this step defaults to."""

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
    "stroke": StepSchema(channels=True, counts=True, direction=True, implies_analysis="linearity"),
    "repeat": StepSchema(block=True, implies_analysis="relative_accuracy"),
}


@dataclass(frozen=True)
class AnalysisNeeds:
    """What a procedure must hold for an analysis kind: a step of a kind with ``facet`` (e.g.
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


_ANALYSES: dict[str, AnalysisNeeds] = {
    "repeatability": AnalysisNeeds(),
    "relative_accuracy": AnalysisNeeds(
        facet="block", facet_words="a repeat block (one per placement)", channels=("x", "y", "z")
    ),
    "linearity": AnalysisNeeds(facet="direction", facet_words="a stroke step (streamed strokes)"),
    # The rest of the report's method (station.method_kinds registers them with these needs;
    # they are known here too so that a file declaring them loads without the registry).
    "gauge_check": AnalysisNeeds(
        facet="counts",
        facet_words="a cycles step (the repeated readings)",
        numbers=("reference", "tolerance"),
        numbers_words="an input step with number fields 'reference' and 'tolerance'",
        limits=False,
    ),
    "joint_troubleshooting": AnalysisNeeds(
        facet="counts",
        facet_in_block=True,
        facet_words="a repeat block (one per joint) holding a cycles step",
        channels=("x", "y", "z"),
    ),
    "gain_schedule": AnalysisNeeds(
        numbers=("q",),
        more_numbers=1,
        numbers_words="an input step with a number field 'q' (the position) and one number "
        "field per gain",
        limits=False,
    ),
}


def register_step_schema(kind: str, schema: StepSchema) -> None:
    """Let procedure files use step kind ``kind`` with ``schema`` (called by the step-handler
    registry when a handler is registered)."""
    if not ID_PATTERN.match(kind):
        raise ValueError(f"a step kind is a plain name, not {kind!r}")
    _STEP_SCHEMAS[kind] = schema


def register_analysis_needs(kind: str, needs: AnalysisNeeds) -> None:
    """Let procedure files declare ``analysis = kind`` (called by the analysis-kind registry)."""
    _ANALYSES[kind] = needs


def step_schema(kind: str) -> StepSchema:
    """What a step of kind ``kind`` may hold (KeyError for an unknown kind)."""
    return _STEP_SCHEMAS[kind]


def step_kinds() -> tuple[str, ...]:
    """The step kinds a procedure file may use."""
    return tuple(_STEP_SCHEMAS)


def analysis_needs(kind: str) -> AnalysisNeeds:
    """What a procedure declaring ``analysis = kind`` must hold (KeyError for an unknown kind)."""
    return _ANALYSES[kind]


def analysis_kinds() -> tuple[str, ...]:
    """The analysis kinds a procedure file may declare."""
    return tuple(_ANALYSES)
