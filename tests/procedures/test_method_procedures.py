"""The gauge check, per-joint troubleshooting and gain schedule procedures: they load, and a
site's edit that drops what their analysis reads fails on load with a sentence."""

from __future__ import annotations

from pathlib import Path

import pytest

from station.errors import StationError
from station.procedures import builtin_procedures_dir, discover_procedures, load_procedure

BUILTIN = builtin_procedures_dir()


@pytest.mark.parametrize("kind", ["gauge_check", "joint_troubleshooting", "gain_schedule"])
def test_builtin_procedures_declare_their_kind(kind):
    procedure = discover_procedures(use_env=False).get(kind)
    assert procedure.analysis == kind


@pytest.mark.parametrize(
    ("kind", "old", "new", "fault"),
    [
        (
            "gauge_check",
            'name = "tolerance"',
            'name = "spread"',
            "needs an input step with number fields 'reference' and 'tolerance'",
        ),
        (
            "joint_troubleshooting",
            'channels = ["x", "y", "z"]',
            'channels = ["x", "y"]',
            "needs the channels x, y, z",
        ),
        ("gain_schedule", 'name = "q"', 'name = "position"', "a number field 'q'"),
    ],
)
def test_an_edit_that_drops_what_the_analysis_reads_fails(tmp_path: Path, kind, old, new, fault):
    text = (BUILTIN / f"{kind}.toml").read_text()
    assert old in text
    edited = tmp_path / f"{kind}.toml"
    edited.write_text(text.replace(old, new, 1))
    with pytest.raises(StationError, match=fault):
        load_procedure(edited)


def test_a_gauge_check_without_repeated_readings_fails(tmp_path: Path):
    path = tmp_path / "one_shot.toml"
    path.write_text(
        'id = "one_shot"\ntitle = "T"\nversion = "1"\nreport_section = "-"\n'
        'channels = ["x"]\nunit = "in"\nresolution = 0.0001\nanalysis = "gauge_check"\n'
        '[[steps]]\nid = "ref"\nkind = "input"\ntitle = "Ref"\n'
        'fields = [{ name = "reference" }, { name = "tolerance" }]\n'
        '[[steps]]\nid = "one"\nkind = "capture"\ntitle = "One"\n'
    )
    with pytest.raises(StationError, match="needs a cycles step"):
        load_procedure(path)
