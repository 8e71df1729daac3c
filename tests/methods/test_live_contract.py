"""Every built-in method's live analysis takes a cycle the way the engine hands it over."""

from __future__ import annotations

import inspect

import pytest

from station.analysis.summary import AnalysisConfig
from station.methods.catalog import BUILT_IN


@pytest.mark.parametrize("method", BUILT_IN, ids=lambda method: method.name)
def test_a_live_analysis_takes_a_cycle_with_its_times_and_placement(method) -> None:
    # The engine calls add_cycle(values, cycle, times, placement) for every method: the
    # linearity's live analysis once lacked `placement`, and a cycle taken in a linearity
    # session (a capture step beside the strokes) raised TypeError in the engine.
    live = method.live(AnalysisConfig(), ("x",), {})
    inspect.signature(live.add_cycle).bind({"x": 0.0}, 1, {"x": 0.0}, None)
