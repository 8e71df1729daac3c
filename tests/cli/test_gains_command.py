"""`station gains fit`: the real console script on CSV files; the C header compiled with gcc."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

STATION = Path(sys.executable).parent / "station"
POSITIONS = np.linspace(-30.0, 120.0, 9)
CUBIC = (2.0, -0.03, 4e-4, -1e-6)


def station(*args: str | Path, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(STATION), "gains", "fit", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=cwd,
    )


@pytest.fixture()
def gains_csv(tmp_path: Path) -> Path:
    kp = np.polynomial.polynomial.polyval(POSITIONS, CUBIC)
    ki = 0.4 + 1e-3 * POSITIONS
    rows = ["# tuned at 9 positions", "q,Kp,ki"]
    for q, p, i in zip(POSITIONS, kp, ki, strict=True):
        rows.append(f"{float(q)!r},{float(p)!r},{float(i)!r}")
    path = tmp_path / "gains.csv"
    path.write_text("\n".join(rows) + "\n")
    return path


def test_json_document(gains_csv: Path):
    result = station(gains_csv, "--json")
    assert result.returncode == 0, result.stderr
    document = json.loads(result.stdout)
    kp = document["gains"]["Kp"]
    assert kp["order"] == 3
    assert kp["coefficients"] == pytest.approx(CUBIC, rel=1e-8, abs=1e-14)
    assert len(kp["residuals"]) == 9 and kp["loo_rmse"] < 1e-9
    assert document["gains"]["ki"]["order"] == 1
    assert document["positions"] == pytest.approx(list(POSITIONS))


def test_text_report_has_scores_coefficients_and_plot(gains_csv: Path):
    result = station(gains_csv, "--order", "auto")
    assert result.returncode == 0, result.stderr
    out = result.stdout
    assert "GAIN Kp: order 3 (AICc)" in out
    assert "a3 = -1.0000000000e-06" in out
    assert "Kp(q), order 3" in out  # the plot's title
    assert "\x1b" not in out  # plain text, no colour codes


@pytest.mark.skipif(shutil.which("gcc") is None, reason="needs gcc")
def test_c_header_compiles_and_evaluates(gains_csv: Path, tmp_path: Path):
    header = tmp_path / "schedule.h"
    result = station(gains_csv, "--c", header, "--json")
    assert result.returncode == 0, result.stderr
    program = tmp_path / "main.c"
    program.write_text(
        '#include <stdio.h>\n#include "schedule.h"\n'
        "int main(void) {\n"
        '  printf("%.12f %.12f %d\\n",\n'
        "    gain_schedule_eval(gain_schedule_kp, GAIN_SCHEDULE_KP_ORDER, 50.0),\n"
        "    gain_schedule_eval(gain_schedule_ki, GAIN_SCHEDULE_KI_ORDER, 50.0),\n"
        "    (int)(sizeof gain_schedule_kp / sizeof gain_schedule_kp[0]));\n"
        "  return 0;\n}\n"
    )
    binary = tmp_path / "main"
    compiled = subprocess.run(
        ["gcc", "-std=c99", "-Wall", "-Werror", "-o", str(binary), str(program)],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert compiled.returncode == 0, compiled.stderr
    output = subprocess.run([str(binary)], capture_output=True, text=True, timeout=10).stdout
    kp, ki, length = output.split()
    assert float(kp) == pytest.approx(np.polynomial.polynomial.polyval(50.0, CUBIC), abs=1e-9)
    assert float(ki) == pytest.approx(0.45, abs=1e-9)
    assert int(length) == 4


def test_c_header_never_overwrites_its_input_nor_follows_a_symlink(gains_csv: Path, tmp_path: Path):
    before = gains_csv.read_bytes()
    result = station(gains_csv, "--c", gains_csv)
    assert result.returncode == 2 and "is the input file" in result.stderr, result.stderr
    assert gains_csv.read_bytes() == before
    victim = tmp_path / "victim.txt"
    victim.write_text("keep me")
    link = tmp_path / "out.h"
    link.symlink_to(victim)
    refused = station(gains_csv, "--c", link)
    assert refused.returncode == 2 and "symbolic link" in refused.stderr, refused.stderr
    assert len(refused.stderr.strip().splitlines()) == 1
    assert victim.read_text() == "keep me" and link.is_symlink()  # nothing written through it


@pytest.mark.parametrize(
    ("content", "args", "fragment"),
    [
        ("x,kp\n1,2\n2,3\n", (), "needs the columns q"),
        ("q\n1\n2\n", (), "no gain columns beside q"),
        ("q,kp\n1,2\n1,3\n2,4\n", (), "given twice"),
        ("q,kp\n1,2\n2,3\n3,4\n", ("--order", "3"), "needs at least 4 positions"),
        ("q,kp\n1,2\n2,3\n3,4\n", ("--order", "two"), "not a whole number or auto"),
    ],
)
def test_bad_input_is_one_sentence(tmp_path: Path, content, args, fragment):
    path = tmp_path / "bad.csv"
    path.write_text(content)
    result = station(path, *args)
    assert result.returncode == 2
    assert fragment in result.stderr
    assert result.stderr.count("\n") == 1


def test_names_from_the_csv_header_are_shown_as_text(tmp_path: Path):
    path = tmp_path / "gains.csv"
    rows = [f"{q},{1 + 0.1 * q}" for q in range(5)]
    path.write_text("q,k\x1b[31mp\u202e\n" + "\n".join(rows) + "\n")
    header = tmp_path / "out.h"
    result = station(path, "--no-plot", "--c", header)
    assert result.returncode == 0, result.stderr
    assert "\x1b" not in result.stdout and "\u202e" not in result.stdout
    assert "GAIN k\\x1b[31mp\\u202e: order 1" in result.stdout
    text = header.read_text()
    assert text.isascii() and "\x1b" not in text
    assert "gain_schedule_k_31mp[2]" in text
