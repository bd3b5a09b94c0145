"""Memo tables for the searches' hot paths (the oracles, the action model, the visibility test): a bounded table
keyed by value, and one keyed by an object's identity.

Keyed by identity: a search passes the same unmoved (immutable) object instances in thousands of states, and hashing
an id is cheaper than hashing the object. Each entry holds its object, so the object's id cannot be reused by
another object while the entry lives, and a hit checks that it is the same object.
"""

from __future__ import annotations


def memo(table: dict, key, compute, limit: int):
    """``table[key]``, made by ``compute()`` on a miss (``compute`` must not return None); ``table`` is emptied
    first when it already holds ``limit`` entries."""
    hit = table.get(key)
    if hit is None:
        if len(table) >= limit:
            table.clear()
        hit = table[key] = compute()
    return hit


class IdentityMemo:
    """``compute(obj)`` per object instance (see the module docstring); emptied when it holds ``limit`` entries
    (None: unbounded, for a table that lives as long as one search)."""

    def __init__(self, compute, limit: int | None = None):
        self._compute, self._limit = compute, limit
        self._entries: dict = {}  # id(obj) -> (obj, value)

    def __call__(self, obj):
        hit = self._entries.get(id(obj))
        if hit is None or hit[0] is not obj:
            if self._limit is not None and len(self._entries) >= self._limit:
                self._entries.clear()
            hit = self._entries[id(obj)] = (obj, self._compute(obj))
        return hit[1]
