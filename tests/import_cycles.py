"""The import graph of a package, read from its source with ast, and its cycles.

Every `import` / `from ... import` anywhere in a module counts (module level, inside functions,
under TYPE_CHECKING): a function-local import is still a dependency, only a later one. An edge
goes to the module named; `from pkg import name` goes to pkg.name when that is a module, else
to pkg. Cycles are the strongly connected components with more than one module (or a module
importing itself).

    .venv/bin/python tests/import_cycles.py [PACKAGE_DIR] [--named]   # prints the cycles

--named also counts the modules that registry tables name in strings ("explorer.x:function"),
imported only when an entry is used: the dependencies the registries hold, rather than hide.
"""

from __future__ import annotations

import ast
import sys
from pathlib import Path


def module_names(package_dir: Path) -> dict[str, Path]:
    """Dotted module name -> file, for every .py file of the package."""
    package_dir = Path(package_dir)
    root = package_dir.name
    names = {}
    for path in sorted(package_dir.rglob("*.py")):
        parts = list(path.relative_to(package_dir).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        names[".".join([root] + parts)] = path
    return names


def import_graph(package_dir: Path, named: bool = False) -> dict[str, set[str]]:
    """module -> the package modules it imports; with `named`, also those a string constant
    names as "pkg.module" or "pkg.module:function" (the registries' lazily imported entries)."""
    modules = module_names(package_dir)
    graph: dict[str, set[str]] = {name: set() for name in modules}
    for name, path in modules.items():
        is_package = path.name == "__init__.py"
        package = name if is_package else name.rpartition(".")[0]
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        for node in ast.walk(tree):
            targets: list[str] = []
            if isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package.split(".")
                    base = base[: len(base) - (node.level - 1)]
                    source = ".".join(base + ([node.module] if node.module else []))
                else:
                    source = node.module or ""
                for alias in node.names:
                    sub = f"{source}.{alias.name}"
                    targets.append(sub if sub in modules else source)
            elif named and isinstance(node, ast.Constant) and isinstance(node.value, str):
                target = node.value.partition(":")[0]
                # a dotted module path ("pkg.module" or "pkg.module:name"), not a bare word that
                # happens to be the package's name (a program name, say)
                if "." in target and target in modules and target != name:
                    targets = [target]
            for target in targets:
                while target and target not in modules:  # import a.b.c of a package module a.b
                    target = target.rpartition(".")[0]
                if target:
                    graph[name].add(target)
    return graph


def write_package(root: Path, files: dict[str, str]) -> Path:
    """A throwaway package `pkg` under root (name -> source, dedented), for the checkers' own tests."""
    import textwrap

    package = Path(root) / "pkg"
    for name, text in files.items():
        path = package / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(textwrap.dedent(text))
    return package


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components that are cycles (Tarjan), each sorted, largest first."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    counter = [0]

    def connect(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                connect(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1 or v in graph.get(v, ()):
                found.append(sorted(component))

    sys.setrecursionlimit(max(sys.getrecursionlimit(), 10000))
    for v in sorted(graph):
        if v not in index:
            connect(v)
    return sorted(found, key=lambda c: (-len(c), c))


def cycle_modules(package_dir: Path) -> set[str]:
    return {m for component in cycles(import_graph(package_dir)) for m in component}


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if a != "--named"]
    where = Path(args[0]) if args else Path(__file__).resolve().parents[1] / "explorer"
    found = cycles(import_graph(where, named="--named" in sys.argv))
    for component in found:
        print(f"cycle of {len(component)}: {', '.join(component)}")
    print(f"{len(found)} cycle(s), {sum(map(len, found))} modules in cycles")
