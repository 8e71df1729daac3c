"""`station analyze` end to end: the real console script in a subprocess, real files."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from helpers import run_station

REPO = Path(__file__).resolve().parents[2]
TABLE_2_1 = REPO / "sessions" / "examples" / "table-2-1.csv"
STATION = Path(sys.executable).parent / "station"
REPORT_LIMITS = ["--lsl", "-0.001", "--usl", "0.001", "--resolution", "0.0001"]


def station(*args: str | Path) -> subprocess.CompletedProcess[str]:
    """``station analyze ARGS``, in this process (test_analyze_honesty runs the real one)."""
    return run_station("analyze", *args, cwd=REPO)


def write_csv(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.write_text(text)
    return path


@pytest.fixture(scope="module")
def xyz_csv(tmp_path_factory) -> Path:
    rng = np.random.default_rng(17)
    folder = tmp_path_factory.mktemp("xyz")
    rows = ["# three indicators, inches", "cycle,x,y,z"]
    for cycle in range(1, 31):
        x, y, z = np.round(rng.normal([0.0, 0.0002, 0.0], [0.0002, 0.0002, 0.0006]), 4)
        rows.append(f"{cycle},{x},{y},{z}")
    return write_csv(folder, "xyz.csv", "\n".join(rows) + "\n")


def test_text_report_of_table_2_1_shows_the_reports_figures():
    result = station(TABLE_2_1, *REPORT_LIMITS, "--unit", "in")
    assert result.returncode == 0, result.stderr
    for figure in [
        "MAXIMUM: +0.00070",
        "AVERAGE: +0.00008",
        "MINIMUM: -0.00050",
        "SIGMA: 0.00026",  # a spread has no sign
        "RANGE: 0.00120",
        "MODE: +0.00020",
        "SKEWNESS a1: -0.356",
        "Cp 1.26   Cpu 1.17   Cpl 1.36   Cpk 1.17",
        "Cp (Pp)   95% interval 0.94 to 1.59 (chi-square)",
        "Cpk (Ppk) 95% interval 0.84 to 1.49, one-sided bounds 0.90 and 1.44 (Bissell)",
        # Issue 20: 30 readings cannot show a Cpk of 1.17 above 1; the report's rule beside it.
        "VERDICT: INCONCLUSIVE (Cpk 1.17; Bissell 95% bounds 0.90 to 1.44 straddle 1: 77",
        "by the report's rule: capable, Cpk 1.17",
    ]:
        assert figure in result.stdout, figure
    assert max(len(line) for line in result.stdout.splitlines()) <= 80
    assert result.stderr == ""


def test_json_has_every_documented_key(xyz_csv):
    result = station(xyz_csv, *REPORT_LIMITS, "--json", "--limit", "z=:0.002")
    assert result.returncode == 0, result.stderr
    document = json.loads(result.stdout)
    assert set(document["channels"]) == {"x", "y", "z"}
    for channel in document["channels"].values():
        assert {"n", "mean", "sd", "skewness", "mode", "min", "max", "range"} <= channel.keys()
        assert {
            "lsl",
            "usl",
            "cp",
            "cpu",
            "cpl",
            "cpk",
            "cpk_lower",
            "cpk_upper",
            "cp_ci",
            "cpk_ci",
            "decision",
            "cp_within",
            "cpk_within",
            "threshold",
            "capable",
        } <= channel["capability"].keys()
        chart = channel["chart"]
        assert {"type", "subgroup", "center", "ucl", "lcl", "sigma_within"} <= chart.keys()
        assert set(chart["dispersion"]) == {"center", "ucl", "lcl"}
        assert isinstance(channel["alarms"], list)
    z = document["channels"]["z"]["capability"]
    assert (z["lsl"], z["usl"], z["cp"]) == (None, 0.002, None)  # one-sided: Cp undefined
    assert {"offset", "total_offset", "ap", "rp"} <= document["spatial"].keys()
    assert isinstance(document["hints"], list)


def test_without_limits_the_json_is_null_where_undefined():
    result = station(TABLE_2_1, "--json")
    assert result.returncode == 0, result.stderr
    document = json.loads(result.stdout)
    capability = document["channels"]["x"]["capability"]
    assert capability["cpk"] is None and capability["capable"] is None
    assert document["channels"]["x"]["chart"]["ucl"] is not None
    assert document["spatial"] is None


def test_fail_if_incapable_exits_1_and_names_the_channel(xyz_csv):
    result = station(xyz_csv, *REPORT_LIMITS, "--fail-if-incapable", "--json")
    assert result.returncode == 1
    assert json.loads(result.stdout)["channels"]["z"]["capability"]["capable"] is False
    # y's bounds straddle 1: it passes, and stderr says it passed without proof.
    assert result.stderr.strip().splitlines() == [
        "station: passed the capability check without proof: y (inconclusive: 57 readings "
        "would settle it); --fail-if-inconclusive fails it",
        "station: failed the capability check: z (not capable)",
    ]


def test_fail_if_incapable_passes_capable_data():
    result = station(TABLE_2_1, *REPORT_LIMITS, "--fail-if-incapable", "--capable-at", "0.85")
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""


def test_an_inconclusive_channel_passes_fail_if_incapable_and_fails_fail_if_inconclusive():
    result = station(TABLE_2_1, *REPORT_LIMITS, "--json", "--fail-if-incapable")
    assert result.returncode == 0
    capability = json.loads(result.stdout)["channels"]["x"]["capability"]
    assert capability["capable"] is True  # the report's own rule, unchanged
    assert capability["decision"] == {
        "rule": "bissell-one-sided-bounds",
        "verdict": "INCONCLUSIVE",
        "confidence": 0.95,
        "readings_needed": 77,
    }
    assert capability["cpk_upper"] == pytest.approx(1.4394, abs=1e-4)
    assert capability["cpk_ci"] == pytest.approx([0.8446, 1.4914], abs=1e-4)
    assert capability["cp_ci"] == pytest.approx([0.9410, 1.5884], abs=1e-4)
    assert "x (inconclusive: 77 readings would settle it)" in result.stderr
    strict = station(TABLE_2_1, *REPORT_LIMITS, "--fail-if-inconclusive")
    assert strict.returncode == 1
    assert strict.stderr.strip() == (
        "station: failed the capability check: x (inconclusive: 77 readings would settle it)"
    )


def test_a_higher_capability_threshold_fails_table_2_1():
    # Above the upper bound 1.44: NOT CAPABLE.
    result = station(TABLE_2_1, *REPORT_LIMITS, "--fail-if-incapable", "--capable-at", "1.5")
    assert result.returncode == 1
    assert "x (not capable)" in result.stderr


def test_subgroups_and_rule_sets_reach_the_analysis():
    result = station(TABLE_2_1, *REPORT_LIMITS, "--subgroup", "5", "--rules", "nelson", "--json")
    chart = json.loads(result.stdout)["channels"]["x"]["chart"]
    assert (chart["type"], chart["subgroup"]) == ("Xbar-R", 5)


BAD_INPUTS = {
    "missing file": (["no-such-file.csv"], "no such file"),
    "empty file": (["{empty}"], "is empty"),
    "non-numeric cell": (["{bad_cell}"], "line 4, column 'x': 'abc' is not a number"),
    "ragged row": (["{ragged}"], "line 3 has 3 cells but the header has 2 columns"),
    "nan cell": (["{nan_cell}"], "line 2, column 'y': 'nan' is not a finite number"),
    "duplicate column": (["{twice}"], "column 'x' appears twice"),
    "header only": (["{header_only}"], "has a header but no readings"),
    "not a session": (["{not_session}"], "other.jsonl is not a station session file"),
    "no channel column": (["{no_channel}"], "no channel columns"),
    "usl below lsl": (["{table}", "--lsl", "0.002", "--usl", "0.001"], "is not above lower"),
    "limit for an unknown channel": (["{table}", "--limit", "q=-1:1"], "channel 'q'"),
    "bad limit syntax": (["{table}", "--limit", "x-1:1"], "is not CH=LSL:USL"),
    "limit with text": (["{table}", "--limit", "x=a:1"], "is not a number"),
    "bad resolution": (["{table}", "--resolution", "-1"], "resolution"),
    "bad subgroup": (["{table}", "--subgroup", "two"], "--subgroup 'two'"),
    "bad threshold": (["{table}", "--capable-at", "x"], "--capable-at 'x'"),
}


@pytest.fixture
def bad_files(tmp_path) -> dict[str, Path]:
    return {
        "empty": write_csv(tmp_path, "empty.csv", "# only a comment\n\n"),
        "bad_cell": write_csv(tmp_path, "bad.csv", "# c\ncycle,x\n1,0.1\n2,abc\n"),
        "ragged": write_csv(tmp_path, "ragged.csv", "cycle,x\n1,0.1\n2,0.2,0.3\n"),
        "no_channel": write_csv(tmp_path, "t.csv", "cycle,T\n1,2\n"),
        "nan_cell": write_csv(tmp_path, "nan.csv", "x,y\n1,nan\n"),
        "twice": write_csv(tmp_path, "twice.csv", "x,x\n1,2\n"),
        "header_only": write_csv(tmp_path, "header.csv", "# c\ncycle,x\n"),
        "not_session": write_csv(tmp_path, "other.jsonl", '{"format": "other/1"}\n'),
        "table": TABLE_2_1,
    }


@pytest.mark.parametrize("case", sorted(BAD_INPUTS))
def test_bad_input_exits_2_with_one_line(case, bad_files, capsys):
    # In-process through the same entry point as the console script (cheap enough to cover
    # every case); the subprocess test below checks a few through the installed script.
    from station.cli import main

    arguments, message = BAD_INPUTS[case]
    code = main(["analyze", *(argument.format(**bad_files) for argument in arguments)])
    out, err = capsys.readouterr()
    assert code == 2, out + err
    assert out == ""
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("station: "), err
    assert message in lines[0]


@pytest.mark.parametrize("case", ["missing file", "non-numeric cell", "usl below lsl"])
def test_bad_input_through_the_console_script(case, bad_files):
    arguments, message = BAD_INPUTS[case]
    result = station(*(argument.format(**bad_files) for argument in arguments))
    assert result.returncode == 2, result.stdout + result.stderr
    assert result.stdout == ""
    assert result.stderr.count("\n") == 1 and message in result.stderr


def test_a_session_file_is_analysed_without_its_rejected_cycles(tmp_path):
    from station.session.journal import SessionWriter

    rng = np.random.default_rng(9)
    header = {
        "robot": "cell-3",
        "procedure": {"id": "repeatability", "version": "1", "sha256": "0" * 64},
        "channels": ["x", "y", "z"],
        "unit": "in",
        "resolution": 0.0001,
        "limits": {axis: {"lsl": -0.001, "usl": 0.001, "nominal": 0.0} for axis in "xyz"},
    }
    with SessionWriter.create(tmp_path, header) as writer:
        for cycle in range(1, 31):
            values = np.round(rng.normal(0, 0.0002, 3), 4)
            if cycle == 7:
                values[0] = 0.05  # a bumped indicator, rejected below
            readings = {axis: {"value": float(v)} for axis, v in zip("xyz", values, strict=True)}
            writer.append("reading", cycle=cycle, channels=readings)
        writer.append("reject", cycle=7, reason="fixture bumped")
        path = writer.path
    result = station(path, "--json")
    assert result.returncode == 0, result.stderr
    document = json.loads(result.stdout)
    assert document["excluded_cycles"] == [7]
    assert document["channels"]["x"]["n"] == 29
    assert document["channels"]["x"]["max"] < 0.01
    assert document["channels"]["x"]["capability"]["usl"] == 0.001  # the session's limits
    assert document["unit"] == "in" and document["resolution"] == 0.0001
    text = station(path).stdout
    assert "Excluded (rejected) cycles: 7" in text and "Last line hash" in text


def _pieces(text: str) -> dict[int, str]:
    """PIECE -> MEASUREMENT of the first channel's readings block of a text report."""
    lines = text.splitlines()
    start = next(i for i, line in enumerate(lines) if "PIECE  MEASUREMENT" in line) + 1
    block = lines[start : lines.index("", start)]
    cells = " ".join(block).split()
    return {int(cells[i]): cells[i + 1] for i in range(0, len(cells) - 1, 2)}


