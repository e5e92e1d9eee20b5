"""The rules' settings: the table's defaults, a scene's [checks] section, a --rules file (later ones
win), each value checked against its setting (one InputError naming the file and dotted key).

A [checks] section or a rules file holds one entry per rule:

    pressure_angle = false              # switch the rule off
    [seating_velocity]                  # in a scene: [checks.seating_velocity]
    fail = "0.8 m/s"
    warn = "0.6 m/s"
    [float_margin]
    fail = "200 rpm"
    enabled = true

A rules file may also wrap its entries in one [checks] table (a scene's section pasted as is).
"""

from __future__ import annotations

import math
import tomllib
from typing import Any, Mapping

from ..core.errors import InputError
from ..core.files import MAX_SCENE_FILE_BYTES, read_regular
from ..core.units import plain_number, short_repr, to_si
from ..scene.checks_section import ChecksSpec, freeze_settings, shown_key
from .registry import rule_names, rules
from .rule import RuleSpec, Setting, Settings


def load_rules_file(path) -> ChecksSpec:
    """A --rules FILE (TOML) as settings; a bad file is one InputError."""
    file = str(path)
    data = read_regular(path, file=file, key="-", limit=MAX_SCENE_FILE_BYTES)
    try:
        table = tomllib.loads(data.decode("utf-8-sig"))  # a leading byte-order mark dropped
    except UnicodeDecodeError:
        raise InputError(file, "-", "not a UTF-8 text file") from None
    except tomllib.TOMLDecodeError as exc:
        raise InputError(file, "-", f"malformed TOML: {str(exc).splitlines()[0] if str(exc) else exc}") from None
    except RecursionError:
        raise InputError(file, "-", "malformed TOML: nested too deeply") from None
    prefix = ""
    if set(table) == {"checks"} and isinstance(table["checks"], Mapping):
        table, prefix = table["checks"], "checks"
    return ChecksSpec(freeze_settings(table, file, prefix), file, prefix)


def resolve(sources: list[ChecksSpec | None]) -> tuple[dict[str, Settings], tuple[str, ...]]:
    """(rule -> Settings, the rules switched off), from the defaults and the `sources` in order."""
    table = rules()
    values: dict[str, dict[str, Any]] = {r.name: {s.name: s.default for s in r.settings} for r in table}
    origin: dict[str, dict] = {r.name: {s.name: "default" for s in r.settings} for r in table}
    enabled = {r.name: True for r in table}
    for source in sources:
        if source is None:
            continue
        for name, entry in source.settings.items():
            key = f"{source.prefix}.{shown_key(name)}" if source.prefix else shown_key(name)
            if name not in enabled:
                raise InputError(source.file, key, f"unknown rule; known: {', '.join(rule_names())}")
            spec = next(r for r in table if r.name == name)
            if isinstance(entry, bool):
                enabled[name] = entry
                continue
            for setting_name, raw in entry.items():
                if setting_name == "enabled":
                    if not isinstance(raw, bool):
                        raise InputError(source.file, f"{key}.enabled", f"expected true or false, got {short_repr(raw)}")
                    enabled[name] = raw
                    continue
                setting = spec.setting(setting_name)
                if setting is None:
                    known = ", ".join(["enabled", *(s.name for s in spec.settings)])
                    raise InputError(source.file, f"{key}.{shown_key(setting_name)}", f"unknown setting of rule {name!r}; "
                                     f"known: {known}")
                values[name][setting_name] = parse_setting(setting, raw, source.file, f"{key}.{setting_name}")
                origin[name][setting_name] = (source.file, f"{key}.{setting_name}")
    settings = {r.name: Settings(values[r.name], origin[r.name]) for r in table}
    for r in table:
        _check_order(r, settings[r.name], sources)
    return settings, tuple(r.name for r in table if not enabled[r.name])


def parse_setting(setting: Setting, raw, file: str, key: str):
    """A setting's value in SI from a TOML value, or InputError."""
    if setting.dimension == "bool":
        if not isinstance(raw, bool):
            raise InputError(file, key, f"expected true or false, got {short_repr(raw)}")
        return raw
    if setting.dimension == "choice":
        if not isinstance(raw, str) or raw not in setting.choices:
            raise InputError(file, key, f"unknown value {short_repr(raw)}; choose one of: {', '.join(setting.choices)}")
        return raw
    if setting.dimension == "number":
        if isinstance(raw, bool) or not isinstance(raw, (int, float)):
            raise InputError(file, key, f"expected a plain number, got {short_repr(raw)}"[:200])
        value = plain_number(raw, file=file, key=key)
    else:
        if isinstance(raw, bool) or not isinstance(raw, (int, float, str)):
            raise InputError(file, key, f"expected a quantity such as '1 {setting.unit or 'm'}', got {short_repr(raw)}"[:200])
        if setting.dimension == "lift_rate" and isinstance(raw, str) and not any(a in raw for a in ("deg", "rad")):
            raise InputError(file, key, f"{short_repr(raw)} is not a lift per cam angle: write it per degree or radian, "
                             "such as '0.002 in/deg'")
        value = to_si(raw, setting.dimension, file=file, key=key)
    if not math.isfinite(value):
        raise InputError(file, key, f"value must be finite, got {short_repr(raw)}")
    if setting.minimum is not None and value < setting.minimum:
        if setting.minimum == 0.0:
            raise InputError(file, key, f"must not be negative (a limit or margin below zero means nothing here), "
                             f"got {short_repr(raw)}")
        raise InputError(file, key, f"must be at least {setting.minimum:g}, got {short_repr(raw)}")
    return value


def _check_order(spec: RuleSpec, settings: Settings, sources) -> None:
    """A warn limit must lie on the safe side of the fail limit (it warns first)."""
    fail, warn = settings.get("fail"), settings.get("warn")
    if fail is None or warn is None:
        return
    wrong = warn > fail if spec.sense == "max" else warn < fail
    if wrong:
        where = settings.origin.get("warn")
        if where == "default":  # a fail limit set beyond the default warning: the warning goes
            settings["warn"] = None
            return
        file, key = where
        side = "below" if spec.sense == "max" else "above"
        raise InputError(file, key, f"the warn limit must lie {side} the fail limit of rule {spec.name!r} "
                         f"(it warns before the rule fails)")
