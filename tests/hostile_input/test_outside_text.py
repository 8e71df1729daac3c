"""Issue 27, findings 2, 3, 4 and 7: text from outside (a CSV header, an output name, a
channel name, an index column) is text; too much of it is one sentence, never a traceback."""

from __future__ import annotations

import json
import re
import subprocess
import warnings
from datetime import UTC, datetime
from pathlib import Path

import pytest
from helpers import run_station
from hostile import raw_controls
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
    "gage_rr",
    "joint_troubleshooting",
    "gain_schedule",
    "positioning",
    "pose_characteristics",
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


# -- finding 4: channel names and units in charts and exports ---------------------------------

MATHTEXT = "$\\frac{1}{$"
CONTROLS = "y\x1b]0;pwned\x07\x9b31m"
LONG_NAME = "N" * 100_000


def named_session(folder: Path, names: dict[str, str], unit: str) -> Path:
    """A finished repeatability session whose channels x, y, z are called ``names`` and whose
    readings are in ``unit``: the header production writes, renamed."""
    from session.conftest import session_header_fields

    from station.session.journal import SessionWriter

    text = json.dumps(session_header_fields(robot="r2", operator="ana"))
    for old, new in names.items():
        text = text.replace(json.dumps(old), json.dumps(new))
    header = json.loads(text) | {"unit": unit}
    folder.mkdir(exist_ok=True)
    with SessionWriter.create(folder, header, now=datetime(2026, 11, 23, 12, tzinfo=UTC)) as w:
        for cycle in range(1, 31):
            channels = {}
            for index, name in enumerate([names.get(c, c) for c in ("x", "y", "z")]):
                value = round(((cycle * 7 + index * 3) % 11 - 5) * 0.0001, 4)
                channels[name] = {
                    "value": value,
                    "raw_value": value,
                    "zero": 0.0,
                    "unit": unit,
                    "raw": f"0{index + 1}A{value:+.4f}",
                    "t_mono": 1000.0 + cycle,
                    "t_wall": 1.7e9 + cycle,
                }
            w.append("reading", cycle=cycle, step="cycles", channels=channels)
        w.append("finish", verdict="capable")
    return w.path


def svg_text(html: str) -> str:
    return "".join(re.findall(r"<svg.*?</svg>", html, flags=re.DOTALL))


def test_mathtext_and_controls_in_names_are_text_in_the_html_report(tmp_path):
    session = named_session(tmp_path / "s", {"x": MATHTEXT, "y": CONTROLS}, "in\x07$")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = run_station("report", session, "--format", "html", "-o", tmp_path / "r.html")
    assert result.returncode == 0, result.stderr[-2000:]
    assert [str(w.message) for w in caught] == []
    html = (tmp_path / "r.html").read_text()
    assert raw_controls(html) == []
    svg = svg_text(html)
    assert MATHTEXT in svg  # shown as typed, not parsed as maths
    assert "y\\x1b]0;pwned\\x07\\x9b31m" in svg and "in\\x07$" in svg


def test_a_glyph_the_font_lacks_warns_nobody(tmp_path):
    session = named_session(tmp_path / "s", {"x": "軸\U0001f916"}, "mm")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = run_station("report", session, "--format", "html")
    assert result.returncode == 0 and result.stderr == "", result.stderr[-2000:]
    assert [str(w.message) for w in caught] == []


def test_a_100k_character_name_is_cut_in_the_charts(tmp_path):
    session = named_session(tmp_path / "s", {"x": LONG_NAME}, "mm")
    result = run_station("report", session, "--format", "html")
    assert result.returncode == 0, result.stderr[-2000:]
    svg = svg_text(result.stdout)
    assert "N" * 59 + "…" in svg and "N" * 61 not in svg


@pytest.mark.parametrize("layout", ["tidy", "wide"])
def test_controls_in_names_and_units_are_visible_in_the_csv_export(tmp_path, layout):
    session = named_session(tmp_path / "s", {"y": CONTROLS}, "in\x07")
    out = tmp_path / "out.csv"
    result = run_station("export", session, "--csv", "--layout", layout, "-o", out)
    assert result.returncode == 0, result.stderr
    text = out.read_text()
    assert raw_controls(text) == []
    assert "y\\x1b]0;pwned\\x07\\x9b31m" in text
