"""Issue 12, findings 6 to 9: bad input gets one sentence (exit 2), never a traceback, a hang
or unbounded memory. Every case runs the real console script in a subprocess."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from helpers import run_station

REPO = Path(__file__).resolve().parents[2]


def station(*args: str | Path, timeout: float = 30, **kwargs) -> subprocess.CompletedProcess:
    """``station ARGS`` in this process; in a real one for the full-screen commands and where
    the test hands the process its own streams (``kwargs``)."""
    if kwargs or str(args[0]) in ("demo", "tui"):
        return subprocess.run(
            [sys.executable, "-m", "station", *map(str, args)],
            capture_output=True,
            text=True,
            cwd=REPO,
            timeout=timeout,
            **kwargs,
        )
    return run_station(*args, cwd=REPO)


def one_sentence(result: subprocess.CompletedProcess, code: int = 2, *words: str) -> None:
    """Exit ``code`` with one ``station: ...`` line on stderr naming ``words``."""
    assert "Traceback" not in result.stderr, result.stderr
    assert result.returncode == code, (result.returncode, result.stdout, result.stderr)
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("station: "), result.stderr
    for word in words:
        assert word in lines[0], lines[0]


def csv_file(folder: Path, text: str, name: str = "t.csv") -> Path:
    path = folder / name
    path.write_text(text)
    return path


READINGS = "".join(f"{(k % 7 - 3) / 10000}\n" for k in range(30))


# -- finding 6: one nested TOML file, a FIFO named x.toml ----------------------------------


def test_a_deeply_nested_procedure_file_is_skipped_with_a_sentence(tmp_path: Path) -> None:
    folder = tmp_path / "procedures"
    folder.mkdir()
    (folder / "x.toml").write_text("x = " + "[" * 5000 + "]" * 5000 + "\n")
    listed = station("procedures", "--procedures", folder)
    assert "Traceback" not in listed.stderr and listed.returncode == 1, listed.stderr
    assert "nests arrays or tables more than 16 deep" in listed.stdout + listed.stderr
    assert "repeatability" in listed.stdout  # the other procedures are still there
    capture = station(
        "capture", "--procedures", folder, "--procedure", "repeatability",
        "--port", "/nonexistent", "--protocol", "mitutoyo", "--robot", "r",
        "--sessions", tmp_path / "s", "--timeout", "0.2",
    )  # fmt: skip
    assert "Traceback" not in capture.stderr and "RecursionError" not in capture.stderr


def test_a_fifo_named_like_a_procedure_does_not_hang(tmp_path: Path) -> None:
    folder = tmp_path / "procedures"
    folder.mkdir()
    os.mkfifo(folder / "x.toml")
    listed = station("procedures", "--procedures", folder, timeout=20)
    assert listed.returncode == 1 and "FIFO" in listed.stdout + listed.stderr
    assert "repeatability" in listed.stdout


# -- finding 7: tracebacks where one line is promised -----------------------------------


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("x\n1e308\n1.7e308\n" + READINGS, ("beyond ±1e+150",)),
        ("x\n-1e308\n" + READINGS, ("beyond ±1e+150",)),
        ("cycle,x\n" + "".join(f"{2**63 + k},0.0001\n" for k in range(30)), ("cycle number",)),
    ],
    ids=["1e308", "-1e308", "cycle 2^63"],
)
def test_analyze_refuses_huge_values_and_cycles_in_one_line(tmp_path, text, words) -> None:
    one_sentence(station("analyze", csv_file(tmp_path, text)), 2, *words)


def test_analyze_refuses_a_huge_subgroup_a_long_name_and_dev_zero(tmp_path: Path) -> None:
    table = csv_file(tmp_path, "x\n" + READINGS)
    one_sentence(station("analyze", table, "--subgroup", "9223372036854775807"), 2, "--subgroup")
    one_sentence(station("analyze", tmp_path / ("n" * 300 + ".csv")), 2, "too long")
    one_sentence(station("analyze", "/dev/zero", timeout=20), 2, "device")


def _crafted_session(tmp_path: Path, **header) -> Path:
    """A session file that chains correctly but carries values no writer would write."""
    sys.path.insert(0, str(REPO / "tests"))
    from session.conftest import reading_fields, session_header_fields

    from station.session.lines import encode_line, line_hash

    fields = {**session_header_fields(), "format": "station-session/1", "session": "s"}
    fields.update(created="2026-11-23T12:00:00Z", host="h", **header)
    lines, prev = [], None
    records = [fields] + [
        {"seq": k, "t": "2026-11-23T12:00:00Z", "type": "reading", **reading_fields(k)}
        for k in range(1, 31)
    ]
    for record in records:
        line = encode_line(record, prev)
        lines.append(line)
        prev = line_hash(line)
    path = tmp_path / "crafted.jsonl"
    path.write_bytes(b"".join(line + b"\n" for line in lines))
    return path


@pytest.mark.parametrize(
    "header",
    [
        {"threshold": "abc"},
        {"limits": {"x": {"lsl": -1e300, "usl": 1e300}}},
    ],
    ids=["threshold abc", "limits 1e300"],
)
def test_crafted_session_headers_do_not_verify_nor_crash_analyze(tmp_path, header) -> None:
    path = _crafted_session(tmp_path, **header)
    verify = station("verify", path)
    assert verify.returncode == 1 and "NOT intact\nline 1:" in verify.stdout, verify.stdout
    analyze = station("analyze", path)
    one_sentence(analyze, 2, "line 1")


def test_a_crafted_huge_cycle_number_does_not_verify(tmp_path: Path) -> None:
    path = _crafted_session(tmp_path)
    data = path.read_bytes().split(b"\n")
    # Rewrite the last reading with cycle 2**63 and a correct chain.
    from station.session.lines import decode_line, encode_line

    record = decode_line(data[-2])
    record = {k: v for k, v in record.items() if k not in ("prev", "hash")}
    record["cycle"] = 2**63
    prev = decode_line(data[-2])["prev"]
    data[-2] = encode_line(record, prev)
    path.write_bytes(b"\n".join(data))
    verify = station("verify", path)
    assert verify.returncode == 1 and "cycle number from 1 to" in verify.stdout, verify.stdout
    one_sentence(station("analyze", path), 2, "cycle number")


@pytest.mark.parametrize(
    ("arguments", "words"),
    [
        (["--tcp", "-1"], ("--tcp",)),
        (["--tcp", "70000"], ("--tcp",)),
        (["--link", "/missing/dir/x"], ("does not exist",)),
        (["--resolution", "1e-300"], ("--resolution",)),
        (["--channels", ",".join(f"c{k}" for k in range(40))], ("one digit or letter",)),
        # finding 9: quiet gaps in simulate's options
        (["--noise", "nan"], ("--noise",)),
        (["--noise", "-1"], ("--noise",)),
        (["--range", "5,1"], ("--range",)),
        (["--push-rate", "-1"], ("--push-rate",)),
    ],
    ids=lambda value: " ".join(value) if isinstance(value, list) else None,
)
def test_simulate_refuses_bad_options_in_one_line(arguments, words) -> None:
    one_sentence(station("simulate", "--protocol", "mitutoyo", *arguments, timeout=20), 2, *words)


@pytest.mark.parametrize("content", [b"placement,x\n1,\xff\xfe\n", None], ids=["latin", "zero"])
def test_capture_inputs_must_be_a_utf8_regular_file(tmp_path: Path, content) -> None:
    if content is None:
        inputs = Path("/dev/zero")
    else:
        inputs = tmp_path / "inputs.csv"
        inputs.write_bytes(content)
    result = station(
        "capture", "--procedure", "relative_accuracy", "--port", "/nonexistent",
        "--protocol", "mitutoyo", "--robot", "r", "--sessions", tmp_path / "s",
        "--inputs", inputs, timeout=20,
    )  # fmt: skip
    one_sentence(result, 2, "--inputs")


def test_capture_timeout_beyond_a_day_exits_2(tmp_path: Path) -> None:
    result = station(
        "capture", "--procedure", "repeatability", "--port", "/nonexistent",
        "--protocol", "mitutoyo", "--robot", "r", "--timeout", "1e300",
    )  # fmt: skip
    one_sentence(result, 2, "--timeout")


def test_stdout_on_a_full_disk_is_one_line(tmp_path: Path) -> None:
    table = csv_file(tmp_path, "x\n" + READINGS)
    with open("/dev/full", "w") as full:
        result = subprocess.run(
            [sys.executable, "-m", "station", "analyze", str(table)],
            stdout=full,
            stderr=subprocess.PIPE,
            text=True,
            cwd=REPO,
            timeout=30,
        )
    one_sentence(result, 1, "cannot write the output")


# -- finding 8: hangs and memory --------------------------------------------------------------


@pytest.mark.parametrize("command", ["analyze", "verify", "export", "resume", "inputs"])
def test_a_fifo_given_as_a_file_is_refused_without_hanging(tmp_path: Path, command) -> None:
    fifo = tmp_path / "f.jsonl"
    os.mkfifo(fifo)
    arguments = {
        "analyze": ["analyze", fifo],
        "verify": ["verify", fifo],
        "export": ["export", fifo, "--csv"],
        "resume": ["capture", "--resume", fifo, "--port", "/nonexistent"],
        "inputs": [
            "capture", "--procedure", "relative_accuracy", "--port", "/nonexistent",
            "--protocol", "mitutoyo", "--robot", "r", "--inputs", fifo,
        ],
    }[command]  # fmt: skip
    result = station(*arguments, timeout=20)
    one_sentence(result, 2, "FIFO")


# -- finding 9: quiet gaps ----------------------------------------------------------------


def test_negative_limits_are_accepted_as_separate_words(tmp_path: Path) -> None:
    table = csv_file(tmp_path, "x\n" + READINGS)
    spaced = station("analyze", table, "--lsl", "-1e-3", "--usl", "1e-3", "--json")
    joined = station("analyze", table, "--lsl=-1e-3", "--usl=1e-3", "--json")
    assert spaced.returncode == 0, spaced.stderr
    assert spaced.stdout == joined.stdout
    open_below = station("analyze", table, "--lsl", "-inf", "--usl", "1e-3", "--json")
    assert open_below.returncode == 0, open_below.stderr
    assert '"lsl": null' in open_below.stdout.replace('"lsl":null', '"lsl": null')


def test_read_refuses_an_unknown_unit() -> None:
    one_sentence(
        station("read", "--port", "/dev/null", "--protocol", "mitutoyo", "--unit", "furlong"),
        2,
        "furlong",
    )


def test_capture_refuses_an_empty_sessions_folder(tmp_path: Path) -> None:
    result = station(
        "capture", "--procedure", "repeatability", "--port", "/nonexistent",
        "--protocol", "mitutoyo", "--robot", "r", "--sessions", "", timeout=20,
    )  # fmt: skip
    # Refused before any gauge is opened, whatever the port.
    one_sentence(result, 2, "--sessions")


def test_a_csv_without_a_header_is_refused_not_shortened(tmp_path: Path) -> None:
    one_sentence(station("analyze", csv_file(tmp_path, READINGS)), 2, "add a header row")


@pytest.mark.parametrize("cell", ["1_000", "\u0661\u0662"], ids=["underscore", "arabic-indic"])
def test_only_ascii_decimal_numbers_are_numbers(tmp_path: Path, cell: str) -> None:
    table = csv_file(tmp_path, "x\n" + READINGS + cell + "\n")
    one_sentence(station("analyze", table), 2, "is not a number")
    one_sentence(station("analyze", csv_file(tmp_path, "x\n" + READINGS, "u.csv"), "--lsl", cell))


def test_a_procedure_with_an_infinite_nominal_is_refused_on_load(tmp_path: Path) -> None:
    folder = tmp_path / "procedures"
    folder.mkdir()
    text = (REPO / "procedures" / "repeatability.toml").read_text()
    text = text.replace('id = "repeatability"', 'id = "inf-nominal"')
    assert "nominal = 0.0" in text
    text = text.replace("nominal = 0.0", "nominal = inf", 1)
    (folder / "inf.toml").write_text(text)
    listed = station("procedures", "--procedures", folder)
    assert listed.returncode == 1 and "finite" in listed.stdout + listed.stderr


@pytest.mark.parametrize(
    ("arguments", "words"),
    # (`--count 5` is a trial run now, issue 13: it ends on a provisional verdict.)
    [(["--count", "1"], ("at least 2",)), (["--procedure", "nope"], ("no procedure 'nope'",))],
    ids=["count 1", "procedure nope"],
)
def test_demo_refuses_what_the_tui_would_wait_on_forever(tmp_path, arguments, words) -> None:
    result = station(
        "demo", "--sessions", tmp_path, *arguments, timeout=30, stdin=subprocess.DEVNULL
    )
    one_sentence(result, 2, *words)
