"""The layering rules of DESIGN.md, checked by import-linter on every test run."""

import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_domain_packages_do_not_import_the_ui():
    lint_imports = shutil.which("lint-imports", path=str(Path(sys.executable).parent))
    assert lint_imports, "import-linter is part of the test extra: pip install -e '.[test]'"
    result = subprocess.run([lint_imports], cwd=ROOT, capture_output=True, text=True)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "2 kept, 0 broken" in result.stdout


def test_readme_test_command_is_what_ci_runs():
    """CI runs the README's command under coverage: the same ``-m pytest`` with no options of
    its own, so the suite's options (pyproject's addopts) are the same in both."""
    readme = (ROOT / "README.md").read_text()
    ci = (ROOT / ".ci" / "run").read_text()
    assert ".venv/bin/python -m pytest\n" in readme
    assert ".venv/bin/coverage run -m pytest\n" in ci


def _loaded_after(code: str) -> set[str]:
    """The top-level packages loaded in a fresh interpreter after running ``code``."""
    probe = f"import sys\n{code}\nprint(' '.join(sorted({{m.split('.')[0] for m in sys.modules}})))"
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, cwd=ROOT)
    assert done.returncode == 0, done.stderr
    return set(done.stdout.split("\n")[-2].split())


def test_station_help_loads_no_numpy():
    """README, Development: a command imports what it needs inside its ``run``."""
    loaded = _loaded_after(
        "from station.cli import main\ntry:\n    main(['--help'])\nexcept SystemExit:\n    pass"
    )
    assert "station" in loaded and "numpy" not in loaded


def test_importing_the_engine_and_the_record_screens_loads_no_scipy():
    """README, Development: the analysis and the record import scipy where they use it, so a
    screen that imports the engine or the record on the UI thread does not wait for scipy (the
    TUI loads it on a worker thread)."""
    loaded = _loaded_after(
        "import station.run, station.verdicts, station.method_kinds\n"
        "import station.record.history, station.record.compare, station.record.render"
    )
    assert "numpy" in loaded and "scipy" not in loaded
