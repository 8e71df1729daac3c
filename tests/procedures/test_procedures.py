"""Procedures as data: validation names the file, the step and the fault; discovery; the wheel."""

from __future__ import annotations

import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy
import pytest
from helpers import CHECK_STEP as CHECK
from helpers import PROBE_HEAD as HEAD
from helpers import write_procedure as write

from station.errors import StationError
from station.procedures import (
    builtin_procedures_dir,
    discover_procedures,
    load_procedure,
)

REPO = Path(__file__).resolve().parents[2]


def test_the_builtin_repeatability_procedure_loads() -> None:
    procedure = load_procedure(builtin_procedures_dir() / "repeatability.toml")
    assert procedure.id == "repeatability" and procedure.report_section == "2.6"
    assert procedure.channels == ("x", "y", "z") and procedure.unit == "in"
    assert procedure.resolution == 0.0001
    assert (procedure.cycles_min, procedure.cycles_target) == (25, 30)
    assert {ch: (lim.lsl, lim.usl) for ch, lim in procedure.limits.items()} == {
        ch: (-0.001, 0.001) for ch in "xyz"
    }
    kinds = [step.kind for step in procedure.steps]
    assert kinds.count("zero") == 1 and kinds[-1] == "cycles"
    assert kinds.index("zero") < kinds.index("cycles")
    cycles = procedure.steps[-1]
    assert (cycles.count_min, cycles.count_target) == (25, 30)
    assert cycles.prompt_for(7, 30).startswith("Cycle 7 of 30:")
    text = " ".join(step.text for step in procedure.steps).lower()
    for phrase in ("surface plate", "blunt", "3/8", "position a", "one inch", "position b"):
        assert phrase in text
    assert len(procedure.sha256) == 64


def test_every_builtin_procedure_loads_and_follows_a_report_section() -> None:
    catalog = discover_procedures(use_env=False)
    assert not catalog.errors
    assert set(catalog.ids()) == {p.stem for p in builtin_procedures_dir().glob("*.toml")}
    accuracy = catalog.get("relative_accuracy")
    assert accuracy.report_section == "2.8.2"
    (block,) = (step for step in accuracy.steps if step.kind == "repeat")
    assert (block.label, block.count_min, block.count_target) == ("placement", 3, 5)
    assert [f.label for f in accuracy.step("pendant").fields] == [
        "Pendant X",
        "Pendant Y",
        "Pendant Z",
    ]
    assert [s.kind for s in block.steps].count("capture") == 1


def test_inline_procedure_with_every_step_kind(tmp_path: Path) -> None:
    path = write(
        tmp_path,
        """
        id = "everything"
        title = "All kinds"
        version = "0.1"
        report_section = "2.8.2"
        channels = ["h", "v", "s"]
        unit = "mm"
        resolution = 0.001
        [cycles]
        target = 10
        [limits]
        h = [-0.02, 0.02]
        v = { lsl = -0.01, usl = 0.03, nominal = 0.01 }
        [[steps]]
        id = "ok"
        kind = "check"
        title = "Check"
        [[steps]]
        id = "pendant"
        kind = "input"
        title = "Read the pendant"
        fields = [
          { name = "x", label = "Pendant X", unit = "mm" },
          { name = "who", type = "text", required = false },
        ]
        [[steps]]
        id = "zero"
        kind = "zero"
        title = "Zero"
        channels = ["h", "v"]
        [[steps]]
        id = "one"
        kind = "capture"
        title = "One reading set"
        [[steps]]
        id = "cycles"
        kind = "cycles"
        title = "Cycles"
        [[steps]]
        id = "stroke"
        kind = "stroke"
        title = "Shuttle"
        channels = ["h", "v", "s"]
        direction_channel = "s"
        min = 25
        target = 30
        [[steps]]
        id = "placements"
        kind = "repeat"
        title = "Per placement"
        label = "placement"
        min = 3
        target = 5
        [[steps.steps]]
        id = "place"
        kind = "check"
        title = "Place the fixtures"
        [[steps.steps]]
        id = "read"
        kind = "capture"
        title = "Read"
        """,
    )
    procedure = load_procedure(path)
    assert [s.kind for s in procedure.all_steps()] == [
        *("check", "input", "zero", "capture", "cycles", "stroke", "repeat"),
        "check",
        "capture",
    ]
    assert (procedure.cycles_min, procedure.cycles_target) == (10, 10)
    assert procedure.limits["v"].nominal == 0.01 and procedure.limits["h"].nominal == 0.0
    fields = procedure.step("pendant").fields
    assert (fields[0].label, fields[0].type, fields[0].required) == ("Pendant X", "number", True)
    assert (fields[1].label, fields[1].type, fields[1].required) == ("who", "text", False)
    assert procedure.step("zero").channels == ("h", "v")
    assert procedure.step("one").channels == ("h", "v", "s")
    assert (procedure.step("cycles").count_min, procedure.step("cycles").count_target) == (10, 10)
    assert procedure.step("stroke").direction_channel == "s"
    repeat = procedure.step("placements")
    assert (repeat.label, repeat.count_min, repeat.count_target) == ("placement", 3, 5)
    assert [s.number for s in repeat.steps] == ["7.1", "7.2"]
    with pytest.raises(StationError, match="no step 'nope'"):
        procedure.step("nope")


