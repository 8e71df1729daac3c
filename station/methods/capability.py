"""The capability analysis a method's verdict judges, of the channels it names: the report's
statistics (:func:`station.analysis.summary.analyze`) without the repeatability hints, since a
method's own report block says what its figures point to."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from station.analysis.summary import Analysis, AnalysisConfig, analyze
from station.methods.contract import MethodInputs


def capability_of(
    inputs: MethodInputs, channels: Sequence[str], config: AnalysisConfig
) -> Analysis:
    """The analysis of ``channels`` of ``inputs`` with ``config`` (their cycle numbers and
    times where the inputs have them)."""
    readings = {name: np.asarray(inputs.channels[name], dtype=float) for name in channels}
    cycles = None if inputs.cycles is None else {c: inputs.cycles[c] for c in channels}
    times = None
    if inputs.times is not None and all(c in inputs.times for c in channels):
        times = {c: inputs.times[c] for c in channels}
    analysis = analyze(
        readings, config, excluded_cycles=inputs.excluded_cycles, cycles=cycles, times=times
    )
    return replace(analysis, given_hints=())