def test_pieces_and_alarms_are_named_by_cycle_number(tmp_path):
    """Review finding 9: with cycle 3 rejected, the outlier of cycle 7 was "PIECE 6", its
    alarm "point 6" and the hint "report-1 at point 6"."""
    from station.session.journal import SessionWriter

    header = {
        "robot": "cell-3",
        "procedure": {"id": "repeatability", "version": "1", "sha256": "0" * 64},
        "channels": ["x"],
        "unit": "in",
        "resolution": 0.0001,
        "limits": {"x": {"lsl": -0.01, "usl": 0.01, "nominal": 0.0}},
    }
    values = [0.0001, -0.0001, 0.0002, 0.0, 0.0001, -0.0002, 0.0060] + [0.0001, -0.0001] * 10
    with SessionWriter.create(tmp_path, header) as writer:
        for cycle, value in enumerate(values, start=1):
            writer.append("reading", cycle=cycle, channels={"x": {"value": value}})
        writer.append("reject", cycle=3, reason="fixture bumped")
        path = writer.path
    document = json.loads(station(path, "--json").stdout)
    x = document["channels"]["x"]
    assert x["cycles"] == [1, 2, *range(4, len(values) + 1)]
    (alarm,) = [a for a in x["alarms"] if a["rule"] == "report-1"]
    assert alarm["points"] == [6] and alarm["cycles"] == [7]
    assert alarm["text"].startswith("Cycle 7 is above the upper control limit")
    assert any(
        "report rule 1 (a point beyond the control limits) at cycle 7;" in hint
        for hint in document["hints"]
    )

    text = station(path).stdout
    pieces = _pieces(text)
    assert 3 not in pieces and pieces[7] == "+0.00600" and pieces[6] == "-0.00020"
    flat = " ".join(text.split())
    assert "report rule 1 (a point beyond the control limits) [" in flat
    assert "]: Cycle 7 is above" in flat


