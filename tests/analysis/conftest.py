"""Shared data for the analysis tests: the report's Table 2-1 and the reference data sets."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
REFERENCE_DATA = REPO / ".." / "shared" / "reference" / "data"
TABLE_2_1 = REPO / "sessions" / "examples" / "table-2-1.csv"


def read_csv(path: Path) -> list[dict[str, str]]:
    """Rows of a CSV file with ``#`` comment lines skipped."""
    with path.open(newline="") as handle:
        return list(csv.DictReader(line for line in handle if not line.startswith("#")))


@pytest.fixture(scope="session")
def table_2_1() -> list[float]:
    """The 30 X-axis readings (inches) of the report's Table 2-1, from the shipped example."""
    return [float(row["x"]) for row in read_csv(TABLE_2_1)]


@pytest.fixture(scope="session")
def reference_data() -> Path:
    """The folder of published reference data sets; tests skip when it is not there."""
    if not REFERENCE_DATA.is_dir():
        pytest.skip(f"reference data not found at {REFERENCE_DATA.resolve()} (outside the repo)")
    return REFERENCE_DATA


@pytest.fixture(scope="session")
def reference_csv(reference_data):
    """Read one reference data file by name: rows as dicts of strings."""
    return lambda name: read_csv(reference_data / name)


def pytest_generate_tests(metafunc):
    """Parametrize ``qcc_rule_row`` with every row of qcc_rules_test_vectors.csv (or one skip)."""
    if "qcc_rule_row" not in metafunc.fixturenames:
        return
    path = REFERENCE_DATA / "qcc_rules_test_vectors.csv"
    if not path.is_file():
        reason = f"reference data not found at {path.resolve()} (outside the repo)"
        metafunc.parametrize("qcc_rule_row", [pytest.param(None, marks=pytest.mark.skip(reason))])
        return
    rows = read_csv(path)
    ids = [f"{row['rule_set']}-{row['rule']}-line{number}" for number, row in enumerate(rows, 1)]
    metafunc.parametrize("qcc_rule_row", rows, ids=ids)
