"""The procedure engine (no UI): set-up, state, the engine and its step handlers.

Front ends import from here: :class:`Runner` (the engine), :class:`SessionSetup` and
:class:`PortSetup` (what a session starts with), and the state they read
(:class:`RunnerState`, :class:`Action`, :class:`Progress`, :class:`RunnerNotice`).
"""

from station.run.engine import CAPTURE_BY, Runner
from station.run.readings import DEVICE_DRIVEN_TRIGGERS, set_problem
from station.run.setup import (
    PortSetup,
    SessionSetup,
    open_gauges,
    plan_steps,
    procedure_limits,
    recorded_setup,
    resume_setup,
    setup_from_header,
)
from station.run.state import (
    ACTION_KINDS,
    Action,
    CycleOutcome,
    CycleRecord,
    Listener,
    OperatorMessage,
    PortState,
    Progress,
    RunnerNotice,
    RunnerState,
    StepView,
    StrokeOutcome,
)
from station.text import figure_decimals, format_figure

__all__ = [
    "ACTION_KINDS",
    "CAPTURE_BY",
    "DEVICE_DRIVEN_TRIGGERS",
    "Action",
    "CycleOutcome",
    "CycleRecord",
    "Listener",
    "OperatorMessage",
    "PortSetup",
    "PortState",
    "Progress",
    "Runner",
    "RunnerNotice",
    "RunnerState",
    "SessionSetup",
    "StepView",
    "StrokeOutcome",
    "figure_decimals",
    "format_figure",
    "open_gauges",
    "plan_steps",
    "procedure_limits",
    "recorded_setup",
    "resume_setup",
    "set_problem",
    "setup_from_header",
]
