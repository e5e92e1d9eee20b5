"""Rewrite explorer's old flat module names to their layer folders (issue #12), in the files given.

    python tools/relayer.py FILE...        # rewrite imports, "module:function" strings, paths
    python tools/relayer.py --move         # (once, done) git mv every module, then rewrite all files

Idempotent: a name that already is a new module is left alone. Relative imports are resolved
against the module's old name (so a file git moved keeps meaning what it meant) and written
back relative to its new place.
"""

from __future__ import annotations

import ast
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

MOVES = {
    # core: no physics, imported by everything
    "errors": "core.errors", "units": "core.units", "reader": "core.reader", "ranges": "core.ranges",
    "files": "core.files", "outputs": "core.outputs", "processes": "core.processes", "jets": "core.jets",
    # lift curves
    "laws": "lift.laws", "lift_table": "lift.table", "lift_acceleration": "lift.acceleration",
    "lift": "lift.curves",
    "geometry": "lift.contours", "geometry.arcs": "lift.contours.arcs",
    "geometry.contour": "lift.contours.contour", "geometry.lift_from_contour": "lift.contours.lift_from_contour",
    "geometry.parametric": "lift.contours.parametric", "geometry.schenker_fig2": "lift.contours.schenker_fig2",
    "geometry.spec": "lift.contours.spec", "geometry.translating": "lift.contours.translating",
    # mechanics
    "kinematics": "mechanics.kinematics", "forces": "mechanics.forces", "contact": "mechanics.contact",
    "springs": "mechanics.springs",
    # dynamics
    "solvers": "dynamics.solvers",
    # scene
    "scene": "scene.scene", "scenes": "scene.builtin",
    # effects
    "effects": "effects.pipeline", "dynamics.effect": "effects.elastic", "gears.effect": "effects.gear",
    "gears.trip_effects": "effects.trip",
    # view
    "meshes": "view.parts", "gears.meshes": "view.gear_parts",
    "viewer": "view.browser", "viewer.app": "view.browser.app", "viewer.model": "view.browser.model",
    "viewer.origin": "view.browser.origin", "viewer.worker": "view.browser.worker",
    "recording": "view.rerun.recording", "recording_job": "view.rerun.job", "recording_live": "view.rerun.live",
    "recording_read": "view.rerun.read", "recording_worker": "view.rerun.worker",
    # studies
    "bench": "studies.bench", "studies": "studies.accuracy", "sweeps": "studies.sweeps",
    "gears.figures": "studies.gear_figures",
    # cli
    "cli_bench": "cli.bench", "cli_fit": "cli.fit", "cli_record": "cli.record", "cli_serve": "cli.serve",
    "cli_simulate": "cli.simulate", "cli_view": "cli.view",
}
OLD = {f"explorer.{k}": f"explorer.{v}" for k, v in MOVES.items()}
NEW_TO_OLD = {v: k for k, v in OLD.items()}


