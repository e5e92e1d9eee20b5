"""No import cycles among explorer's modules (issue #12), read from the source with ast
(tests/import_cycles.py: function-local imports count, and so do the "module:function" strings of
the plug-in tables: a table naming a module that imports the table back is a cycle too), and a
checker that sees a planted one."""

from __future__ import annotations

from pathlib import Path

from import_cycles import cycles, import_graph, write_package

PACKAGE = Path(__file__).resolve().parents[1] / "explorer"

# Modules allowed in a cycle: none. A module that joins a cycle fails the test (the last pair,
# the browser's model <-> worker, was cut by moving ComputeWorker into view/browser/compute.py).
ALLOWED_IN_CYCLES: frozenset[str] = frozenset()


def cycle_problems(package_dir: Path, allowed=frozenset()) -> list[str]:
    """What is wrong with the package's import cycles, given the modules allowed in one."""
    found = cycles(import_graph(package_dir, named=True))
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


def test_the_checker_finds_a_cycle_through_a_table_string(tmp_path):
    """A table naming "pkg.solver:solve" in a module the solver imports back is a cycle."""
    package = write_package(tmp_path, {
        "__init__.py": "",
        "table.py": 'SOLVERS = {"fast": "pkg.solver:solve"}\nclass Error(Exception):\n    pass\n',
        "solver.py": "from .table import Error\n\ndef solve():\n    raise Error\n",
    })
    assert cycles(import_graph(package)) == []  # plain imports alone do not see it
    assert cycle_problems(package) == ["pkg.solver is in the import cycle pkg.solver <-> pkg.table",
                                       "pkg.table is in the import cycle pkg.solver <-> pkg.table"]


def test_every_table_entry_resolves():
    """The plug-in tables' references ("module:function", imported when used) name real objects, and
    every entry keeps the contract's shape: a gear's view for every gear, callables where a function
    is named."""
    import inspect

    from explorer.core.plugins import is_reference, resolve
    from explorer.dynamics.solvers import SOLVERS
    from explorer.effects.registry import EFFECTS
    from explorer.gears.base import Gear
    from explorer.gears.registry import GEARS
    from explorer.lift.registry import LAWS
    from explorer.scene.scene import OWNED_SECTIONS
    from explorer.view.gear_views import VIEWS, GearView

    targets = list(OWNED_SECTIONS.values())
    for info in SOLVERS.entries():
        targets += [t for t in (info.entry, info.chain_entry, info.stable_steps) if t is not None]
        if info.batch_entry is not None:
            assert inspect.ismodule(resolve(info.batch_entry)), info.name
    for law in LAWS.entries():
        targets += [t for t in (law.builder, law.parser) if t is not None]
        assert law.closed_form or law.builder is not None or law.gear_made or law.from_contour, law.name
    for spec in EFFECTS.entries():
        targets += [t for t in (spec.function, spec.row, spec.figures) if is_reference(t)]
        targets += [t for _, t in spec.sections]
        assert all(dep in EFFECTS for dep in spec.depends), spec.name
    for name, gear in GEARS.items():
        assert isinstance(gear, Gear) and gear.type == name
        assert all(callable(f) for f in gear.effects.values()) and set(gear.effects) <= set(EFFECTS.names())
    assert set(VIEWS.names()) == set(GEARS.names())
    assert all(isinstance(view, GearView) for view in VIEWS.entries())
    for target in targets:
        assert callable(resolve(target)), target
