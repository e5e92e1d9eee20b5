"""No import cycles among explorer's modules (issue #12), read from the source with ast
(tests/import_cycles.py: function-local imports count), and a checker that sees a planted one."""

from __future__ import annotations

import importlib
from pathlib import Path

from import_cycles import cycles, import_graph, write_package

PACKAGE = Path(__file__).resolve().parents[1] / "explorer"

# Modules allowed in a cycle: none. A module that joins a cycle fails the test (the last pair,
# the browser's model <-> worker, was cut by moving ComputeWorker into view/browser/compute.py).
ALLOWED_IN_CYCLES: frozenset[str] = frozenset()


def cycle_problems(package_dir: Path, allowed=frozenset()) -> list[str]:
    """What is wrong with the package's import cycles, given the modules allowed in one."""
    found = cycles(import_graph(package_dir))
    in_cycles = {m for component in found for m in component}
    problems = [f"{m} is in the import cycle {' <-> '.join(c)}" for c in found for m in c if m not in allowed]
    problems += [f"{m} is no longer in an import cycle: remove it from ALLOWED_IN_CYCLES"
                 for m in sorted(set(allowed) - in_cycles)]
    return problems


def test_no_module_joins_an_import_cycle():
    assert cycle_problems(PACKAGE, ALLOWED_IN_CYCLES) == []



def test_the_checker_finds_a_planted_cycle_of_function_local_imports(tmp_path):
    package = write_package(tmp_path, {
        "__init__.py": "",
        "a.py": "from .b import g\n\ndef f():\n    return g()\n",
        "b.py": "def g():\n    from . import a  # hidden in a function\n    return a\n",
        "c.py": "import pkg.sub.d\n",
        "sub/__init__.py": "",
        "sub/d.py": "from ..a import f\n",
    })
    assert cycles(import_graph(package)) == [["pkg.a", "pkg.b"]]
    assert cycle_problems(package) == ["pkg.a is in the import cycle pkg.a <-> pkg.b",
                                       "pkg.b is in the import cycle pkg.a <-> pkg.b"]
    assert cycle_problems(package, {"pkg.a", "pkg.b"}) == []
    assert cycle_problems(package, {"pkg.a", "pkg.b", "pkg.c"}) == [
        "pkg.c is no longer in an import cycle: remove it from ALLOWED_IN_CYCLES"]


def test_the_checker_finds_a_cycle_through_a_package_and_type_checking(tmp_path):
    package = write_package(tmp_path, {
        "__init__.py": "from .x import X\n",
        "x.py": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from pkg import Y\nX = 1\n",
        "y.py": "import pkg\n",
    })
    assert cycles(import_graph(package)) == [["pkg", "pkg.x"]]


def test_registry_entries_name_real_functions():
    """The tables that name plug-ins as "module:function" (imported when used) stay resolvable."""
    from explorer.effects.pipeline import EFFECT_FUNCTIONS, SECTION_SUMMARIES
    from explorer.gears.registry import GEARS
    from explorer.lift.registry import LAWS
    from explorer.view.parts import CONTOUR_FUNCTIONS

    targets = list(EFFECT_FUNCTIONS.values()) + list(CONTOUR_FUNCTIONS)
    for law in LAWS.entries():
        targets += [t for t in (law.builder, law.parser) if t is not None]
        assert law.closed_form or law.builder is not None or law.gear_made, law.name
    targets += [target for entries in SECTION_SUMMARIES.values() for _, target in entries]
    for entry in GEARS.values():
        targets += [entry.lift, *entry.effects.values()]
        meshes = importlib.import_module(entry.meshes)
        assert all(callable(getattr(meshes, f)) for f in ("gear_layout", "gear_parts", "gear_poses"))
    for target in targets:
        module, _, attr = target.partition(":")
        assert callable(getattr(importlib.import_module(module), attr)), target
