"""Compiled (numba typed) lists kept across calls, for kernels that take one list entry per
run: the ensemble's run states and generators, a vector environment's runs and twins.

Converting a value into a typed list costs microseconds, and numba's own Python-side list
methods compile anew in every process (about a second each); :class:`TypedListCache`
therefore converts only what changed and builds and changes the lists with cached compiled
functions.
"""

from __future__ import annotations

import weakref
from collections.abc import Callable, Sequence
from typing import Any

from numba.typed import List

from hcomc._jit import kernel

__all__ = ["TypedListCache"]


class TypedListCache:
    """Compiled (numba typed) lists of values taken from the same places across calls.

    Called again, only the places whose key changed are converted again, and a longer or
    shorter list of keys appends or drops places at the end, since each entry costs
    microseconds to convert (a learning environment passes its episodes' runs in the same
    places every step, with a few new episodes and a varying tail of twins). Keys are held
    weakly; the lists hold the values until the next call or :meth:`clear`. The lists are
    built and changed by cached compiled functions (:func:`_list_of` …): numba's own
    Python-side list methods compile anew in every process, about a second each.
    """

    def __init__(self) -> None:
        self._keys: list[weakref.ref[Any]] = []
        self._lists: tuple[List, ...] = ()

    def lists(self, keys: Sequence[Any], *columns: Callable[[Any], Any]) -> tuple[List, ...]:
        """One list per column function, entry k being ``column(keys[k])``."""
        if len(self._lists) != len(columns) or not self._keys or not keys:
            self._lists = tuple(_typed_list([column(key) for key in keys]) for column in columns)
            self._keys = [weakref.ref(key) for key in keys]
            return self._lists
        kept = min(len(keys), len(self._keys))
        for k in range(kept):
            key = keys[k]
            if self._keys[k]() is not key:
                self._keys[k] = weakref.ref(key)
                for values, column in zip(self._lists, columns, strict=True):
                    _list_set(values, k, column(key))
        for values, column in zip(self._lists, columns, strict=True):
            for _ in range(len(self._keys) - len(keys)):
                _list_pop(values)
            for key in keys[kept:]:
                _list_append(values, column(key))
        self._keys = self._keys[: len(keys)] + [weakref.ref(key) for key in keys[kept:]]
        return self._lists

    def clear(self) -> None:
        """Drop the lists (and the values they hold)."""
        self._keys, self._lists = [], ()


def _typed_list(values: list[Any]) -> List:
    """A compiled list of ``values`` (all of one type)."""
    if not values:
        return List()
    out = _list_of(values[0])
    for value in values[1:]:
        _list_append(out, value)
    return out


@kernel
def _list_of(first: Any) -> Any:
    """A compiled list holding ``first``, typed by it."""
    values = List()
    values.append(first)
    return values


@kernel
def _list_append(values: Any, item: Any) -> None:
    """Append ``item`` to a compiled list."""
    values.append(item)


@kernel
def _list_set(values: Any, k: int, item: Any) -> None:
    """Replace entry k of a compiled list."""
    values[k] = item


@kernel
def _list_pop(values: Any) -> None:
    """Drop the last entry of a compiled list."""
    values.pop()
