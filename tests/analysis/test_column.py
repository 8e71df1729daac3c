"""Columns of readings kept as arrays: read like the tuples they replace, cost no copies."""

import numpy as np
import pytest

from station.analysis.column import Column
from station.analysis.summary import AnalysisConfig, analyze_channel, cycle_labels
from station.errors import StationError


def test_a_column_reads_as_a_tuple_of_python_numbers():
    column = Column([0.5, -0.25, 1.0])
    assert len(column) == 3 and column == (0.5, -0.25, 1.0) and column == [0.5, -0.25, 1.0]
    assert column[1] == -0.25 and type(column[1]) is float and column[-1] == 1.0
    assert column[1:] == (-0.25, 1.0) and list(reversed(column)) == [1.0, -0.25, 0.5]
    assert all(type(v) is float for v in column) and column and not Column(())
    cycles = Column([3, 7], dtype=np.int64)
    assert type(cycles[0]) is int and list(cycles) == [3, 7]
    assert Column([1.0, 2.0]) == Column([1.0, 2.0]) != Column([1.0])
    assert hash(Column([1.0, 2.0])) == hash(Column([1.0, 2.0]))


def test_a_column_is_its_array_read_only_and_apart_from_what_it_was_made_of():
    values = np.array([1.0, 2.0, 3.0])
    column = Column(values)
    values[0] = 99.0
    assert column[0] == 1.0
    assert np.asarray(column) is column.array and np.asarray(column, dtype=float) is column.array
    with pytest.raises(ValueError):
        column.array[0] = 5.0


def test_an_analysis_keeps_its_readings_cycles_and_points_as_arrays():
    values = np.round(np.random.default_rng(5).normal(0.0, 0.0003, 200), 4)
    channel = analyze_channel("x", values, AnalysisConfig(), cycles=np.arange(11, 211))
    for column in (channel.readings, channel.cycles, channel.chart.points):
        assert isinstance(column, Column)
    assert np.array_equal(channel.readings.array, values)
    assert channel.cycles[0] == 11 and channel.cycles == tuple(range(11, 211))


def test_cycle_numbers_must_be_whole_and_one_per_reading():
    assert cycle_labels("x", None, 3) == (1, 2, 3)
    assert cycle_labels("x", [4.0, 9.0], 2) == (4, 9)
    for wrong in ([1, 2], [1.0, 2.5, 3.0], [1.0, float("nan"), 3.0], ["a", "b", "c"]):
        with pytest.raises(StationError, match="give one whole cycle number per reading"):
            cycle_labels("x", wrong, 3)
