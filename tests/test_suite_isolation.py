"""The suite itself: every test starts from the same process state (tests/conftest.py), and both
``pytest`` and ``python -m pytest`` find the suite's own modules."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]

LEAVES_AND_LOOKS = r"""
import os
from pathlib import Path

from station.methods import names
from station.tui.instruments import running_fixture, start_demo_fixture

LEFT = {}
SITE = '''
from station.methods.repeatability import Repeatability


class LeftBehind(Repeatability):
    name = "left-behind"


METHOD = LeftBehind()
'''


def test_1_leaves_state_behind(tmp_path, monkeypatch):
    # A site's method, installed on this test's own path (an entry point of a distribution).
    info = tmp_path / "left_site-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: left-site\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text("[station.methods]\nleft = left_site:METHOD\n")
    (tmp_path / "left_site.py").write_text(SITE)
    monkeypatch.syspath_prepend(str(tmp_path))
    assert "left-behind" in names()
    LEFT["url"] = start_demo_fixture(1).url  # never stopped
    LEFT["home"] = os.environ["HOME"]
    config = Path(os.environ["XDG_CONFIG_HOME"]) / "station"
    config.mkdir(parents=True)
    (config / "last-setup.json").write_text("{}")


def test_2_sees_none_of_it():
    assert "left-behind" not in names()
    assert running_fixture(LEFT["url"]) is None
    assert os.environ["HOME"] != LEFT["home"]
    for variable in ("XDG_CONFIG_HOME", "XDG_DATA_HOME", "XDG_STATE_HOME", "XDG_CACHE_HOME"):
        assert os.environ[variable].startswith(os.environ["HOME"])
        assert not any(Path(os.environ[variable]).rglob("*"))
    assert Path(os.environ["STATION_GAUGES"]).parent == Path(os.environ["HOME"])
    assert "STATION_SESSIONS" not in os.environ and "NO_COLOR" not in os.environ
"""


def test_no_state_carries_from_one_test_to_the_next(
    pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A test that installs a site's method, leaves a followed simulator running, writes a
    remembered set-up and runs under the developer's settings; the next test sees none of it."""
    monkeypatch.setenv("STATION_SESSIONS", "/srv/sessions")
    monkeypatch.setenv("NO_COLOR", "1")
    monkeypatch.setenv("PYTHONPATH", str(REPO))  # for -p tests.conftest
    pytester.makepyfile(test_order=LEAVES_AND_LOOKS)
    result = pytester.runpytest_subprocess(
        "-p", "tests.conftest", "-p", "no:randomly", "-p", "no:cacheprovider", "-q", timeout=120
    )
    result.assert_outcomes(passed=2)


def test_plain_pytest_imports_the_suites_own_modules() -> None:
    """``from tests.… import`` (the repository root) and ``from helpers import`` (tests/) work
    under plain ``pytest`` too, which once failed with ``No module named 'tests'`` (the suite
    itself runs under ``python -m pytest``, which puts the current folder on sys.path)."""
    importers = ["tests/tui/test_followed_fixture.py", "tests/runner/test_paced_capture.py"]
    pytest_script = Path(sys.executable).with_name("pytest")
    done = subprocess.run(
        [
            str(pytest_script),
            "--collect-only",
            "-q",
            "-n",
            "0",
            "-p",
            "no:cacheprovider",
            *importers,
        ],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    assert "error" not in done.stdout.lower()
