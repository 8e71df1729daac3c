"""`station analyze --procedure linearity|relative_accuracy`: the real console script on real
CSV files generated from the simulator's models."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from helpers import run_station

from station.analysis.strokes import split_strokes
from station.instruments.simulator import BarModel, TwoFixtureModel

REPO = Path(__file__).resolve().parents[2]
STATION = Path(sys.executable).parent / "station"


def station(*args: str | Path) -> subprocess.CompletedProcess[str]:
    """``station analyze ARGS``, in this process (test_analyze_honesty runs the real one)."""
    return run_station("analyze", *args, cwd=REPO)


@pytest.fixture(scope="module")
def linearity_csv(tmp_path_factory) -> Path:
    model = BarModel(length=20.0, points=120, dwell=8, bow=0.0012, sag=0.0006)
    stream = model.stream(6, seed=3)
    rows = ["# a simulated parallel bar, inches", "stroke,s,h,v"]
    for stroke in split_strokes(stream["s"]):
        rows += [
            f"{stroke.index},{stream['s'][i]},{stream['h'][i]},{stream['v'][i]}"
            for i in range(stroke.start, stroke.stop)
        ]
    path = tmp_path_factory.mktemp("linearity") / "bar.csv"
    path.write_text("\n".join(rows) + "\n")
    return path


@pytest.fixture(scope="module")
def accuracy_csv(tmp_path_factory) -> Path:
    model = TwoFixtureModel(captures=2, seed=8)
    rows = ["placement,x,y,z,px,py,pz"]
    # Two returns per placement (rests 1 and 2 of each block of three: home, return, return).
    for number in range(1, 6):
        for rest in (model.rest_of(number, 1), model.rest_of(number, 2)):
            placement = model.placement_of(model.current_placement(rest))
            errors = ",".join(str(model.value(axis, rest, 1)) for axis in "xyz")
            pendant = ",".join(str(c) for c in placement.pendant)
            rows.append(f"{placement.number},{errors},{pendant}")
    path = tmp_path_factory.mktemp("accuracy") / "fixtures.csv"
    path.write_text("\n".join(rows) + "\n")
    return path


def test_linearity_json_has_the_documented_document(linearity_csv):
    result = station(
        linearity_csv, "--procedure", "linearity", "--tolerance", "0.0025", "--json", "--unit", "in"
    )
    assert result.returncode == 0, result.stderr
    document = json.loads(result.stdout)
    assert document["procedure"] == "linearity"
    linearity = document["linearity"]
    for channel in ("h", "v"):
        assert set(linearity[channel]) == {"ls", "mz"}
        assert 0 < linearity[channel]["mz"] <= linearity[channel]["ls"]
    assert linearity["h"]["mz"] == pytest.approx(0.0012 + 2 * 0.0004, abs=3e-4)
    assert [s["stroke"] for s in linearity["strokes"]] == [1, 2, 3, 4, 5, 6]
    assert [s["direction"] for s in linearity["strokes"]] == ["A→B", "B→A"] * 3
    assert {"ls", "mz"} <= linearity["strokes"][0]["h"].keys()
    assert set(linearity["path_repeatability"]) == {"h", "v"}
    # The verdict channels are the per-stroke straightness, judged one-sided.
    assert document["channels"]["h"]["n"] == 6
    assert document["channels"]["h"]["capability"]["usl"] == 0.0025
    assert document["channels"]["h"]["capability"]["lsl"] is None


def test_linearity_text_report_fits_80_columns(linearity_csv):
    result = station(linearity_csv, "--procedure", "linearity", "--tolerance", "0.0025")
    assert result.returncode == 0, result.stderr
    assert "LINEARITY (report §2.9; 6 strokes" in result.stdout
    assert "path repeatability" in result.stdout
    assert max(len(line) for line in result.stdout.splitlines()) <= 80


def test_a_tight_tolerance_fails_the_capability_check(linearity_csv):
    result = station(
        linearity_csv, "--procedure", "linearity", "--tolerance", "0.0005", "--fail-if-incapable"
    )
    assert result.returncode == 1
    assert "failed the capability check" in result.stderr


def test_relative_accuracy_json_and_report(accuracy_csv):
    result = station(accuracy_csv, "--procedure", "relative_accuracy", "--json")
    assert result.returncode == 0, result.stderr
    document = json.loads(result.stdout)
    assert document["procedure"] == "relative_accuracy"
    assert set(document["channels"]) == {"x", "y", "z"}
    accuracy = document["accuracy"]
    assert [p["placement"] for p in accuracy["placements"]] == [1, 2, 3, 4, 5]
    first = accuracy["placements"][0]
    expected = TwoFixtureModel(seed=8).placement_of(1).pendant
    assert first["pendant"] == dict(zip("xyz", expected, strict=True))
    assert first["n"] == 2
    assert set(accuracy["axes"]) == {"x", "y", "z"}
    assert accuracy["error_3d"]["n"] == 10
    text = station(accuracy_csv, "--procedure", "relative_accuracy")
    assert text.returncode == 0, text.stderr
    assert "ACROSS PLACEMENTS" in text.stdout
    assert max(len(line) for line in text.stdout.splitlines()) <= 80


@pytest.mark.parametrize(
    ("procedure", "header", "missing"),
    [
        ("linearity", "stroke,s,h", "v"),
        ("linearity", "s,h,v", "stroke"),
        ("relative_accuracy", "placement,x,y", "z"),
        ("relative_accuracy", "x,y,z", "placement"),
    ],
)
def test_bad_columns_are_one_line_errors(tmp_path, procedure, header, missing):
    path = tmp_path / "bad.csv"
    columns = header.split(",")
    path.write_text(header + "\n" + ",".join(["1"] * len(columns)) + "\n")
    result = station(path, "--procedure", procedure)
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("station: ")
    assert f"{missing} missing" in lines[0]
    assert "Traceback" not in result.stderr


@pytest.mark.parametrize(
    ("args", "fault"),
    [
        (["--tolerance", "abc"], "--tolerance 'abc' is not a number"),
        (["--tolerance", "-1"], "must be greater than 0"),
    ],
)
def test_bad_tolerance_is_a_one_line_error(linearity_csv, args, fault):
    result = station(linearity_csv, "--procedure", "linearity", *args)
    assert result.returncode == 2
    assert fault in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1


# -- session files ----------------------------------------------------------------------------


def write_session(folder: Path, procedure_id: str, events: list[tuple[str, dict]]) -> Path:
    """A real, hash-chained session file of the built-in procedure ``procedure_id``."""
    from station.procedures import builtin_procedures_dir, load_procedure
    from station.run import PortSetup, SessionSetup
    from station.session.journal import SessionWriter

    procedure = load_procedure(builtin_procedures_dir() / f"{procedure_id}.toml")
    channel_map = {str(n): ch for n, ch in enumerate(procedure.channels, start=1)}
    port = PortSetup("loop://", "mitutoyo", channel_map)
    header = SessionSetup(procedure, "sim", "F", (port,)).header_fields()
    with SessionWriter.create(folder, header) as writer:
        for kind, fields in events:
            writer.append(kind, **fields)
        return writer.path


@pytest.mark.parametrize("numbered", [True, False])
def test_a_linearity_session_is_analysed_from_its_samples(tmp_path, numbered):
    model = BarModel(length=20.0, points=80, dwell=6)
    stream = model.stream(4, seed=2)
    rows = list(zip(stream["h"], stream["v"], stream["s"], strict=True))
    if numbered:
        strokes = split_strokes(stream["s"])
        events = [
            (
                "samples",
                {
                    "step": "strokes",
                    "stroke": stroke.index,
                    "channels": ["h", "v", "s"],
                    "values": [list(row) for row in rows[stroke.start : stroke.stop]],
                },
            )
            for stroke in strokes
        ]
    else:
        # Batches of a stream as it came, without stroke numbers: split by the scale.
        events = [
            (
                "samples",
                {"step": "strokes", "channels": ["h", "v", "s"], "values": rows[i : i + 50]},
            )
            for i in range(0, len(rows), 50)
        ]
    path = write_session(tmp_path, "linearity", events)
    result = station(path, "--json")
    assert result.returncode == 0, result.stderr
    document = json.loads(result.stdout)
    assert document["procedure"] == "linearity"
    directions = [s["direction"] for s in document["linearity"]["strokes"]]
    assert directions == ["A→B", "B→A", "A→B", "B→A"]
    # The procedure's limits (h, v within +/- 0.001 in) give a 0.002 in tolerance.
    assert document["linearity"]["tolerance"] == pytest.approx(0.002)
    assert document["channels"]["h"]["capability"]["usl"] == pytest.approx(0.002)


def test_a_relative_accuracy_session_keeps_the_pendant_of_each_placement(tmp_path):
    model = TwoFixtureModel(seed=4)
    events = []
    for placement in range(1, 4):
        x, y, z = model.placement_of(placement).pendant
        values = {"x": x, "y": y, "z": z}
        events.append(("input", {"step": "pendant", "placement": placement, "values": values}))
        readings = {axis: {"value": model.value(axis, placement - 1, 0)} for axis in "xyz"}
        events.append(
            (
                "reading",
                {
                    "cycle": placement,
                    "step": "return",
                    "placement": placement,
                    "channels": readings,
                },
            )
        )
    path = write_session(tmp_path, "relative_accuracy", events)
    result = station(path, "--json")
    assert result.returncode == 0, result.stderr
    accuracy = json.loads(result.stdout)["accuracy"]
    assert [p["placement"] for p in accuracy["placements"]] == [1, 2, 3]
    assert accuracy["placements"][2]["pendant"] == dict(
        zip("xyz", model.placement_of(3).pendant, strict=True)
    )
    assert accuracy["per_unit"] is not None


def test_a_linearity_session_without_samples_says_so(tmp_path):
    path = write_session(tmp_path, "linearity", [])
    result = station(path)
    assert result.returncode == 2
    assert "no streamed strokes" in result.stderr


def test_a_site_procedure_is_analysed_by_its_declared_kind(tmp_path, monkeypatch):
    """Review finding 17: a site's `relative_accuracy_site` was analysed as repeatability
    because analyze chose the analysis by the procedure's id."""
    from station.procedures import builtin_procedures_dir, load_procedure
    from station.run import PortSetup, SessionSetup
    from station.session.journal import SessionWriter

    site = tmp_path / "site"
    site.mkdir()
    text = (builtin_procedures_dir() / "relative_accuracy.toml").read_text()
    (site / "ra.toml").write_text(
        text.replace('id = "relative_accuracy"', 'id = "relative_accuracy_site"')
    )
    procedure = load_procedure(site / "ra.toml")
    assert procedure.analysis == "relative_accuracy"
    port = PortSetup("loop://", "mitutoyo", {"1": "x", "2": "y", "3": "z"})
    header = SessionSetup(procedure, "cell 9", "F", (port,)).header_fields()
    with SessionWriter.create(tmp_path / "sessions", header) as writer:
        for placement in range(1, 4):
            readings = {axis: {"value": 0.0001 * placement} for axis in "xyz"}
            writer.append(
                "reading", cycle=placement, step="return", placement=placement, channels=readings
            )
        path = writer.path
    # The reviewing machine need not have the site's procedure file: the session says enough.
    monkeypatch.delenv("STATION_PROCEDURES", raising=False)
    result = station(path, "--json")
    assert result.returncode == 0, result.stderr
    document = json.loads(result.stdout)
    assert document["procedure"] == "relative_accuracy"
    assert [p["placement"] for p in document["accuracy"]["placements"]] == [1, 2, 3]