def new_modules() -> set[str]:
    names = set()
    for path in (ROOT / "explorer").rglob("*.py"):
        parts = list(path.relative_to(ROOT).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        names.add(".".join(parts))
    return names | set(OLD.values()) | {v.rpartition(".")[0] for v in OLD.values()}


NEW = new_modules()
FORCE_OLD = False  # --move: every relative import still means what it meant before the move
PROTECT = "EXPLORER\x00"  # a rewritten import head, restored after the dotted-name pass
_CHAIN = re.compile(r"\bexplorer(?:\.\w+)+")
_PATH = re.compile(r"\bexplorer/[\w/]+\.py\b")


def map_name(name: str) -> str:
    """A dotted name (module, or module.attribute) under its new module."""
    parts = name.split(".")
    old_len = max((n for n in range(1, len(parts) + 1) if ".".join(parts[:n]) in OLD), default=0)
    new_len = max((n for n in range(1, len(parts) + 1) if ".".join(parts[:n]) in NEW), default=0)
    if old_len == 0 or new_len > old_len:
        return name
    return ".".join([OLD[".".join(parts[:old_len])]] + parts[old_len:])


def _chain(match: re.Match) -> str:
    return map_name(match.group(0))


def _path(match: re.Match) -> str:
    dotted = match.group(0)[:-3].replace("/", ".")
    if dotted.endswith(".__init__"):
        return match.group(0)
    mapped = map_name(dotted)
    if mapped == dotted:
        return match.group(0)
    return mapped.replace(".", "/") + ".py"


def module_of(path: Path) -> tuple[str, bool]:
    parts = list(path.resolve().relative_to(ROOT).with_suffix("").parts)
    is_package = parts[-1] == "__init__"
    if is_package:
        parts = parts[:-1]
    return ".".join(parts), is_package


def _relative(from_package: str, target: str) -> str:
    """`target` written relative to `from_package` (the package the importing module is in)."""
    a, b = from_package.split("."), target.split(".")
    common = 0
    while common < min(len(a), len(b)) and a[common] == b[common]:
        common += 1
    dots = "." * (len(a) - common + 1)
    return dots + ".".join(b[common:])


def rewrite_absolute_from(text: str) -> str:
    """`from explorer[.x] import a, b` where a name is a module that moved: one line per new package."""
    tree = ast.parse(text)
    lines = text.splitlines(keepends=True)
    offsets = [0]
    for line in lines:
        offsets.append(offsets[-1] + len(line))
    edits = []
    for node in ast.walk(tree):
        if not (isinstance(node, ast.ImportFrom) and node.level == 0 and node.module
                and (node.module == "explorer" or node.module.startswith("explorer."))):
            continue
        start = offsets[node.lineno - 1] + node.col_offset
        end = offsets[node.end_lineno - 1] + node.end_col_offset
        moved = [a for a in node.names if f"{node.module}.{a.name}" in OLD]
        if not moved and any(f"{node.module}.{a.name}" in NEW for a in node.names):
            # `from explorer.effects import pipeline`: already the new package; protected as below
            edits.append((start, start + len("from ") + len("explorer"), f"from {PROTECT}"))
            continue
        if not moved:
            # the head alone; protected from the dotted-name pass, which cannot tell the old module
            # explorer.effects from the new package of that name
            segment = text[start:end]
            head = re.match(r"from\s+[\w.]+\s+import", segment)
            edits.append((start, start + head.end(), f"from {PROTECT}{map_name(node.module)[len('explorer'):]} import"))
            continue
        groups: dict[str, list[str]] = {}
        for alias in node.names:
            full = f"{node.module}.{alias.name}"
            if full in OLD:
                parent, _, leaf = OLD[full].rpartition(".")
                groups.setdefault(parent, []).append(leaf if leaf == (alias.asname or alias.name) and alias.asname is None
                                                     else f"{leaf} as {alias.asname or alias.name}")
            else:
                groups.setdefault(node.module, []).append(alias.name if alias.asname is None
                                                          else f"{alias.name} as {alias.asname}")
        indent = " " * node.col_offset
        edits.append((start, end, f"\n{indent}".join(f"from {PROTECT}{parent[len('explorer'):]} import {', '.join(names)}"
                                                      for parent, names in groups.items())))
    for start, end, new in sorted(edits, reverse=True):
        text = text[:start] + new + text[end:]
    return text


def _resolve(package: str, node: ast.ImportFrom) -> str:
    base = package.split(".")
    if node.level - 1 >= len(base):
        return ""  # above the top: not how this line was meant
    base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def rewrite_imports(text: str, path: Path) -> str:
    text = rewrite_absolute_from(text)
    if not path.resolve().is_relative_to(ROOT / "explorer"):
        return text
    module, is_package = module_of(path)
    old_module = NEW_TO_OLD.get(module, module)
    old_package = old_module if is_package else old_module.rpartition(".")[0]
    if module == "explorer.cli":
        old_package = "explorer"  # explorer/cli.py became the package explorer/cli/__init__.py
    new_package = module if is_package else module.rpartition(".")[0]
    tree = ast.parse(text)
    lines = text.splitlines(keepends=True)
    offsets = [0]
    for line in lines:
        offsets.append(offsets[-1] + len(line))
    edits = []
    for node in ast.walk(tree):
        if not (isinstance(node, ast.ImportFrom) and node.level):
            continue
        # Written for the new place (a line this tool wrote, or one that kept its meaning), else
        # for the old one (a line written before the file moved).
        new_source, old_source = _resolve(new_package, node), _resolve(old_package, node)
        if node.module is None:  # `from . import a, b`: modules, or attributes of the package
            written_new = all(f"{new_source}.{a.name}" in NEW for a in node.names)
            written_old = any(f"{old_source}.{a.name}" in OLD for a in node.names)
        else:
            written_new = new_source in NEW
            if new_source in OLD and not any(f"{new_source}.{a.name}" in NEW for a in node.names):
                written_new = False  # `from .lift import LawLift`: the old module, not the new package
            written_old = old_source in OLD or old_source in NEW
        use_old = FORCE_OLD or (written_old and not written_new)
        source = old_source if use_old else new_source
        if not use_old:
            # already written for the new layout: nothing to map (explorer.effects is a package now)
            start = offsets[node.lineno - 1] + node.col_offset
            end = offsets[node.end_lineno - 1] + node.end_col_offset
            segment = text[start:end]
            head = re.match(r"from\s+\.+[\w.]*\s+import", segment)
            if node.module is None:
                continue
            edits.append((start, start + head.end(), f"from {_relative(new_package, source)} import"))
            continue
        start = offsets[node.lineno - 1] + node.col_offset
        end = offsets[node.end_lineno - 1] + node.end_col_offset
        segment = text[start:end]
        if node.module is None:
            # `from . import a, b`: each name is a module; group them by their new package
            groups: dict[str, list[str]] = {}
            for alias in node.names:
                target = map_name(f"{source}.{alias.name}")
                parent, _, leaf = target.rpartition(".")
                groups.setdefault(parent, []).append(leaf if alias.asname is None and leaf == alias.name
                                                     else f"{leaf} as {alias.asname or alias.name}")
            indent = " " * node.col_offset
            new = f"\n{indent}".join(f"from {_relative(new_package, parent)} import {', '.join(names)}"
                                     for parent, names in groups.items())
            edits.append((start, end, new))
            continue
        target = map_name(source)
        head = re.match(r"from\s+\.+[\w.]*\s+import", segment)
        edits.append((start, start + head.end(), f"from {_relative(new_package, target)} import"))
    for start, end, new in sorted(edits, reverse=True):
        text = text[:start] + new + text[end:]
    return text


# Definitions that moved between modules in the same change (a scene-level function out of the
# physics, into the effect that uses it): (new module of the old place, name) -> its module now.
NAME_MOVES = {
    ("explorer.lift.curves", "build_lift"): "explorer.effects.lift",
    ("explorer.lift.curves", "LIFT_BUILDERS"): "explorer.effects.lift",
    ("explorer.mechanics.kinematics", "kinematics_effect"): "explorer.effects.kinematics",
    ("explorer.mechanics.kinematics", "lash_effect"): "explorer.effects.kinematics",
    ("explorer.mechanics.forces", "forces_effect"): "explorer.effects.forces",
    ("explorer.mechanics.contact", "translating_geometry"): "explorer.effects.contact",
    ("explorer.mechanics.contact", "gear_geometry"): "explorer.effects.contact",
    ("explorer.mechanics.contact", "contact_geometry"): "explorer.effects.contact",
    ("explorer.mechanics.contact", "contact_effect"): "explorer.effects.contact",
    ("explorer.mechanics.contact", "check_follower"): "explorer.scene.contact_section",
    ("explorer.mechanics.contact", "parse_contact_section"): "explorer.scene.contact_section",
    ("explorer.mechanics.springs", "advise_spring"): "explorer.effects.spring_design",
    ("explorer.mechanics.springs", "compare_events"): "explorer.effects.spring_design",
    ("explorer.mechanics.springs", "spring_design_summary"): "explorer.effects.spring_design",
    ("explorer.lift.contours.contour", "cam_contour"): "explorer.effects.contour",
    ("explorer.lift.contours.contour", "pitch_curve"): "explorer.effects.contour",
    ("explorer.lift.contours.contour", "geometry_columns"): "explorer.effects.contour",
}
_TARGET = re.compile(r"\b(explorer(?:\.\w+)+):(\w+)")


def rewrite_moved_names(text: str, path: Path) -> str:
    """`from M import name` where name moved out of M: split the line; "M:name" strings too."""
    text = _TARGET.sub(lambda m: f"{NAME_MOVES.get((m.group(1), m.group(2)), m.group(1))}:{m.group(2)}", text)
    in_package = path.resolve().is_relative_to(ROOT / "explorer")
    module, is_package = module_of(path) if in_package else ("", False)
    package = module if is_package else module.rpartition(".")[0]
    tree = ast.parse(text)
    offsets = [0]
    for line in text.splitlines(keepends=True):
        offsets.append(offsets[-1] + len(line))
    edits = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.ImportFrom) or node.module is None:
            continue
        source = _resolve(package, node) if node.level else node.module
        if not any((source, a.name) in NAME_MOVES for a in node.names):
            continue
        groups: dict[str, list[str]] = {}
        for a in node.names:
            target = NAME_MOVES.get((source, a.name), source)
            groups.setdefault(target, []).append(a.name if a.asname is None else f"{a.name} as {a.asname}")
        lines = []
        for target, names in groups.items():
            if target == module:
                continue  # the name now lives in this very module
            head = _relative(package, target) if node.level else target
            lines.append(f"from {head} import {', '.join(names)}")
        start = offsets[node.lineno - 1] + node.col_offset
        end = offsets[node.end_lineno - 1] + node.end_col_offset
        edits.append((start, end, ("\n" + " " * node.col_offset).join(lines) or "pass"))
    for start, end, new in sorted(edits, reverse=True):
        text = text[:start] + new + text[end:]
    return text


