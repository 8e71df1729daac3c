"""Issue 27, findings 2, 3, 4 and 7: text from outside (a CSV header, an output name, a
channel name, an index column) is text; too much of it is one sentence, never a traceback."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest
from helpers import run_station
from record.conftest import write_repeatability

READINGS = "".join(f"{(k % 7 - 3) / 10000},{(k % 5 - 2) / 10000}\n" for k in range(30))
HUGE_CELL = "h" * (140 << 10)
"""Over the csv module's 128 KiB field limit."""


def one_sentence(result: subprocess.CompletedProcess, *words: str) -> str:
    """Exit 2 with one ``station: ...`` line on stderr naming ``words``; the line."""
    assert result.returncode == 2, (result.returncode, result.stdout[-500:], result.stderr[-2000:])
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("station: "), result.stderr[-2000:]
    for word in words:
        assert word in lines[0], lines[0]
    return lines[0]


# -- finding 2: a CSV cell over 128 KiB -------------------------------------------------------

PROCEDURES = (
    "repeatability",
    "linearity",
    "relative_accuracy",
    "gauge_check",
    "gauge_linearity",
    "joint_troubleshooting",
    "gain_schedule",
)


@pytest.mark.parametrize("procedure", PROCEDURES)
def test_a_header_cell_over_128_kib_is_one_sentence_in_every_analysis(tmp_path, procedure):
    table = tmp_path / "long-header.csv"
    table.write_text(f"cycle,{HUGE_CELL}\n" + READINGS)
    result = run_station("analyze", table, "--procedure", procedure)
    one_sentence(result, "long-header.csv", "line 1", "128 KiB")


def test_a_reading_cell_and_a_tidy_cell_over_128_kib_name_their_line(tmp_path):
    wide = tmp_path / "wide.csv"
    wide.write_text("x,y\n" + READINGS + f"0.1,{HUGE_CELL}\n")
    one_sentence(run_station("analyze", wide), "wide.csv", "line 32", "128 KiB")
    tidy = tmp_path / "tidy.csv"
    tidy.write_text(f"cycle,channel,value\n1,x,0.1\n2,{HUGE_CELL},0.1\n")
    one_sentence(run_station("analyze", tidy), "tidy.csv", "line 3", "128 KiB")


def test_gains_fit_says_a_header_cell_is_over_128_kib(tmp_path):
    gains = tmp_path / "gains.csv"
    gains.write_text(f"q,{HUGE_CELL}\n" + "".join(f"{q},{1 + q / 100}\n" for q in range(9)))
    one_sentence(run_station("gains", "fit", gains), "gains.csv", "line 1", "128 KiB")


# -- finding 3: an output name over 255 bytes -------------------------------------------------


@pytest.fixture(scope="module")
def session(tmp_path_factory) -> Path:
    return write_repeatability(tmp_path_factory.mktemp("sessions"))


@pytest.mark.parametrize(
    "command",
    [("report", "--format", "html"), ("export", "--csv")],
    ids=["report", "export"],
)
def test_an_output_name_over_255_bytes_is_one_sentence(tmp_path, session, command):
    out = tmp_path / ("r" * 300)
    result = run_station(command[0], session, *command[1:], "-o", out)
    line = one_sentence(result, "longer than the file system allows", "shorter name")
    assert len(line) < 300, line
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize(
    "command",
    [("report", "--format", "html"), ("export", "--csv")],
    ids=["report", "export"],
)
def test_an_output_in_a_missing_folder_is_one_sentence(tmp_path, session, command):
    out = tmp_path / "missing" / "out"
    result = run_station(command[0], session, *command[1:], "-o", out)
    one_sentence(result, "does not exist", "create it first")


def test_gains_fit_c_header_over_255_bytes_is_one_sentence(tmp_path):
    gains = tmp_path / "gains.csv"
    gains.write_text("q,kp\n" + "".join(f"{q},{1 + q / 100}\n" for q in range(9)))
    result = run_station("gains", "fit", gains, "--c", tmp_path / ("g" * 300 + ".h"))
    one_sentence(result, "longer than the file system allows")


# -- finding 7: a row-number column is no channel ---------------------------------------------

CAPABLE_READINGS = [(k % 7 - 3) / 10000 for k in range(30)]
"""Readings well inside ±0.001 (Cpk about 1.6)."""


@pytest.mark.parametrize("index", ["sample", "Sample", "ID", "index", "Obs"])
def test_a_row_number_column_as_spreadsheets_name_it_is_not_a_channel(tmp_path, index):
    table = tmp_path / "minitab.csv"
    rows = "".join(f"{k},{value}\n" for k, value in enumerate(CAPABLE_READINGS, start=1))
    table.write_text(f"{index},x\n" + rows)
    result = run_station(
        "analyze", table, "--lsl", "-0.001", "--usl", "0.001", "--fail-if-incapable"
    )
    assert result.returncode == 0, result.stdout[-2000:] + result.stderr
    assert f"FEATURE: {index}" not in result.stdout and "FEATURE: x" in result.stdout


def test_a_column_that_counts_the_rows_is_left_out_with_a_note(tmp_path):
    table = tmp_path / "excel.csv"
    rows = "".join(f"{k},{value}\n" for k, value in enumerate(CAPABLE_READINGS, start=1))
    table.write_text("n,x\n" + rows)
    limits = ("--lsl", "-0.001", "--usl", "0.001", "--fail-if-incapable")
    result = run_station("analyze", table, *limits)
    assert result.returncode == 0, result.stdout[-2000:] + result.stderr
    assert "FEATURE: n" not in result.stdout
    assert "column 'n' counts the rows" in result.stdout
    as_json = run_station("analyze", table, *limits, "--json")
    assert as_json.returncode == 0, as_json.stderr
    assert "station: note: column 'n' counts the rows" in as_json.stderr


def test_a_counting_column_a_method_reads_by_name_stays(tmp_path):
    # A gains table's positions may well be 1, 2, 3 ...: q is the method's own column.
    gains = tmp_path / "gains.csv"
    gains.write_text("q,kp\n" + "".join(f"{q},{1 + q * q / 100}\n" for q in range(1, 10)))
    result = run_station("analyze", gains, "--procedure", "gain_schedule")
    assert result.returncode == 0, result.stderr
    assert "counts the rows" not in result.stdout


def test_a_lone_column_of_counting_readings_is_still_analysed(tmp_path):
    table = tmp_path / "coarse.csv"
    table.write_text("x\n" + "".join(f"{k}\n" for k in range(1, 31)))
    result = run_station("analyze", table)
    assert result.returncode == 0, result.stderr
    assert "FEATURE: x" in result.stdout
