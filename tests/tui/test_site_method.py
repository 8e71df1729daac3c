"""A method and a step kind the station does not ship (:mod:`toy_method`), installed as a site
installs its own (a distribution offering them under the ``station.methods`` and
``station.step_kinds`` entry points), run through every front end with no change to
``station/``: the TUI (Pilot), ``station capture``, ``analyze``, ``report`` in txt, md and html,
and ``export``."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
import toy_method

from station.session.model import load_session
from station.tui.app import StationApp, StationConfig
from station.tui.screens.summary import SummaryScreen

HERE = Path(__file__).resolve().parent
STATION = [sys.executable, "-m", "station"]


def install_site_package(folder: Path) -> Path:
    """A distribution's metadata in ``folder`` (as ``pip install`` leaves it in site-packages)
    offering the toy method and step kind by entry point; the folder to put on the path."""
    info = folder / "station_toy_site-1.0.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: station-toy-site\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text(
        "[station.methods]\nspread = toy_method:METHOD\n\n"
        "[station.step_kinds]\nsoak = toy_method:SOAK\n"
    )
    return folder


@pytest.fixture
def site(tmp_path: Path, monkeypatch) -> dict[str, str]:
    """The toy site installed for this process (its path on ``sys.path``) and for the
    processes a test starts (``PYTHONPATH``), with its procedure folder; their environment."""
    installed = install_site_package(tmp_path / "site-packages")
    monkeypatch.syspath_prepend(str(HERE))
    monkeypatch.syspath_prepend(str(installed))
    folder = tmp_path / "procedures"
    folder.mkdir()
    (folder / "soak-check.toml").write_bytes(toy_method.SOAK_PROCEDURE)
    path = os.pathsep.join([str(installed), str(HERE), os.environ.get("PYTHONPATH", "")])
    return {**os.environ, "PYTHONPATH": path, "STATION_PROCEDURES": str(folder)}


def station(env: dict[str, str], *args: str) -> subprocess.CompletedProcess[str]:
    done = subprocess.run([*STATION, *args], capture_output=True, text=True, timeout=120, env=env)
    assert done.returncode == 0, done.stdout + done.stderr
    return done


def test_the_site_method_runs_headless_and_through_the_record(tmp_path, fixture_pty, site):
    listed = station(site, "procedures").stdout
    assert "soak-check" in listed
    done = station(
        site,
        "capture", "--procedure", "soak-check", "--port", fixture_pty.url,
        "--protocol", fixture_pty.protocol, "--map", "1=x,2=y,3=z", "--robot", "R1",
        "--sessions", str(tmp_path / "sessions"), "--timeout", "5", "--every", "0.01",
    )  # fmt: skip
    # The capture summary is the method's report.
    assert "SPREAD REPORT" in done.stdout and "x range" in done.stdout
    path = next((tmp_path / "sessions").glob("*.jsonl"))
    session = load_session(path, recover=False)
    assert session.status == "finished" and len(session.cycles) == 3
    assert session.header["procedure"]["analysis"] == "spread"

    document = json.loads(station(site, "analyze", str(path), "--json").stdout)
    assert document["procedure"] == "spread" and set(document["spread"]) == {"x", "y", "z"}
    assert set(document["channels"]) == {"x", "y", "z"}

    text = station(site, "report", str(path)).stdout
    assert text.startswith("SPREAD REPORT ON") and "x range" in text
    markdown = station(site, "report", str(path), "--format", "md").stdout
    assert "SPREAD" in markdown and "x range" in markdown
    html = station(site, "report", str(path), "--format", "html").stdout
    # The method's own chart, then the histograms and control charts of its channels.
    assert 'id="chart-0-ranges"' in html and "Range of each channel" in html
    assert "Histogram of x" in html

    # Its export layout by default: its own wide table, which analyze reads back the same.
    table = tmp_path / "spread.csv"
    station(site, "export", str(path), "--csv", "-o", str(table))
    rows = [line for line in table.read_text().splitlines() if not line.startswith("#")]
    assert rows[0] == "cycle,x,y,z" and len(rows) == 4
    again = json.loads(
        station(site, "analyze", str(table), "--procedure", "spread", "--json").stdout
    )
    assert again["spread"] == pytest.approx(document["spread"])
    tidy = station(site, "export", str(path), "--csv", "--layout", "tidy").stdout
    assert tidy.startswith("cycle,channel,value")


async def test_the_site_method_runs_through_the_tui(tmp_path, fixture_pty, site, tui):
    app = StationApp(
        StationConfig(
            sessions_dir=tmp_path / "sessions",
            sessions_reason="test folder",
            procedure_dirs=(Path(site["STATION_PROCEDURES"]),),
            capture_timeout=3.0,
        )
    )
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.pause()
        app.screen.open_new("soak-check")
        await tui.wait_until(pilot, lambda: app.screen.query("#port"))
        await pilot.pause()
        await pilot.press(*"R1")
        app.screen.query_one("#port").value = fixture_pty.url
        app.screen.query_one("#map").value = "1=x,2=y,3=z"
        await pilot.press("f2")
        await tui.walk_checklist(pilot)
        for _ in range(3):
            await tui.capture_one(pilot)
        # Every step is done: the dashboard offers to finish.
        await tui.wait_until(pilot, lambda: app.runner.state().action.kind == "finish")
        await pilot.press("f")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, SummaryScreen), timeout=30)
        await pilot.pause()
        shown = str(app.screen.query_one("#summary-report").render())
        assert "SPREAD" in shown and "x range" in shown
        title = str(app.screen.query_one("#summary-title").render())
        assert "3 channels" in title
