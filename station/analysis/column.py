"""A column of numbers kept as one numpy array and shown as a read-only sequence.

An analysis holds each channel's readings, their cycle numbers and their times. As tuples of
Python numbers a million-reading channel cost a second to build and another to turn back into
an array wherever the analysis computed on it; as one array the analysis passes them on as
they are. :class:`Column` keeps the array (a private, read-only copy) and reads like the tuple
it replaces: ``len``, indexing, iteration and equality give Python numbers, and
``numpy.asarray(column)`` gives the array itself, without a copy.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from typing import Any

import numpy as np


class Column(Sequence[Any]):
    """A read-only one-dimensional column of numbers (see the module docstring)."""

    __slots__ = ("_array",)

    def __init__(self, values: Sequence[float] | np.ndarray, dtype: Any = float) -> None:
        array = np.array(values, dtype=dtype).reshape(-1)
        array.flags.writeable = False
        self._array = array

    @property
    def array(self) -> np.ndarray:
        """The numbers as a read-only numpy array (no copy)."""
        return self._array

    def __array__(self, dtype: Any = None, copy: bool | None = None) -> np.ndarray:
        if dtype is None or np.dtype(dtype) == self._array.dtype:
            return self._array.copy() if copy else self._array
        return self._array.astype(dtype)

    def __len__(self) -> int:
        return int(self._array.size)

    def __getitem__(self, index: Any) -> Any:
        if isinstance(index, slice):
            return tuple(self._array[index].tolist())
        return self._array[index].item()

    def __iter__(self) -> Iterator[Any]:
        return iter(self._array.tolist())

    def __reversed__(self) -> Iterator[Any]:
        return iter(self._array[::-1].tolist())

    def __eq__(self, other: object) -> bool:
        if isinstance(other, Column):
            return self._array.shape == other._array.shape and bool(
                np.all(self._array == other._array)
            )
        if isinstance(other, tuple | list):
            return len(other) == len(self) and tuple(self) == tuple(other)
        return NotImplemented

    def __hash__(self) -> int:
        return hash((self._array.dtype.str, self._array.tobytes()))

    def __repr__(self) -> str:
        return f"Column({self._array.tolist()!r})"