def rewrite(path: Path) -> bool:
    text = path.read_text(encoding="utf-8")
    new = text
    if path.suffix == ".py":
        new = rewrite_imports(new, path)
    new = _CHAIN.sub(_chain, new)
    new = _PATH.sub(_path, new).replace(PROTECT, "explorer")
    if path.suffix == ".py":
        new = rewrite_moved_names(new, path)
    if new != text:
        path.write_text(new, encoding="utf-8")
        return True
    return False


def move() -> None:
    (ROOT / "explorer" / "cli").mkdir(exist_ok=True)
    subprocess.run(["git", "mv", "explorer/cli.py", "explorer/cli/__init__.py"], cwd=ROOT, check=True)
    for old, new in sorted(MOVES.items()):
        if old in ("geometry", "viewer"):
            continue
        src = ROOT / "explorer" / (old.replace(".", "/") + ".py")
        dst = ROOT / "explorer" / (new.replace(".", "/") + ".py")
        dst.parent.mkdir(parents=True, exist_ok=True)
        subprocess.run(["git", "mv", str(src), str(dst)], cwd=ROOT, check=True)
    for old, new in (("geometry", "lift/contours"), ("viewer", "view/browser")):
        subprocess.run(["git", "mv", f"explorer/{old}/__init__.py", f"explorer/{new}/__init__.py"], cwd=ROOT, check=True)
    for folder in ("core", "lift", "mechanics", "scene", "effects", "view", "view/rerun", "studies"):
        init = ROOT / "explorer" / folder / "__init__.py"
        if not init.exists():
            init.write_text("")
            subprocess.run(["git", "add", str(init)], cwd=ROOT, check=True)


def main(argv: list[str]) -> int:
    if argv == ["--move"]:
        global FORCE_OLD
        FORCE_OLD = True
        move()
        files = subprocess.run(["git", "ls-files", "*.py", "*.md", "*.toml", "*.sh", "Makefile", "*.txt"],
                               cwd=ROOT, capture_output=True, text=True, check=True).stdout.split()
        paths = [ROOT / f for f in files if not f.startswith("tools/")]
    else:
        paths = [Path(a) for a in argv]
    changed = [p for p in paths if p.exists() and rewrite(p)]
    for p in changed:
        print(f"rewrote {p}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
