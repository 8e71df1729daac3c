"""Typed values out of TOML tables, with errors that name the file and the place; and the TOML
nesting bound checked before :mod:`tomllib` reads a file."""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any, Literal, overload

from station.errors import StationError
from station.procedures.model import ID_PATTERN


class Checker:
    """Reads typed values out of TOML tables, raising errors that name the file and the place."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def fail(self, where: str, fault: str) -> StationError:
        place = f"{where}: " if where else ""
        return StationError(f"procedure file {self.path}: {place}{fault}")

    def only_keys(self, table: Mapping[str, Any], allowed: Iterable[str], where: str) -> None:
        unknown = sorted(set(table) - set(allowed))
        if unknown:
            raise self.fail(
                where,
                f"unknown key(s) {', '.join(map(repr, unknown))}; "
                f"allowed: {', '.join(sorted(allowed))}",
            )

    def get(
        self,
        table: Mapping[str, Any],
        key: str,
        kind: type | tuple[type, ...],
        where: str,
        *,
        required: bool = True,
        default: Any = None,
    ) -> Any:
        if key not in table:
            if required:
                raise self.fail(where, f"missing required key {key!r}")
            return default
        value = table[key]
        kinds = kind if isinstance(kind, tuple) else (kind,)
        # TOML booleans are ints in Python; a boolean is never a number here.
        if isinstance(value, bool) and bool not in kinds:
            raise self.fail(where, f"{key!r} must be {_type_name(kinds)}, not a boolean")
        if not isinstance(value, kinds):
            raise self.fail(
                where, f"{key!r} must be {_type_name(kinds)}, not {_toml_type(value)} {value!r}"
            )
        return value

    def text(self, table: Mapping[str, Any], key: str, where: str, **kw: Any) -> str:
        value = self.get(table, key, str, where, **kw)
        if kw.get("required", True) and not str(value).strip():
            raise self.fail(where, f"{key!r} must not be empty")
        return value

    @overload
    def number(
        self,
        table: Mapping[str, Any],
        key: str,
        where: str,
        *,
        required: Literal[True] = True,
        default: float | None = None,
    ) -> float: ...
    @overload
    def number(
        self, table: Mapping[str, Any], key: str, where: str, *, required: bool, default: float
    ) -> float: ...
    @overload
    def number(
        self,
        table: Mapping[str, Any],
        key: str,
        where: str,
        *,
        required: bool,
        default: None = None,
    ) -> float | None: ...
    def number(
        self,
        table: Mapping[str, Any],
        key: str,
        where: str,
        *,
        required: bool = True,
        default: float | None = None,
    ) -> float | None:
        """The number at ``key``, finite; ``default`` when it is absent and not ``required``."""
        value = self.get(table, key, (int, float), where, required=required, default=default)
        if value is None:
            return value
        try:
            number = float(value)
        except OverflowError:
            number = math.inf
        if not math.isfinite(number):
            raise self.fail(where, f"{key!r} must be a finite number, not {value}")
        return number

    def count(self, table: Mapping[str, Any], key: str, where: str, **kw: Any) -> int | None:
        value = self.get(table, key, int, where, **kw)
        if value is not None and value < 1:
            raise self.fail(where, f"{key!r} must be at least 1, not {value}")
        return value

    def names(
        self, table: Mapping[str, Any], key: str, where: str, **kw: Any
    ) -> tuple[str, ...] | None:
        value = self.get(table, key, list, where, **kw)
        if value is None:
            return None
        if not value:
            raise self.fail(where, f"{key!r} must name at least one channel")
        for item in value:
            if not isinstance(item, str) or not ID_PATTERN.match(item):
                raise self.fail(where, f"{key!r} holds {item!r}, which is not a channel name")
        if len(set(value)) != len(value):
            raise self.fail(where, f"{key!r} names a channel twice: {value!r}")
        return tuple(value)


def _type_name(kinds: tuple[type, ...]) -> str:
    names = {str: "a string", int: "an integer", float: "a number", list: "a list"}
    names |= {dict: "a table", bool: "true or false"}
    if set(kinds) == {int, float}:
        return "a number"
    return " or ".join(names.get(k, k.__name__) for k in kinds)


def _toml_type(value: Any) -> str:
    return {str: "a string", int: "an integer", float: "a number", list: "a list"}.get(
        type(value), "a table" if isinstance(value, dict) else type(value).__name__
    )


TOML_DEPTH_LIMIT = 16
"""The deepest nesting of arrays and inline tables a procedure file may have (tomllib recurses
once per level: a file of ``[[[[...`` would otherwise end in a RecursionError)."""


def toml_nesting_depth(text: str) -> int:
    """The deepest nesting of ``[`` and ``{`` in TOML ``text`` outside strings and comments
    (a table header ``[a]`` or ``[[a]]`` counts its brackets too). Linear, no recursion."""
    depth = deepest = 0
    index, length = 0, len(text)
    while index < length:
        char = text[index]
        if char == "#":
            newline = text.find("\n", index)
            index = length if newline < 0 else newline
            continue
        if char in "\"'":
            triple = text.startswith(char * 3, index)
            quote = char * 3 if triple else char
            index += len(quote)
            while index < length:
                if char == '"' and text[index] == "\\":
                    index += 2
                    continue
                if text.startswith(quote, index):
                    index += len(quote)
                    break
                if not triple and text[index] == "\n":
                    break
                index += 1
            continue
        if char in "[{":
            depth += 1
            deepest = max(deepest, depth)
        elif char in "]}":
            depth = max(depth - 1, 0)
        index += 1
    return deepest
