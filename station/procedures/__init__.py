"""Procedures as data: load and validate ``procedures/*.toml`` into frozen dataclasses.

A procedure file is TOML read with :mod:`tomllib`; nothing in it is ever executed. Every fault
found on load is a :class:`~station.errors.StationError` naming the file, the step (number and
id) and what is wrong, so a site editing its own procedure sees exactly where to look.

The file format (see ``procedures/repeatability.toml`` for a full example)::

    id = "repeatability"            # letters, digits, '.', '_' and '-'
    title = "..."
    version = "1.0"                 # a string
    report_section = "2.6"
    description = "..."             # optional
    channels = ["x", "y", "z"]
    unit = "in"                     # "in" or "mm"
    resolution = 0.0001             # the gauge's resolution in `unit`
    analysis = "repeatability"      # optional: the method that judges its sessions (see
                                    # station.methods: repeatability, relative_accuracy,
                                    # linearity, gauge_check, gauge_linearity, gage_rr,
                                    # joint_troubleshooting, gain_schedule or a site's own);
                                    # default by the steps: a stroke step -> linearity, a repeat
                                    # block over x, y, z -> relative_accuracy, else repeatability

    [cycles]                        # optional; default min 25, target 30 (the report's 25 to 30)
    min = 25
    target = 30

    trigger = "arrival"             # optional: the trigger a session takes by default where
                                    # the gauges can be read continuously (a polled protocol):
                                    # poll, push, stable or arrival; else poll

    [arrival]                       # optional: the arrival trigger (cycles paced by the robot)
    band = 0.01                     # a channel farther than this from its zero has left the
                                    # fixture (in `unit`; default 100 x the gauge resolution)
    still = 2                       # resolutions the readings may spread and still be still (2)
    settle = 0.5                    # seconds of stillness before the set is taken (0.5)
    timeout = 10.0                  # seconds after its return by which the robot must be
                                    # still, else the return is reported, not recorded (10)
    stop = "low"                    # the end of its travel an indicator shows with nothing
                                    # touching it: "low" (a plunger pushed in reads higher) or
                                    # "high"; the station learns where it is from the robot's
                                    # round trips, and never zeroes nor takes a set there
    free_travel = -0.375            # optional: the reading there, before any zero (one number,
                                    # or per channel: { x = -0.375, y = -0.37 }); with it a
                                    # robot stopped at the fixture is zeroed without a trip

    [limits]                        # optional; either a tolerance about a nominal for every channel
    tolerance = 0.001
    nominal = 0.0                   # optional, default 0
    # ... or per channel:  x = { lsl = -0.001, usl = 0.001, nominal = 0.0 }  or  x = [-0.001, 0.001]

    causes = ["fixture moved", "gauge", "temperature", "robot", "other"]
                                    # optional: the assignable causes an operator acknowledges
                                    # an alarm with (this list is the default; "other" asks for
                                    # a text and is always offered)

    [[steps]]
    id = "fixture"
    kind = "check"                  # check input zero capture cycles parts stroke repeat
    title = "Fix the fixture"
    text = "Bolt or clamp the 3D fixture to a surface plate within the robot's work envelope."

Keys per step kind, beyond ``id``, ``kind``, ``title`` and ``text``:

- ``input``: ``fields = [{ name, label, type = "number"|"text", unit, required }]``
- ``zero``: ``channels`` (default: all), ``readings`` (per channel, 2 or more: the zero is
  their mean; default 5, or 3 DATA presses with the push trigger), ``settle`` (seconds
  the readings are spread over; default 1.0) and ``still`` (resolutions the readings may spread
  before a gauge counts as moving and the zero is refused; default 3)
- ``capture``: ``channels`` (default: all the procedure's channels)
- ``cycles``: ``channels``, ``min``, ``target`` (default: the procedure's cycle counts), ``prompt``
  (shown before each cycle; ``{cycle}`` and ``{count}`` are replaced by plain text substitution)
- ``parts``: ``channels``, ``target`` (the parts, numbered 1 to target, each read once; also its
  minimum), ``prompt`` (``{part}``: the part to read; ``{cycle}`` and ``{count}``: its place in
  the order and how many). The order is drawn afresh each time the step comes (each placement
  of a block) and recorded before its first reading; each reading records its part
- ``stroke``: ``channels``, ``direction_channel`` (the channel that tracks the position along the
  stroke, e.g. the linear scale ``s``), ``min``, ``target`` (strokes), ``prompt``
- ``repeat``: ``label`` (e.g. ``"placement"``), ``min``, ``target``, ``prompt``, and its own
  ``[[steps.steps]]`` block (no nested ``repeat``)
"""

from station.procedures.discovery import (
    PROCEDURES_ENV,
    builtin_procedures_dir,
    discover_procedures,
    procedure_dirs_from_env,
)
from station.procedures.kinds import (
    AnalysisNeeds,
    StepSchema,
    analysis_kinds,
    analysis_needs,
    step_kinds,
    step_schema,
    use_methods,
)
from station.procedures.loading import load_procedure, parse_procedure
from station.procedures.model import (
    DEFAULT_CAUSES,
    OTHER_CAUSE,
    UNITS,
    AnalysisKind,
    InputField,
    Limit,
    Procedure,
    ProcedureCatalog,
    Step,
    StepKind,
)

__all__ = [
    "DEFAULT_CAUSES",
    "OTHER_CAUSE",
    "PROCEDURES_ENV",
    "UNITS",
    "AnalysisKind",
    "AnalysisNeeds",
    "InputField",
    "Limit",
    "Procedure",
    "ProcedureCatalog",
    "Step",
    "StepKind",
    "StepSchema",
    "analysis_kinds",
    "analysis_needs",
    "builtin_procedures_dir",
    "discover_procedures",
    "load_procedure",
    "parse_procedure",
    "procedure_dirs_from_env",
    "step_kinds",
    "step_schema",
    "use_methods",
]
