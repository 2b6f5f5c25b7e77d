"""`BoundedMemo`: a least-recently-used memo of a pure function's results, bounded in entries.

For results that depend only on their key (a shape's symmetry order, a tile's meshes) and are
asked for again and again: a procedural design source builds every class shape, validates it,
loads it into a design and builds its cell, each of which asks for the same shape's figures.
The memo holds at most ``maxsize`` entries; the least recently used one is dropped first.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable, Hashable
from typing import Generic, TypeVar

from qshape.errors import DesignError

V = TypeVar("V")


class BoundedMemo(Generic[V]):
    """Results by key, at most ``maxsize`` of them (least recently used dropped first).

    Args:
        maxsize: Largest number of entries kept (>= 1).

    Raises:
        DesignError: ``maxsize`` < 1.
    """

    def __init__(self, maxsize: int) -> None:
        if maxsize < 1:
            raise DesignError(f"a memo holds at least one entry; maxsize={maxsize} given")
        self.maxsize = maxsize
        self._items: OrderedDict[Hashable, V] = OrderedDict()
        self.hits = 0
        """Lookups answered from the memo."""
        self.misses = 0
        """Lookups that computed their result."""

    def get(self, key: Hashable, compute: Callable[[], V]) -> V:
        """The result of ``key``: kept, or ``compute()`` kept now."""
        items = self._items
        if key in items:
            items.move_to_end(key)
            self.hits += 1
            return items[key]
        value = compute()
        self.misses += 1
        items[key] = value
        if len(items) > self.maxsize:
            items.popitem(last=False)
        return value

    def __len__(self) -> int:
        return len(self._items)

    def __contains__(self, key: Hashable) -> bool:
        return key in self._items

    def clear(self) -> None:
        """Drop every entry (the counts stay)."""
        self._items.clear()


__all__ = ["BoundedMemo"]
