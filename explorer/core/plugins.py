"""Plug-in tables: the one resolver of "module:attribute" references, and the table type every
kind of plug-in is listed in (gears, effects, lift laws, solvers, gear views).

A table maps a name to an entry. Built-in entries that would import much (a solver, numba, a
gear's geometry) are written as references, "explorer.dynamics.exact:solve" ("module:" for a
module), imported on first use; cheap ones are plain objects. `Registry.register` adds one more
(a plug-in written outside the package, or a test's toy) with one call; the returned
`Registration` undoes it, directly or as a context manager, so a test leaves the table as it found
it.

The layer and cycle tests (tests/test_layers.py, tests/test_imports.py) read the reference
strings as imports (tests/import_cycles.py, named=True): a table may name only modules of its own
layer or below.
"""

from __future__ import annotations

import importlib
from typing import Any, Generic, Iterator, TypeVar

T = TypeVar("T")


def is_reference(value: Any) -> bool:
    """True for a "package.module:attribute" string."""
    return isinstance(value, str) and ":" in value and "." in value.partition(":")[0]


def resolve(reference: Any) -> Any:
    """The object a "module:attribute" reference names (its module imported now; "module:" names
    the module itself); any other value is returned as it is (a plain object in a table)."""
    if not is_reference(reference):
        return reference
    module, _, attribute = reference.partition(":")
    target = importlib.import_module(module)
    for part in filter(None, attribute.split(".")):
        target = getattr(target, part)
    return target


class Registration:
    """What `Registry.register` returns: `undo()` (or leaving a `with` block) removes the entry
    and puts back the one it replaced, if any."""

    def __init__(self, registry: "Registry", name: str, previous: Any, had: bool):
        self._registry, self._name, self._previous, self._had = registry, name, previous, had
        self._done = False
        self._also: list = []

    def also(self, undo) -> "Registration":
        """One more step for `undo` (a table that keeps a second store, such as the closed forms)."""
        self._also.append(undo)
        return self

    def undo(self) -> None:
        if self._done:
            return
        self._done = True
        for step in reversed(self._also):
            step()
        entries = self._registry._entries
        entries.pop(self._name, None)
        self._registry._cache.pop(self._name, None)
        if self._had:
            entries[self._name] = self._previous

    def __enter__(self) -> "Registration":
        return self

    def __exit__(self, *exc) -> None:
        self.undo()


class Registry(Generic[T]):
    """name -> entry (an object, or a reference resolved on first use), in registration order.

    `kind` names the table in messages ("gear", "effect", "law", "solver", ...)."""

    def __init__(self, kind: str, entries: dict[str, Any] | None = None):
        self.kind = kind
        self._entries: dict[str, Any] = dict(entries or {})
        self._cache: dict[str, T] = {}

    def register(self, name: str, entry: T | str, *, replace: bool = False) -> Registration:
        """Add `entry` under `name` (ValueError when the name is taken, unless `replace`)."""
        if not isinstance(name, str) or not name:
            raise ValueError(f"a {self.kind} needs a name, got {name!r}")
        had = name in self._entries
        if had and not replace:
            raise ValueError(f"{self.kind} {name!r} is registered already")
        previous = self._entries.get(name)
        self._entries[name] = entry
        self._cache.pop(name, None)
        return Registration(self, name, previous, had)

    def names(self) -> tuple[str, ...]:
        return tuple(self._entries)

    def __contains__(self, name: object) -> bool:
        return name in self._entries

    def __iter__(self) -> Iterator[str]:
        return iter(tuple(self._entries))

    def __len__(self) -> int:
        return len(self._entries)

    def get(self, name: str) -> T:
        """The entry `name` (imported on first use); KeyError naming the known ones if none."""
        try:
            return self._cache[name]
        except KeyError:
            pass
        try:
            raw = self._entries[name]
        except KeyError:
            raise KeyError(f"unknown {self.kind} {name!r}; known: {', '.join(self._entries)}") from None
        entry = self._cache[name] = resolve(raw)
        return entry

    def __getitem__(self, name: str) -> T:
        return self.get(name)

    def entries(self) -> list[T]:
        """Every entry, in table order (imports the referenced ones)."""
        return [self.get(name) for name in self._entries]

    def items(self) -> list[tuple[str, T]]:
        return [(name, self.get(name)) for name in self._entries]

    def raw(self, name: str) -> Any:
        """The entry as written in the table (a reference stays a string): for tests and docs."""
        return self._entries[name]
