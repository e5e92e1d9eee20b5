"""mkdocs hook: pages generated from the code, never typed.

A page holds a marker line `<!-- generate: NAME -->`; on build it is replaced by what the
generator NAME returns (markdown). The generators read the program itself: the command line
from its argument parsers (`explorer.cli.build_parser`), so the reference cannot drift from
the code. `tests/test_docs.py` builds the site with these hooks and checks its links.
"""

from __future__ import annotations

import argparse
import os
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
MARKER = re.compile(r"^<!-- generate: ([a-z0-9-]+) -->$", re.M)


def _subcommands(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    for action in parser._actions:  # argparse keeps its subparsers only here
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


def cli_reference() -> str:
    """Every command's --help, as the program prints it at 100 columns."""
    os.environ["COLUMNS"] = "100"  # argparse wraps at $COLUMNS; fixed so the page is reproducible
    from explorer.cli import build_parser

    parser = build_parser()
    parts = ["## explorer", "", "```text", parser.format_help().rstrip(), "```", ""]
    for name, sub in _subcommands(parser).items():
        parts += [f"## explorer {name}", "", "```text", sub.format_help().rstrip(), "```", ""]
    return "\n".join(parts)


def _normalise(key: str) -> str:
    """lift.stations[3].angle -> lift.stations[].angle: one row for every element of an array."""
    return re.sub(r"\[\d+\]", "[]", key)


def _shown(value, dimension: str | None) -> str:
    from explorer.core.ranges import SHOWN_UNITS

    if value is ... or value is None:
        return "required" if value is ... else "none"
    if isinstance(value, bool):
        return str(value).lower()
    if dimension and isinstance(value, (int, float)):
        unit, factor = SHOWN_UNITS.get(dimension, ("", 1.0))
        return f"{value * factor:g} {unit}".strip()
    return f"`{value!r}`" if not isinstance(value, str) else f"`{value}`"


def scene_keys_reference() -> str:
    """Every key the scene loader reads, with its kind, SI unit, range and default.

    Recorded, not typed: the loader reads every key through `explorer.core.reader.Table`
    (quantity, number, string, raw), whose methods are wrapped here while every
    built-in scene and every example scene under docs/ is loaded, so a key appears exactly as
    the loader asks for it -- its default when the scene leaves it out included. Each table's
    `reject_unknown` list names the keys it accepts: one that no loaded scene made the loader
    read is listed too, marked, so nothing the loader accepts is missing from this page.
    """
    from explorer.core import reader
    from explorer.core.ranges import SHOWN_UNITS, range_for
    from explorer.scene.builtin import builtin_scenes
    from explorer.scene.scene import load_scene

    rows: dict[str, dict] = {}
    accepted: dict[str, set[str]] = {}
    original = {name: getattr(reader.Table, name) for name in ("quantity", "number", "string", "raw", "reject_unknown")}

    def record(table, name, default, **info):
        row = rows.setdefault(_normalise(table.key(name)), {"defaults": []})
        if not any(d is default or (type(d) is type(default) and d == default) for d in row["defaults"]):
            row["defaults"].append(default)  # a default that differs between scenes is the scene's own
        for field, value in info.items():
            row.setdefault(field, value)

    def quantity(self, name, dimension, default=..., **limits):
        record(self, name, default, kind="quantity", dimension=dimension, limits=limits)
        return original["quantity"](self, name, dimension, default, **limits)

    def number(self, name, default=..., **limits):
        record(self, name, default, kind="number", limits=limits)
        return original["number"](self, name, default, **limits)

    def string(self, name, default=..., *, choices=None):
        choices = None if choices is None else list(choices)
        record(self, name, default, kind="string", choices=choices)
        return original["string"](self, name, default, choices=choices)

    def raw(self, name, default=...):
        record(self, name, default, kind="value")
        return original["raw"](self, name, default)

    def reject_unknown(self, known):
        known = list(known)
        accepted.setdefault(_normalise(self.prefix), set()).update(known)
        return original["reject_unknown"](self, known)

    scenes = sorted(builtin_scenes())
    scenes += sorted((ROOT / "docs" / "examples").glob("*.toml"))
    try:
        for name, fn in (("quantity", quantity), ("number", number), ("string", string),
                         ("raw", raw), ("reject_unknown", reject_unknown)):
            setattr(reader.Table, name, fn)
        for path in scenes:
            load_scene(path)
    finally:
        for name, fn in original.items():
            setattr(reader.Table, name, fn)

    def flatten(data: dict, prefix: str = ""):
        for name, value in data.items():
            key = f"{prefix}.{name}" if prefix else name
            if isinstance(value, dict):
                yield from flatten(value, key)
            elif isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
                for item in value:
                    yield from flatten(item, key + "[]")
            else:
                yield key

    import tomllib

    for path in scenes:  # keys a section's parser reads without Table (as raw dicts) still get a row
        for key in flatten(tomllib.loads(Path(path).read_text(encoding="utf-8"))):
            if key not in rows and not any(k.startswith(key + "[]") for k in rows):
                rows[key] = {"kind": "unread"}
    for prefix, names in accepted.items():
        for name in names:
            key = f"{prefix}.{name}" if prefix else name
            if key not in rows and not any(k.startswith(key + ".") or k.startswith(key + "[]") for k in rows):
                rows[key] = {"kind": "unread"}

    def default_of(row: dict, dimension: str | None) -> str:
        defaults = row.get("defaults", [])
        if len(defaults) > 1:
            return "the scene's own (see the guide)"
        return _shown(defaults[0], dimension) if defaults else "optional"

    def describe(row: dict) -> tuple[str, str, str]:
        kind = row.get("kind", "value")
        dimension = row.get("dimension")
        limits = {k: v for k, v in (row.get("limits") or {}).items() if v not in (None, False)}
        if kind == "quantity":
            unit, factor = SHOWN_UNITS.get(dimension, ("", 1.0))
            parts = ["> 0" if limits.get("positive") else "≥ 0" if limits.get("nonnegative") else ""]
            if "minimum" in limits:
                parts.append(f"≥ {limits['minimum'] * factor:g} {unit}")
            if "maximum" in limits:
                parts.append(f"≤ {limits['maximum'] * factor:g} {unit}")
            else:
                bounds = range_for(dimension, "")
                if bounds:
                    parts.append(f"size ≤ {bounds[1] * factor:g} {unit}")
            return f"{dimension} [{unit}]", ", ".join(p for p in parts if p), default_of(row, dimension)
        if kind == "number":
            lo, hi = limits.get("minimum"), limits.get("maximum")
            what = "whole number" if limits.get("integer") else "number"
            low = "" if lo is None else (f"> {lo:g}" if limits.get("open_minimum") else f"≥ {lo:g}")
            high = "" if hi is None else (f"< {hi:g}" if limits.get("open_maximum") else f"≤ {hi:g}")
            return what, ", ".join(p for p in (low, high) if p), default_of(row, None)
        if kind == "string":
            choices = row.get("choices")
            return "text", (" \\| ".join(f"`{c}`" for c in choices) if choices else ""), default_of(row, None)
        if kind == "unread":
            return "(see the section's guide)", "", "optional"
        return "table or array", "", default_of(row, None)

    sections: dict[str, list[str]] = {}
    for key in sorted(rows):
        section = key.split(".")[0] if "." in key else "(top level)"
        kind, rng, default = describe(rows[key])
        sections.setdefault(section, []).append(f"| `{key}` | {kind} | {rng} | {default} |")
    out = [f"Generated from {len(scenes)} scene files: the {len(builtin_scenes())} built-in scenes "
           "and the examples under docs/examples.", ""]
    for section, lines in sorted(sections.items(), key=lambda kv: (kv[0] != "(top level)", kv[0])):
        out += [f"## {section}", "", "| key | kind [SI unit] | range | default |", "|---|---|---|---|", *lines, ""]
    return "\n".join(out)


GENERATORS = {
    "cli": cli_reference,
    "scene-keys": scene_keys_reference,
}


def on_page_markdown(markdown: str, page, config, files) -> str:
    if str(ROOT) not in sys.path:
        sys.path.insert(0, str(ROOT))

    def replace(match: re.Match) -> str:
        name = match.group(1)
        if name not in GENERATORS:
            raise ValueError(f"{page.file.src_path}: unknown generator {name!r}; known: {', '.join(GENERATORS)}")
        return GENERATORS[name]()

    return MARKER.sub(replace, markdown)
