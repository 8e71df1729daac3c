"""Review finding 16: one way to read numbers from the command line, for every command."""

from __future__ import annotations

import pytest

from station.cli import main
from station.commands._args import parse_number, positive_number
from station.errors import StationError


def test_parse_number() -> None:
    assert parse_number(None, "--lsl") is None and parse_number(" ", "--lsl") is None
    assert parse_number("-0.001", "--lsl") == -0.001
    with pytest.raises(StationError, match=r"^--lsl 'abc' is not a number\.$"):
        parse_number("abc", "--lsl")
    with pytest.raises(StationError, match=r"^--lsl 'nan' is not a finite number\.$"):
        parse_number("nan", "--lsl")


def test_positive_number() -> None:
    assert positive_number(None, "--count", int) is None
    assert positive_number("3", "--count", int) == 3
    assert positive_number("0.2", "--interval") == 0.2
    for text, kind, message in (
        ("zero", int, "--x 'zero' is not a number."),
        ("2.5", int, "--x '2.5' is not a whole number."),
        ("0", int, "--x must be more than 0, not 0."),
        ("-1", float, "--x must be more than 0, not -1."),
        ("inf", float, "--x 'inf' is not a finite number."),
        ("", float, "--x '' is not a number."),
    ):
        with pytest.raises(StationError) as caught:
            positive_number(text, "--x", kind)
        assert caught.value.message == message


def test_commands_share_the_wording(capsys: pytest.CaptureFixture) -> None:
    # `station read` took --interval inf before (float("inf") > 0).
    assert main(["read", "--port", "/dev/null", "--protocol", "mitutoyo", "--interval", "inf"]) == 2
    assert capsys.readouterr().err == "station: --interval 'inf' is not a finite number.\n"
    assert main(["analyze", "x.csv", "--resolution", "inf"]) == 2
    assert capsys.readouterr().err == "station: --resolution 'inf' is not a finite number.\n"
