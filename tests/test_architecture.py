"""The layering rules of DESIGN.md, checked by import-linter on every test run."""

import ast
import re
import shutil
import subprocess
import sys
from pathlib import Path

import grimp

from station.methods import BUILT_IN

ROOT = Path(__file__).resolve().parents[1]


def test_domain_packages_do_not_import_the_ui():
    lint_imports = shutil.which("lint-imports", path=str(Path(sys.executable).parent))
    assert lint_imports, "import-linter is part of the test extra: pip install -e '.[test]'"
    result = subprocess.run([lint_imports], cwd=ROOT, capture_output=True, text=True)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "3 kept, 0 broken" in result.stdout


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
    """station/README.md, Deferred imports: a command imports what it needs inside its ``run``."""
    loaded = _loaded_after(
        "from station.cli import main\ntry:\n    main(['--help'])\nexcept SystemExit:\n    pass"
    )
    assert "station" in loaded and "numpy" not in loaded


def test_importing_the_engine_and_the_record_screens_loads_no_scipy():
    """station/README.md, Deferred imports: the analysis and the record import scipy where they
    use it, so a screen that imports the engine or the record on the UI thread does not wait for
    scipy (the TUI loads it on a worker thread)."""
    loaded = _loaded_after(
        "import station.run, station.methods\n"
        "import station.record.history, station.record.compare, station.record.render"
    )
    assert "numpy" in loaded and "scipy" not in loaded


FRONT_ENDS = ("tui", "commands", "record")
"""The packages that ask the methods and the step kinds, and never name one (issue 19)."""
STEP_KIND_NAMES = {"check", "cycles", "stroke", "repeat"}
"""Step kinds that are no action's name ("input", "zero", "capture" are actions too)."""


def _front_end_sources() -> list[Path]:
    return [p for package in FRONT_ENDS for p in (ROOT / "station" / package).rglob("*.py")]


def test_no_front_end_tests_a_method_or_a_step_kind_by_name():
    """Outside station/methods, the TUI, the commands and the record ask the method (and the
    step handler) instead of comparing its name: no comparison with a method's name or a step
    kind's, and no ``step.kind ==`` or ``.analysis ==``."""
    methods = {method.name for method in BUILT_IN}
    found = []
    for path in _front_end_sources():
        source = path.read_text()
        for node in ast.walk(ast.parse(source)):
            if not isinstance(node, ast.Compare):
                continue
            parts = [node.left, *node.comparators]
            constants = {
                value.value
                for part in parts
                for value in (part.elts if isinstance(part, ast.Tuple | ast.List) else [part])
                if isinstance(value, ast.Constant) and isinstance(value.value, str)
            }
            # A step kind's name against a ``.kind`` that is not an action's.
            of_a_kind = any(
                isinstance(part, ast.Attribute)
                and part.attr == "kind"
                and "action" not in ast.unparse(part.value)
                for part in parts
            )
            named = (constants & methods) | (constants & STEP_KIND_NAMES if of_a_kind else set())
            found.extend(f"{path.relative_to(ROOT)}:{node.lineno} {name!r}" for name in named)
        for number, line in enumerate(source.splitlines(), start=1):
            if re.search(r"\bstep\.kind\s*(==|!=|in\b)|\.analysis\s*(==|!=)", line):
                found.append(f"{path.relative_to(ROOT)}:{number} {line.strip()}")
    assert not found, "kind-name tests outside station/methods:\n" + "\n".join(found)


def test_no_registry_imports_its_members_back():
    """The methods and the step kinds are listed in explicit tuples: nothing the list imports
    (a method package, a step handler, what they build on) imports the list back, so no circle
    runs through a registry."""
    graph = grimp.build_graph("station", exclude_type_checking_imports=True)
    circles = []
    for listing in ("station.methods.catalog", "station.run.steps"):
        for member in sorted(graph.find_modules_directly_imported_by(listing)):
            chain = graph.find_shortest_chain(importer=member, imported=listing)
            if chain:
                circles.append(" -> ".join(chain))
    assert not circles, "\n".join(circles)
