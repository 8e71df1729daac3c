"""The procedure file's arrival trigger and zero-step settings: defaults, values, faults."""

from __future__ import annotations

from pathlib import Path

import pytest
from helpers import PROBE_HEAD as HEAD
from helpers import write_procedure as write

from station.errors import StationError
from station.instruments.arrival import ArrivalConfig
from station.procedures import load_procedure

ZERO = """
[[steps]]
id = "zero"
kind = "zero"
title = "Zero"
text = "Keep the robot still and zero."
"""


def test_without_settings_the_defaults_apply(tmp_path: Path) -> None:
    procedure = load_procedure(write(tmp_path, HEAD + ZERO))
    assert procedure.arrival == ArrivalConfig()
    zero = procedure.steps[0]
    # Without readings: the gauge's zero command, else one reading set (as before).
    assert (zero.readings, zero.settle, zero.still) == (None, 1.0, 3.0)


def test_the_files_settings_are_kept(tmp_path: Path) -> None:
    text = (
        HEAD
        + "\n[arrival]\nband = 0.02\nstill = 3\nsettle = 0.8\ntimeout = 15\n"
        + ZERO
        + "readings = 20\nsettle = 2.5\nstill = 4\n"
    )
    procedure = load_procedure(write(tmp_path, text))
    assert procedure.arrival == ArrivalConfig(band=0.02, still=3, settle=0.8, timeout=15)
    zero = procedure.steps[0]
    assert (zero.readings, zero.settle, zero.still) == (20, 2.5, 4.0)


@pytest.mark.parametrize(
    ("extra", "zero_extra", "fault"),
    [
        ("\n[arrival]\nwait = 2\n", "", r"\[arrival\]: unknown key\(s\) 'wait'"),
        ("\n[arrival]\nband = -1\n", "", r"\[arrival\]: 'band' must be greater than 0"),
        ("\n[arrival]\nsettle = 20\n", "", r"\[arrival\]: The arrival timeout \(10 s\) must"),
        ("", "readings = 1\n", r"step 1 \(zero\): 'readings' must be 2 or more"),
        ("", "settle = 0\n", r"step 1 \(zero\): 'settle' must be greater than 0"),
        ("", "readings = 2.5\n", r"step 1 \(zero\): 'readings' must be an integer"),
    ],
)
def test_faults_name_the_file_and_the_place(tmp_path: Path, extra, zero_extra, fault) -> None:
    path = write(tmp_path, HEAD + extra + ZERO + zero_extra)
    with pytest.raises(StationError, match=fault) as caught:
        load_procedure(path)
    assert str(path) in caught.value.message


def test_the_indicators_stop_and_its_reading_are_kept(tmp_path: Path) -> None:
    text = HEAD + '\n[arrival]\nstop = "high"\nfree_travel = 0.375\n' + ZERO
    procedure = load_procedure(write(tmp_path, text))
    assert procedure.arrival.stop == "high"
    assert procedure.arrival.free_travel == dict.fromkeys(procedure.channels, 0.375)


@pytest.mark.parametrize(
    ("extra", "fault"),
    [
        ('\n[arrival]\nstop = "left"\n', r"'stop' must be \"low\" or \"high\", not 'left'"),
        ("\n[arrival]\nfree_travel = { q = 1.0 }\n", r"'free_travel' names q, not a channel"),
        ('\n[arrival]\nfree_travel = "far"\n', r"'free_travel' of \w+ must be a number"),
        ("\n[arrival]\nfree_travel = inf\n", r"'free_travel' of \w+ must be finite"),
    ],
)
def test_a_wrong_stop_is_refused_naming_the_place(tmp_path: Path, extra, fault) -> None:
    path = write(tmp_path, HEAD + extra + ZERO)
    with pytest.raises(StationError, match=fault):
        load_procedure(path)