FAULTS = [
    (HEAD + CHECK + "color = 'red'\n", "", "unknown key(s) 'color'"),
    (HEAD.replace('title = "Probe"\n', "") + CHECK, "", "missing required key 'title'"),
    (HEAD.replace("resolution = 0.0001", "resolution = '0.1'") + CHECK, "", "'resolution' must be"),
    (HEAD.replace('version = "1"', "version = 1"), "", "'version' must be a string"),
    (HEAD + "[cycles]\nmin = 30\ntarget = 25\n" + CHECK, r"\[cycles\]", "min 30 is more than"),
    (HEAD + "[limits]\nx = [0.001, -0.001]\n" + CHECK, r"\[limits\] x", "impossible limits"),
    (HEAD + "[limits]\nq = [0, 1]\n" + CHECK, r"\[limits\]", "unknown key(s) 'q'"),
    (HEAD + "[limits]\ntolerance = -1\n" + CHECK, r"\[limits\]", "greater than 0"),
    (HEAD, "", "missing required key 'steps'"),
    (HEAD + CHECK + CHECK, r"step 2 \(first\)", "duplicate step id 'first' (also step 1)"),
    (HEAD + CHECK.replace("check", "dance"), r"step 1 \(first\)", "unknown step kind 'dance'"),
    (
        HEAD + CHECK.replace('kind = "check"', 'kind = "check"\nwho = 1'),
        r"step 1 \(first\)",
        "'who'",
    ),
    (HEAD + CHECK.replace('title = "First"', ""), r"step 1 \(first\)", "missing required key"),
    (HEAD + CHECK.replace('"check"', '"zero"\nchannels = ["x", "w"]'), r"step 1", "channel(s) w"),
    (
        HEAD + CHECK.replace('"check"', '"cycles"\nmin = 9\ntarget = 3'),
        r"step 1 \(first\)",
        "min 9 is more than target 3",
    ),
    (
        HEAD + CHECK.replace('"check"', '"stroke"\ndirection_channel = "s"'),
        r"step 1 \(first\)",
        "direction_channel 's' is not one of",
    ),
    (
        HEAD + CHECK.replace('"check"', '"input"'),
        r"step 1 \(first\)",
        "missing required key 'fields'",
    ),
    (
        HEAD + CHECK.replace('"check"', '"input"\nfields = [{ name = "a", type = "date" }]'),
        r"step 1 \(first\), field 1",
        "'type' must be 'number' or 'text'",
    ),
    (
        HEAD
        + CHECK.replace('"check"', '"repeat"\ntarget = 2')
        + '[[steps.steps]]\nid = "in"\nkind = "repeat"\ntitle = "x"\ntarget = 2\n',
        r"step 1\.1 \(in\)",
        "cannot hold another repeat",
    ),
    (
        HEAD
        + CHECK.replace('"check"', '"repeat"\ntarget = 2')
        + CHECK.replace("[[steps]]", "[[steps.steps]]"),
        r"step 1\.1 \(first\)",
        "duplicate step id 'first' (also step 1)",
    ),
    (HEAD + CHECK.replace('id = "first"', 'id = "../x"'), "step 1", "may hold only"),
    (HEAD + CHECK + "[[steps]]\nkind = 'check'\n", "step 2", "missing required key 'id'"),
    ("id = \n", "", "is not valid TOML"),
]


