"""What a procedure file holds once validated: frozen dataclasses (a procedure, its steps, their
input fields, the limits) and the catalog :func:`~station.procedures.discover_procedures` finds."""

from __future__ import annotations

import re
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from station.errors import StationError
from station.instruments.arrival import ArrivalConfig

StepKind = str
"""A step kind: one of :func:`step_kinds` (the built-ins, and any a handler registered)."""
UNITS: tuple[str, ...] = ("in", "mm")
AnalysisKind = str
"""A method's name (what ``analysis =`` names): one of :func:`analysis_kinds`."""

DEFAULT_CYCLES_MIN = 25
#: The assignable causes an alarm is acknowledged with when the procedure names none.
DEFAULT_CAUSES: tuple[str, ...] = ("fixture moved", "gauge", "temperature", "robot", "other")
#: The cause that asks the operator to say what it was.
OTHER_CAUSE = "other"
DEFAULT_CYCLES_TARGET = 30

ID_PATTERN = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]*$")
"""An id, a step kind, a field or channel name: letters, digits, '.', '_' and '-'."""


@dataclass(frozen=True)
class InputField:
    """One value an ``input`` step asks the operator for, e.g. the teach pendant's X."""

    name: str
    label: str
    type: Literal["number", "text"] = "number"
    unit: str | None = None
    required: bool = True


@dataclass(frozen=True)
class Step:
    """One step of a procedure. Fields that do not apply to the step's kind keep their defaults.

    ``channels`` is always filled for ``zero``, ``capture``, ``cycles`` and ``stroke`` steps (the
    procedure's channels when the file does not name them). ``count_min``/``count_target`` are
    the cycle counts of a ``cycles`` step, the stroke counts of a ``stroke`` step and the
    repetition counts of a ``repeat`` block; ``None`` for the other kinds.
    """

    id: str
    kind: StepKind
    title: str
    text: str = ""
    fields: tuple[InputField, ...] = ()
    channels: tuple[str, ...] = ()
    count_min: int | None = None
    count_target: int | None = None
    prompt: str = ""
    direction_channel: str | None = None
    label: str = ""
    steps: tuple[Step, ...] = ()
    number: str = ""
    """Where the step is in the file, 1-based: ``"3"``, or ``"5.2"`` inside a repeat block."""
    options: Mapping[str, Any] = field(default_factory=dict)
    """The values of the keys a registered step kind declares as its own (``schema.keys``)."""
    readings: int | None = None
    """A ``zero`` step: readings per channel the zero is the mean of (None: the engine's default
    for the session's trigger, always several; always None for other kinds)."""
    settle: float | None = None
    """A ``zero`` step: seconds its readings are spread over."""
    still: float | None = None
    """A ``zero`` step: resolutions its readings may spread before the zero is refused."""

    def prompt_for(self, cycle: int, count: int) -> str:
        """The per-cycle prompt with ``{cycle}`` and ``{count}`` filled in (plain substitution)."""
        return self.prompt.replace("{cycle}", str(cycle)).replace("{count}", str(count))


@dataclass(frozen=True)
class Limit:
    """Specification limits of one channel, in the procedure's unit."""

    lsl: float
    usl: float
    nominal: float = 0.0


@dataclass(frozen=True)
class Procedure:
    """A validated procedure file. ``sha256`` is the hash of the file's bytes (kept in sessions)."""

    id: str
    title: str
    version: str
    report_section: str
    description: str
    channels: tuple[str, ...]
    unit: str
    resolution: float
    cycles_min: int
    cycles_target: int
    limits: Mapping[str, Limit]
    """Default limits per channel; empty when the file gives none (the set-up asks)."""
    steps: tuple[Step, ...]
    path: Path
    sha256: str
    analysis: AnalysisKind = "repeatability"
    """How its sessions are analysed: the file's ``analysis``, else by its steps."""
    arrival: ArrivalConfig = field(default_factory=ArrivalConfig)
    """The ``arrival`` trigger's parameters: the file's ``[arrival]``, else the defaults."""
    trigger: str | None = None
    """The trigger its sessions take by default where the gauges can be read continuously (the
    file's ``trigger``); None: poll."""
    causes: tuple[str, ...] = DEFAULT_CAUSES
    """The assignable causes an alarm is acknowledged with; "other" (with a text) is last."""

    def all_steps(self) -> Iterator[Step]:
        """Every step in file order, including those inside repeat blocks (after their block)."""
        for step in self.steps:
            yield step
            yield from step.steps

    def step(self, step_id: str) -> Step:
        """The step with this id, anywhere in the procedure; StationError when there is none."""
        for step in self.all_steps():
            if step.id == step_id:
                return step
        raise StationError(f"procedure {self.id!r} has no step {step_id!r}")


@dataclass(frozen=True)
class ProcedureCatalog:
    """The procedures found by :func:`discover_procedures`, one per id (a user's wins)."""

    procedures: tuple[Procedure, ...]
    builtin_ids: frozenset[str] = frozenset()
    """Ids whose winning procedure is the built-in one."""
    overridden: Mapping[str, Path] = field(default_factory=dict)
    """Id -> the file that was overridden (built-in or an earlier folder's)."""
    notes: tuple[str, ...] = ()
    """Sentences for the listing: overrides, and files that failed to load (with their error)."""
    errors: tuple[str, ...] = ()
    """The load errors alone (also in ``notes``)."""
    overrides_builtin: frozenset[str] = frozenset()
    """Ids where a site's procedure replaced the built-in one."""

    def get(self, procedure_id: str) -> Procedure:
        """The procedure with this id; StationError naming the known ids when there is none."""
        for procedure in self.procedures:
            if procedure.id == procedure_id:
                return procedure
        known = ", ".join(p.id for p in self.procedures) or "none"
        hint = f" ({len(self.errors)} file(s) failed to load: run `station procedures`)"
        raise StationError(
            f"no procedure {procedure_id!r}; known procedures: {known}"
            + (hint if self.errors else "")
        )

    def ids(self) -> tuple[str, ...]:
        """The ids, sorted."""
        return tuple(p.id for p in self.procedures)

    def is_builtin(self, procedure_id: str) -> bool:
        """True when the procedure with this id is the built-in one (not overridden)."""
        return procedure_id in self.builtin_ids

    def origin(self, procedure_id: str) -> str:
        """``built-in``, ``site`` or ``site, overrides built-in``: for listings."""
        if procedure_id in self.builtin_ids:
            return "built-in"
        if procedure_id in self.overrides_builtin:
            return "site, overrides built-in"
        return "site"
