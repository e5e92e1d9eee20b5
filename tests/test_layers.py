"""Layers (issue #12): every module of explorer imports only from its own layer and the layers below,
read from the source with ast (tests/import_cycles.py: function-local and TYPE_CHECKING imports
count, and so do the "module:function" strings of the plug-in tables, named=True: a table may name
only what its layer may import), and the checker fails on planted violations.

A module's layer is its folder under explorer/ (explorer/result.py is the layer `result`). From the
bottom up:

    core       errors, units, the scene-file reader, files, outputs, child processes, jets, plug-in tables
    lift       lift curves: closed-form laws, tables, acceleration laws, cam contours; the law table
    mechanics  rigid kinematics and lash, loads and float speed, contact statics, spring rules
    dynamics   the elastic linkage: model, the solver table, exact/taylor/reference/1902 solvers
    result     what a simulation returns (columns, summary, events) and what an effect hands over
    effects    the effect table, the pipeline, one module per effect
    gears      the follower types (each a plug-in: keys, geometry, lift, figures, variants of
               effects) and their table
    scene      scene files -> validated, frozen Scene; built-in scenes; section parsers
    view | studies   3D parts (the gears' views), browser, rerun  |  bench, sweeps, studies
    checks     design rules over the operating range and the tolerances (runs the sweep engine)
    cli        the `explorer` command

view and studies stand side by side: neither imports the other. The package's own __init__ (the
notebook API: load_scene, simulate) and __main__ sit on top.
"""

from __future__ import annotations

from pathlib import Path

from import_cycles import import_graph, write_package

PACKAGE = Path(__file__).resolve().parents[1] / "explorer"

LAYERS: tuple[tuple[str, ...], ...] = (
    ("core",),
    ("lift",),
    ("mechanics",),
    ("dynamics",),
    ("result",),
    ("effects",),
    ("gears",),
    ("scene",),
    ("view", "studies"),
    ("checks",),
    ("cli",),
    ("__init__", "__main__"),
)


def layer_of(module: str, root: str) -> str:
    parts = module.split(".")
    if parts == [root]:
        return "__init__"
    return parts[1]


def layer_problems(package_dir: Path, layers=LAYERS) -> list[str]:
    """Each import (or table string naming a module) that runs up a layer or sideways between
    sibling layers, and each module in no layer."""
    root = Path(package_dir).name
    rank = {name: i for i, group in enumerate(layers) for name in group}
    problems = []
    graph = import_graph(Path(package_dir), named=True)
    for module in sorted(graph):
        here = layer_of(module, root)
        if here not in rank:
            problems.append(f"{module} is in no layer (folder {here!r}): add the folder to LAYERS")
            continue
        for target in sorted(graph[module]):
            there = layer_of(target, root)
            if there not in rank:
                continue  # reported as a module of its own
            if rank[there] > rank[here]:
                problems.append(f"{module} ({here}) imports {target} ({there}), a layer above it")
            elif rank[there] == rank[here] and there != here:
                problems.append(f"{module} ({here}) imports {target} ({there}), a sibling layer")
    return problems


def test_every_import_runs_down_the_layers():
    assert layer_problems(PACKAGE) == []


def test_every_folder_of_the_package_is_a_layer():
    folders = {p.name for p in PACKAGE.iterdir() if p.is_dir() and (p / "__init__.py").exists()}
    modules = {p.stem for p in PACKAGE.glob("*.py")}
    named = {name for group in LAYERS for name in group}
    assert folders | modules <= named



PLANTED_LAYERS = (("core",), ("lift",), ("view", "studies"), ("__init__",))


def test_the_checker_finds_planted_violations(tmp_path):
    package = write_package(tmp_path, {
        "__init__.py": "from .lift.curve import c\n",
        "core/__init__.py": "",
        "core/errors.py": "def e():\n    from ..lift import curve  # up, hidden in a function\n",
        "lift/__init__.py": "",
        "lift/curve.py": "from ..core.errors import e\nc = 1\n",
        "view/__init__.py": "",
        "view/parts.py": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from pkg.studies import bench\n",
        "studies/__init__.py": "",
        "studies/bench.py": "import pkg.lift.curve\n",
        "stray/__init__.py": "",
    })
    assert layer_problems(package, PLANTED_LAYERS) == [
        "pkg.core.errors (core) imports pkg.lift.curve (lift), a layer above it",
        "pkg.stray is in no layer (folder 'stray'): add the folder to LAYERS",
        "pkg.view.parts (view) imports pkg.studies.bench (studies), a sibling layer",
    ]


def test_the_checker_reads_the_strings_of_plug_in_tables(tmp_path):
    """A table that names a module of a higher layer as "module:function" (imported only when the
    entry is used) is an upward dependency all the same; a string naming a lower layer is not."""
    package = write_package(tmp_path, {
        "__init__.py": "",
        "core/__init__.py": "",
        "core/table.py": 'ENTRIES = {"curve": "pkg.lift.curve:c", "self": "pkg.core.errors:e"}\n',
        "core/errors.py": "e = 1\n",
        "lift/__init__.py": "",
        "lift/curve.py": 'c = 1\nBUILDERS = ("pkg.core.errors:e",)\n',
    })
    assert layer_problems(package, PLANTED_LAYERS) == [
        "pkg.core.table (core) imports pkg.lift.curve (lift), a layer above it",
    ]


def test_the_checker_accepts_a_clean_package(tmp_path):
    package = write_package(tmp_path, {
        "__init__.py": "from .studies.bench import b\n",
        "core/__init__.py": "",
        "core/errors.py": "class E(Exception):\n    pass\n",
        "lift/__init__.py": "from ..core import errors\n",
        "studies/__init__.py": "",
        "studies/bench.py": "from ..lift import errors as _\nfrom ..core.errors import E\nb = E\n",
    })
    assert layer_problems(package, PLANTED_LAYERS) == []
