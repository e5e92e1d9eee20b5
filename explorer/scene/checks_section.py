"""The [checks] section of a scene: the design rules' settings (explorer.checks), kept as written.

Its form (the same as a `--rules FILE`): one entry per rule, `RULE = false` to switch it off or a
table of its settings, `[checks.RULE] fail = "32 deg"`. Which rules and settings exist, and their
dimensions, are the checks layer's (explorer/checks/registry.py, a layer above this one): the
settings are validated there, when a design is checked, with errors naming this file and the
dotted key. Here only the shape is checked, so that a malformed section fails at load time.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, Mapping

from ..core.errors import InputError


@dataclass(frozen=True)
class ChecksSpec:
    settings: Mapping[str, Any]  # rule -> False | {setting: value}, read-only
    file: str
    prefix: str = "checks"  # the dotted path of the settings in `file` ("" for a --rules file)


def shown_key(name) -> str:
    """A TOML key as an error names it: itself, or its repr when it holds anything but printable
    characters (a quoted key may hold a newline; an error is one line)."""
    text = str(name)
    return text if text.isprintable() and len(text) <= 60 else repr(text)[:60]


def freeze_settings(data: Mapping, file: str, prefix: str) -> Mapping[str, Any]:
    """The rules' entries, shape-checked and read-only: RULE = bool | {NAME = value}."""
    out: dict[str, Any] = {}
    for rule, entry in data.items():
        key = f"{prefix}.{shown_key(rule)}" if prefix else shown_key(rule)
        if isinstance(entry, bool):
            out[rule] = entry
        elif isinstance(entry, Mapping):
            for name, value in entry.items():
                if isinstance(value, (Mapping, list)):
                    raise InputError(file, f"{key}.{shown_key(name)}", "expected a value (a quantity such as \"30 deg\", a "
                                     "number, a string or true/false), not a table or a list")
            out[rule] = MappingProxyType(dict(entry))
        else:
            raise InputError(file, key, f"expected true/false (switch the rule on or off) or a table of its "
                             f"settings, got {entry!r}"[:200])
    return MappingProxyType(out)


def parse_checks_section(table, fields) -> ChecksSpec | None:
    if table is None:
        return None
    return ChecksSpec(freeze_settings(table.data, table.file, "checks"), table.file, "checks")