@pytest.mark.parametrize(("text", "where", "fault"), FAULTS)
def test_each_fault_names_the_file_the_step_and_what_is_wrong(
    tmp_path: Path, text: str, where: str, fault: str
) -> None:
    path = write(tmp_path, text)
    with pytest.raises(StationError) as caught:
        load_procedure(path)
    message = caught.value.message
    assert message.startswith(f"procedure file {path}: ")
    assert fault in message
    if where:
        assert pytest.importorskip("re").search(where, message), message


def test_a_missing_procedure_file_is_a_station_error(tmp_path: Path) -> None:
    with pytest.raises(StationError, match="does not exist"):
        load_procedure(tmp_path / "none.toml")


def test_a_site_procedure_overrides_the_builtin_one_and_says_so(tmp_path, monkeypatch) -> None:
    builtin = (builtin_procedures_dir() / "repeatability.toml").read_text()
    site = tmp_path / "site"
    site.mkdir()
    (site / "ours.toml").write_text(builtin.replace('version = "1.0"', 'version = "site-7"'))
    (site / "broken.toml").write_text("id = 'broken'\n")
    monkeypatch.delenv("STATION_PROCEDURES", raising=False)
    plain = discover_procedures()
    assert plain.is_builtin("repeatability") and plain.origin("repeatability") == "built-in"
    catalog = discover_procedures([site])
    assert catalog.get("repeatability").version == "site-7"
    assert catalog.origin("repeatability") == "site, overrides built-in"
    assert any("overrides built-in" in note for note in catalog.notes)
    assert any("broken.toml" in error for error in catalog.errors)
    with pytest.raises(StationError, match="known procedures: .*repeatability"):
        catalog.get("nope")
    monkeypatch.setenv("STATION_PROCEDURES", f"{tmp_path / 'empty'}")
    with pytest.raises(StationError, match="does not exist"):
        discover_procedures()
    (tmp_path / "empty").mkdir()
    monkeypatch.setenv("STATION_PROCEDURES", f"{tmp_path / 'empty'}:{site}")
    assert discover_procedures().get("repeatability").version == "site-7"


@pytest.mark.slow  # builds the wheel
def test_a_wheel_carries_the_builtin_procedures(tmp_path: Path) -> None:
    # Build from a copy so the build's own files never touch the working tree.
    source = tmp_path / "src"
    shutil.copytree(
        REPO,
        source,
        ignore=shutil.ignore_patterns(".venv", ".git", "__pycache__", "*.egg-info", "build", ".*"),
    )
    built = subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "wheel",
            "--no-deps",
            "-w",
            str(tmp_path / "dist"),
            str(source),
        ],
        capture_output=True,
        text=True,
        timeout=240,
    )
    offline = ("Could not find a version", "No matching distribution", "NewConnectionError")
    if built.returncode and any(sign in built.stderr for sign in offline):
        pytest.skip("building a wheel needs setuptools and wheel from the package index (offline)")
    assert built.returncode == 0, built.stderr[-2000:]
    (wheel,) = (tmp_path / "dist").glob("station-*.whl")
    names = zipfile.ZipFile(wheel).namelist()
    shipped = {Path(n).name for n in names if n.startswith("station/builtin_procedures/")}
    expected = {p.name for p in (REPO / "procedures").glob("*.toml")}
    assert "repeatability.toml" in shipped and expected <= shipped
    # Every package of the source tree is in the wheel (a package split out of a module must
    # also be named in pyproject.toml's list, or an installed station cannot import it).
    packages = {
        str(init.parent.relative_to(REPO)) for init in (REPO / "station").rglob("__init__.py")
    }
    missing = {package for package in packages if f"{package}/__init__.py" not in names}
    assert not missing, f"not in the wheel: {sorted(missing)}"

    # Installed from the wheel alone (no checkout beside it), the procedures are still found.
    # Without site (so no editable install of the checkout), the dependencies' folder is added
    # after the wheel's: the methods that procedure files name import numpy.
    target = tmp_path / "installed"
    zipfile.ZipFile(wheel).extractall(target)
    dependencies = str(Path(numpy.__file__).resolve().parent.parent)
    probe = (
        "import sys; sys.path.insert(0, sys.argv[1]); sys.path.append(sys.argv[2]); "
        "import station.methods; "
        "from station.procedures import builtin_procedures_dir, discover_procedures; "
        "print(builtin_procedures_dir()); print(*discover_procedures(use_env=False).ids()); "
        "print(station.methods.__file__)"
    )
    found = subprocess.run(
        [sys.executable, "-S", "-c", probe, str(target), dependencies],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        timeout=60,
    )
    assert found.returncode == 0, found.stderr
    folder, ids, methods = found.stdout.splitlines()
    assert Path(folder) == target / "station" / "builtin_procedures"
    assert Path(methods).is_relative_to(target)
    assert "repeatability" in ids.split()


