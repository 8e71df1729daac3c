"""`station analyze FILE --procedure positioning` on a CSV of approaches (``target,direction,
cycle`` and ``actual`` or ``deviation``): the ISO 230-2 figures of tests/methods'
hand-checked set A, as JSON and as the text report, and a one-line error for each bad table."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from helpers import run_station

# Set A of tests/methods/test_positioning_iso230.py: targets 0, 100, 200; per target the five
# approaches up and down about their means (see there for every figure worked out by hand).
SET_A = {
    (0, "up"): (1, 1, 2, 3, 3),
    (0, "down"): (-2, -2, -1, 0, 0),
    (100, "up"): (4.5, 4.5, 5, 5.5, 5.5),
    (100, "down"): (3.5, 3.5, 4, 4.5, 4.5),
    (200, "up"): (-0.5, -0.5, 1, 2.5, 2.5),
    (200, "down"): (3, 3, 3, 3, 3),
}
FIGURES = {
    "B": 3.0, "B_mean": 2 / 3, "R": 7.0, "R_up": 6.0, "R_down": 4.0, "E": 6.0, "E_up": 4.0,
    "E_down": 5.0, "M": 4.0, "A": 9.0, "A_up": 8.0, "A_down": 8.0,
}  # fmt: skip


def write(path: Path, *, actual: bool = False, signs: bool = False, extra: str = "") -> Path:
    """Set A as a CSV: deviations, or the actual positions (target + deviation); directions
    as words or as + and -; ``extra`` rows appended."""
    lines = [
        "# set A, hand-checked",
        f"target,direction,cycle,{'actual' if actual else 'deviation'}",
    ]
    for (target, direction), values in SET_A.items():
        word = {"up": "+", "down": "-"}[direction] if signs else direction
        for cycle, value in enumerate(values, start=1):
            lines.append(f"{target},{word},{cycle},{target + value if actual else value}")
    path.write_text("\n".join(lines) + "\n" + extra)
    return path


def analyze(*args: str | Path):
    return run_station("analyze", *args)


def one_line(done) -> str:
    assert done.returncode == 2, done.stdout
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("station: "), done.stderr
    return lines[0]


@pytest.mark.parametrize(("actual", "signs"), [(False, False), (True, True)])
def test_the_json_document_holds_every_figure(tmp_path: Path, actual: bool, signs: bool):
    table = write(tmp_path / "axis.csv", actual=actual, signs=signs)
    done = analyze(table, "--procedure", "positioning", "--json")
    assert done.returncode == 0, done.stderr
    document = json.loads(done.stdout)
    assert document["procedure"] == "positioning" and "channels" not in document
    figures = document["iso230_2"]
    for name, value in FIGURES.items():
        assert figures[name] == pytest.approx(value), name
    targets = figures["targets"]
    assert [t["target"] for t in targets] == [0, 100, 200]
    assert set(targets[0]) >= {
        "target", "mean_up", "mean_down", "s_up", "s_down", "reversal", "R",
    }  # fmt: skip
    assert [t["R"] for t in targets] == pytest.approx([7, 3, 6])
    assert [t["reversal"] for t in targets] == pytest.approx([3, 1, -2])


def test_the_text_report(tmp_path: Path):
    table = write(tmp_path / "axis.csv")
    done = analyze(
        table, "--procedure", "positioning", "--unit", "mm", "--resolution", "0.001",
        "--fail-if-incapable",
    )  # fmt: skip
    # ISO 230-2 states figures, not a verdict: asked for one, the command says it has none.
    assert done.returncode == 1
    assert "positioning (no verdict: it judges no readings)" in done.stderr
    text = done.stdout
    assert text.startswith("AXIS POSITIONING REPORT (ISO 230-2) ON axis.csv")
    assert "AXIS POSITIONING (ISO 230-2): 3 targets, 30 approaches" in text
    assert "       100    +5.0000    +4.0000    0.5000    0.5000    +1.0000    3.0000" in text
    assert "R = 7.0000  repeatability, the largest R_i (at 0: 2s↑ + 2s↓ + |B_i|)" in text
    assert "E = 6.0000  systematic error (mean 100↑ - mean 0↓)" in text
    assert "A = 9.0000  accuracy (mean+2s 100↑ - mean-2s 0↓)" in text
    assert all(len(line) <= 80 for line in text.splitlines())


def test_a_target_approached_from_one_direction_only(tmp_path: Path):
    table = write(tmp_path / "axis.csv")
    kept = [line for line in table.read_text().splitlines() if not line.startswith("200,down")]
    table.write_text("\n".join(kept) + "\n")
    line = one_line(analyze(table, "--procedure", "positioning"))
    assert "target 200 is approached up only, never down" in line


def test_fewer_than_two_approaches(tmp_path: Path):
    table = write(tmp_path / "axis.csv")
    lines = table.read_text().splitlines()
    kept = [ln for ln in lines if not ln.startswith("0,up,") or ln.startswith("0,up,1,")]
    table.write_text("\n".join(kept) + "\n")
    assert "target 0 has 1 approach up" in one_line(analyze(table, "--procedure", "positioning"))


def test_a_text_cell_names_its_line_and_column(tmp_path: Path):
    table = write(tmp_path / "axis.csv", extra="100,up,6,n/a\n")
    line = one_line(analyze(table, "--procedure", "positioning"))
    assert "axis.csv: line 33, column 'deviation': 'n/a' is not a number" in line
    table = write(tmp_path / "axis.csv", extra="100,sideways,6,4\n")
    line = one_line(analyze(table, "--procedure", "positioning"))
    assert "line 33, column 'direction': 'sideways' is not up, down, + or -" in line


def test_missing_columns_are_named(tmp_path: Path):
    table = tmp_path / "axis.csv"
    table.write_text("target,actual\n0,0.1\n")
    line = one_line(analyze(table, "--procedure", "positioning"))
    assert (
        "needs the columns target, direction and actual (or deviation); missing direction" in line
    )
    table.write_text("target,direction,cycle\n0,up,1\n")
    line = one_line(analyze(table, "--procedure", "positioning"))
    assert "missing actual (or deviation) (it has target, direction)" in line
    table.write_text("direction,cycle\nup,1\n")
    line = one_line(analyze(table, "--procedure", "positioning"))
    assert "no channel columns in the header 'direction,cycle'" in line
    table.write_text("target,direction,x\n0,up,1\n")
    assert "missing actual (or deviation)" in one_line(analyze(table, "--procedure", "positioning"))
    table.write_text("target,direction,actual,deviation\n0,up,1,1\n")
    assert "both an actual and a deviation column" in one_line(
        analyze(table, "--procedure", "positioning")
    )


def test_an_approach_given_twice_in_one_cycle_is_refused(tmp_path: Path):
    table = write(tmp_path / "axis.csv", extra="0,down,3,0.5\n")
    line = one_line(analyze(table, "--procedure", "positioning"))
    assert "target 0 is approached down twice in cycle 3 (lines 10 and 33)" in line


def test_words_are_read_only_for_the_method_that_reads_them(tmp_path: Path):
    """Without --procedure positioning the direction column is no channel of words: a cell
    that is not a number, as before."""
    table = write(tmp_path / "axis.csv")
    line = one_line(analyze(table))
    assert "line 3, column 'direction': 'up' is not a number" in line