def test_a_csv_cycle_column_numbers_the_readings(tmp_path):
    rows = ["cycle,x"] + [f"{10 + n},{v}" for n, v in enumerate([0.0, 0.1, -0.1] * 8 + [9.0])]
    path = write_csv(tmp_path, "numbered.csv", "\n".join(rows) + "\n")
    document = json.loads(station(path, "--json").stdout)
    assert document["channels"]["x"]["cycles"] == list(range(10, 35))
    (alarm,) = document["channels"]["x"]["alarms"]
    assert alarm["cycles"] == [34] and alarm["text"].startswith("Cycle 34 ")
    # No gauge step given: every figure at six decimals (the one format's rule for an unknown
    # step), as station analyze --resolution 0.1 would write +9.00.
    assert _pieces(station(path).stdout)[34] == "+9.000000"
    assert _pieces(station(path, "--resolution", "0.1").stdout)[34] == "+9.00"
    unnumbered = write_csv(
        tmp_path, "plain.csv", "x\n" + "\n".join(r.split(",")[1] for r in rows[1:])
    )
    plain = json.loads(station(unnumbered, "--json").stdout)["channels"]["x"]
    # Cycles 1 to n in order are not listed (issue 12: no per-point arrays that say 1..n).
    assert "cycles" not in plain and plain["alarms"][0]["cycles"] == [25]
    bad = write_csv(tmp_path, "bad.csv", "cycle,x\n1,0.1\n2.5,0.2\n")
    result = station(bad)
    assert result.returncode == 2 and "'2.5' is not a cycle number" in result.stderr
