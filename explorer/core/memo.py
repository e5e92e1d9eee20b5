"""Bounded caches shared across the runs of a batch (a sweep's chunk, the browser's speed sweep)."""

from __future__ import annotations

CACHE_ENTRIES = 16  # per cache: a tolerance study draws a new lash every run; memory must not grow with runs


def remember(cache: dict, key, make):
    """cache[key], made on first use; the oldest entry goes when the cache is full."""
    try:
        return cache[key]
    except KeyError:
        pass
    if len(cache) >= CACHE_ENTRIES:
        del cache[next(iter(cache))]
    value = cache[key] = make()
    return value