def test_the_analysis_a_header_records_wins(tmp_path, capsys):
    """A header that records its procedure's analysis (``procedure.analysis``) is analysed so,
    whatever the session holds."""
    from station.cli import main
    from station.session.journal import SessionWriter

    header = {
        "robot": "cell 9",
        "procedure": {"id": "site_a", "version": "1", "sha256": "0" * 64},
        "channels": ["x", "y", "z"],
        "unit": "in",
    }
    header["procedure"]["analysis"] = "repeatability"
    with SessionWriter.create(tmp_path, header) as writer:
        for cycle in range(1, 4):
            readings = {axis: {"value": 0.0001 * cycle} for axis in "xyz"}
            writer.append("reading", cycle=cycle, placement=cycle, channels=readings)
        path = writer.path
    assert main(["analyze", str(path), "--json"]) == 0
    document = json.loads(capsys.readouterr().out)
    assert document["procedure"] == "repeatability" and "accuracy" not in document
    header["procedure"]["analysis"] = "relative_accuracy"
    with SessionWriter.create(tmp_path, header) as writer:
        for cycle in range(1, 4):
            readings = {axis: {"value": 0.0001 * cycle} for axis in "xyz"}
            writer.append("reading", cycle=cycle, channels=readings)
        path = writer.path
    assert main(["analyze", str(path)]) == 2
    assert "no accepted readings at a fixture placement" in capsys.readouterr().err
