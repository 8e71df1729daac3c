"""``station budget``: the budget file read, evaluated and judged; its JSON; bad input refused in
one line."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from helpers import run_station

HAND_BUDGET = """
unit = "mm"
confidence = 0.95

[[input]]
name = "repeatability"
readings = [1, 2, 3, 4, 5]

[[input]]
name = "resolution"
half_width = 0.3
distribution = "rectangular"

[[input]]
name = "certificate"
expanded = 0.4
k = 2
dof = 10

[[input]]
name = "temperature"
u = 0.05
sensitivity = -4

[[input]]
name = "triangle"
half_width = 0.6
distribution = "triangular"

[[input]]
name = "cycling"
half_width = 0.2
distribution = "arcsine"
"""
"""u_c² = 0.5 + 0.03 + 0.04 + 0.04 + 0.06 + 0.02 = 0.69; ν_eff = 0.4761/0.06266 = 7.6; k = t(7)."""


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "budget.toml"
    path.write_text(text, encoding="utf-8")
    return path


def test_json_shape_and_figures(tmp_path):
    path = write(tmp_path, HAND_BUDGET)
    done = run_station(
        "budget", path, "--lsl", "-3", "--usl", "3", "--value", "0", "--value", "-1.5", "--json"
    )
    assert done.returncode == 1, done.stderr  # -1.5 is not proven inside
    document = json.loads(done.stdout)
    assert {"u_c", "nu_eff", "k", "U", "contributions", "acceptance_zone", "decisions"} <= set(
        document
    )
    assert document["u_c"] == pytest.approx(math.sqrt(0.69))
    assert document["nu_eff"] == pytest.approx(0.4761 / 0.06266)
    assert document["k"] == pytest.approx(2.3646, abs=1e-4)  # the file's confidence, t at 7
    u_expanded = document["k"] * math.sqrt(0.69)
    assert document["U"] == pytest.approx(u_expanded)
    first, second = document["contributions"][:2]
    assert set(first) == {"name", "u", "sensitivity", "ui", "dof", "share"}
    assert first["name"] == "repeatability" and first["dof"] == 4
    assert first["share"] == pytest.approx(0.5 / 0.69)
    assert second["dof"] is None  # ∞: JSON has no infinity
    temperature = document["contributions"][3]
    assert (temperature["sensitivity"], temperature["ui"]) == pytest.approx((-4, 0.2))
    assert document["acceptance_zone"] == pytest.approx([-3 + u_expanded, 3 - u_expanded])
    assert [d["verdict"] for d in document["decisions"]] == ["PASS", "INDETERMINATE"]
    assert [d["value"] for d in document["decisions"]] == [0, -1.5]
    assert 0 < document["decisions"][1]["p_conformance"] < 1


def test_k_on_the_command_line_overrides_the_file(tmp_path):
    path = write(tmp_path, HAND_BUDGET)
    document = json.loads(run_station("budget", path, "--k", "3", "--json").stdout)
    assert document["k"] == 3
    assert document["confidence"] is None
    assert document["acceptance_zone"] is None and document["decisions"] == []
    document = json.loads(run_station("budget", path, "--confidence", "0.99", "--json").stdout)
    assert document["k"] == pytest.approx(3.4995, abs=1e-4)  # t(0.995, 7)


def test_text_output_and_exit_codes(tmp_path):
    path = write(tmp_path, "[[input]]\nname = 'gauge'\nexpanded = 0.25\nk = 2\n")
    done = run_station("budget", path, "--lsl=-1", "--usl", "1", "--value", "0.75")
    assert done.returncode == 0, done.stderr
    assert "gauge" in done.stdout
    assert "u_c = 0.125, nu_eff = inf" in done.stdout
    assert "k = 2, U = 0.25" in done.stdout
    assert "acceptance zone (guarded): [-0.75, 0.75]" in done.stdout
    assert "0.75: PASS (probability of conformance 0.9772)" in done.stdout
    fail = run_station("budget", path, "--lsl", "-1", "--usl", "1", "--value", "1.3")
    assert fail.returncode == 1 and "1.3: FAIL" in fail.stdout
    simple = run_station(
        "budget", path, "--lsl", "-1", "--usl", "1", "--value", "1", "--rule", "simple"
    )
    assert simple.returncode == 0 and "1: PASS" in simple.stdout
    overlap = run_station("budget", path, "--lsl", "0", "--usl", "0.4", "--value", "0.2")
    assert overlap.returncode == 1
    assert "no value can pass by guarded acceptance" in overlap.stdout
    assert "0.2: INDETERMINATE" in overlap.stdout


ONE = "[[input]]\nname = 'cal'\n"


@pytest.mark.parametrize(
    ("text", "options", "words"),
    [
        (ONE + "u = -0.1\n", (), "input 'cal': u must be a finite number 0 or more"),
        (ONE + "u = nan\n", (), "input 'cal': u is NaN"),
        (ONE + "u = inf\n", (), "input 'cal': u must be a finite number"),
        (ONE + "expanded = 0.1\nk = 0\n", (), "input 'cal': k must be a finite number above 0"),
        (ONE + "expanded = 0.1\nk = inf\n", (), "input 'cal': k must be a finite number above 0"),
        (ONE + "expanded = 0.1\n", (), "input 'cal': an expanded uncertainty needs its"),
        (
            ONE + "half_width = 0.1\ndistribution = 'gaussian'\n",
            (),
            "input 'cal': distribution 'gaussian' is not one of rectangular",
        ),
        (ONE + "half_width = 0.1\n", (), "input 'cal': a half_width needs its 'distribution'"),
        (ONE + "u = 0.1\nsensitivity = 'two'\n", (), "input 'cal': sensitivity must be a number"),
        (ONE + "u = 0.1\nsensitivity = nan\n", (), "input 'cal': sensitivity is NaN"),
        (ONE + "u = 0.1\nexpanded = 0.2\nk = 2\n", (), "input 'cal': give exactly one of"),
        (ONE + "readings = [1.0]\n", (), "input 'cal': readings need at least 2 values"),
        (ONE + "readings = [1.0, 2.0]\ndof = 3\n", (), "readings give their own dof"),
        (ONE + "u = 0.1\nsensitvity = 2\n", (), "input 'cal': unknown key 'sensitvity'"),
        ("[[input]]\nu = 0.1\n", (), "input 1 has no 'name'"),
        ("unit = 'mm'\n", (), "no [[input]] tables"),
        ("k = 0\n" + ONE + "u = 0.1\n", (), "'k' must be a finite number above 0"),
        ("confidence = 95\n" + ONE + "u = 0.1\n", (), "'confidence' must be a probability"),
        ("[[input]\n", (), "is not valid TOML"),
        ("a = " + "[" * 50_000 + "]" * 50_000 + "\n", (), "nests arrays or tables too deeply"),
        (ONE + "u = 0.1\n", ("--lsl", "1", "--usl", "0"), "the LSL 1 is not below the USL 0"),
        (ONE + "u = 0.1\n", ("--lsl", "1", "--usl", "1"), "the LSL 1 is not below the USL 1"),
        (ONE + "u = 0.1\n", ("--k", "0"), "--k must be a finite number above 0"),
        (ONE + "u = 0.1\n", ("--k", "inf"), "--k 'inf' is not a finite number"),
        (ONE + "u = 0.1\n", ("--confidence", "1.5"), "--confidence must be a probability"),
        (ONE + "u = 0.1\n", ("--value", "0.1"), "--value needs limits"),
        (ONE + "u = 0.1\n", ("--usl", "1", "--value", "x"), "--value 'x' is not a number"),
    ],
)
def test_bad_input_is_refused_in_one_line_naming_it(tmp_path, text, options, words):
    path = write(tmp_path, text)
    done = run_station("budget", path, *options)
    assert done.returncode == 2, done.stdout
    assert done.stdout == ""
    assert done.stderr.count("\n") == 1, done.stderr
    assert done.stderr.startswith("station: ")
    assert words in done.stderr


def test_a_file_that_is_not_text_is_one_line(tmp_path):
    path = tmp_path / "budget.toml"
    path.write_bytes(b"\xff\xfe[[input]]")
    done = run_station("budget", path)
    assert done.returncode == 2
    assert done.stderr.count("\n") == 1 and "is not UTF-8 text" in done.stderr


def test_a_missing_file_is_one_line(tmp_path):
    done = run_station("budget", tmp_path / "absent.toml")
    assert done.returncode == 2
    assert done.stderr.count("\n") == 1 and "no such file" in done.stderr


def test_the_readme_example_runs(tmp_path):
    """The budget example of station/analysis/README.md (it was in the top-level README)."""
    root = Path(__file__).resolve().parents[2]
    readme = (root / "station" / "analysis" / "README.md").read_text(encoding="utf-8")
    section = readme.split("station budget FILE.toml", 1)[1]
    example = section.split("```toml\n", 1)[1].split("```", 1)[0]
    document = json.loads(run_station("budget", write(tmp_path, example), "--json").stdout)
    # 0.00005/√3 and 0.00004/2: u_c = √(8.33e-10 + 4e-10) = 3.51e-5 in, both lines ν = ∞.
    assert document["u_c"] == pytest.approx(math.sqrt(0.00005**2 / 3 + 0.00002**2))
    assert document["nu_eff"] is None
    assert document["k"] == pytest.approx(1.96, abs=1e-3)
    assert document["unit"] == "in"