# Review finding 17: the analysis a procedure's sessions get is declared, not guessed from its id.
REPEAT = """
[[steps]]
id = "place"
kind = "repeat"
title = "Place"
target = 3

[[steps.steps]]
id = "grab"
kind = "capture"
title = "Grab"
"""
STROKE = CHECK.replace('kind = "check"', 'kind = "stroke"\ndirection_channel = "z"')


def test_the_analysis_kind_defaults_by_step_kinds(tmp_path: Path) -> None:
    assert load_procedure(write(tmp_path, HEAD + CHECK)).analysis == "repeatability"
    assert load_procedure(write(tmp_path, HEAD + REPEAT)).analysis == "relative_accuracy"
    assert load_procedure(write(tmp_path, HEAD + STROKE)).analysis == "linearity"
    builtin = discover_procedures(use_env=False)
    assert {p.id: p.analysis for p in builtin.procedures} == {
        "repeatability": "repeatability",
        "relative_accuracy": "relative_accuracy",
        "linearity": "linearity",
        "gauge_check": "gauge_check",
        "gauge_linearity": "gauge_linearity",
        "gage_rr": "gage_rr",
        "joint_troubleshooting": "joint_troubleshooting",
        "gain_schedule": "gain_schedule",
        "positioning": "positioning",
        "pose_characteristics": "pose_characteristics",
        "stabilisation": "stabilisation",
    }


def test_a_declared_analysis_kind_is_kept_and_validated(tmp_path: Path) -> None:
    declared = HEAD.replace('unit = "in"', 'unit = "in"\nanalysis = "repeatability"')
    assert load_procedure(write(tmp_path, declared + REPEAT)).analysis == "repeatability"
    for kind, body, fault in (
        ("accuracy", CHECK, "'analysis' must be one of repeatability, relative_accuracy, "),
        ("linearity", CHECK, "'analysis' linearity needs a stroke step"),
        ("relative_accuracy", CHECK, "'analysis' relative_accuracy needs a repeat block"),
        # A parts step outside a block is no trial: the study needs one per appraiser in it.
        ("gage_rr", REPEAT, r"'analysis' gage_rr needs a repeat block \(one per trial\) holding"),
        ("gage_rr", CHECK.replace('kind = "check"', 'kind = "parts"'), "needs a repeat block"),
    ):
        text = HEAD.replace('unit = "in"', f'unit = "in"\nanalysis = "{kind}"') + body
        with pytest.raises(StationError, match=fault):
            load_procedure(write(tmp_path, text))


def test_a_block_kind_with_a_zero_window_numbers_its_inner_steps_by_the_block(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # The loader once reused the step's number for the zero's settle and still seconds, so a
    # block kind that also takes a zero window numbered its inner steps "0.25.1", not "1.1".
    from station.procedures import kinds

    zeroed_repeat = kinds.StepSchema(block=True, zero_window=True)
    monkeypatch.setattr(kinds, "_STEP_SCHEMAS", {**kinds._STEP_SCHEMAS, "zeroed": zeroed_repeat})
    block_step = (
        '[[steps]]\nid = "placements"\nkind = "zeroed"\ntitle = "Per placement"\n'
        "target = 3\nsettle = 0.5\nstill = 0.25\n"
        '[[steps.steps]]\nid = "read"\nkind = "check"\ntitle = "Read"\n'
    )
    (block,) = load_procedure(write(tmp_path, HEAD + block_step)).steps
    assert (block.number, block.settle, block.still) == ("1", 0.5, 0.25)
    assert [inner.number for inner in block.steps] == ["1.1"]
