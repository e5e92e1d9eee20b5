"""Profile the compiled batch engine with Linux `perf`: numba's compiled code has no symbols perf
can read, so this script writes a perf map (/tmp/perf-PID.map, perf's format for JIT code) of the
functions in the compiled sweep's object code, then runs sweeps of elastic_float.toml (400 speeds
3000-5000 rpm, 3600 steps) for the given seconds. Functions numba inlines (inline="always": the
phases, the windows, a step) count to their caller, kernel_phase.run_nodes.

    perf record -F 4999 -o /tmp/k.data .venv/bin/python benchmarks/perf_kernel.py 10
    perf report -i /tmp/k.data --no-children --sort sym

The map is read from the object code numba loads from its cache (kept as it is loaded: numba
drops it after linking) with `objdump -t` (binutils), its load address from the entry point of
kernel_figures.revolutions. perf reads the map after the process has ended, so it stays in /tmp
(delete it after `perf report`).
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from numba.core import codegen

from _timing import ROOT

_load = codegen.CPUCodeLibrary._set_compiled_object


def _keep(self, value):  # the object code as numba loads it from its cache
    self.kept_object = value
    return _load(self, value)


codegen.CPUCodeLibrary._set_compiled_object = _keep

sys.path.insert(0, str(ROOT))
from explorer.dynamics import kernel_figures  # noqa: E402 (after the hook above)
from explorer.scene.scene import load_scene  # noqa: E402
from explorer.studies.sweep_engine import _Shared, compute_chunk, result_columns  # noqa: E402


def _demangled(name: str) -> str:
    """numba's symbol _ZN8explorer8dynamics12kernel_phase9run_nodesB3v33... as
    explorer.dynamics.kernel_phase.run_nodes (its parts' lengths and names, up to the B or E that
    ends them); other symbols unchanged."""
    if not name.startswith("_ZN"):
        return name
    parts, i = [], 3
    while i < len(name) and name[i].isdigit():  # bounded: i grows every pass
        j = i
        while j < len(name) and name[j].isdigit():
            j += 1
        parts.append(name[j:j + int(name[i:j])])
        i = j + int(name[i:j])
    return ".".join(parts) if parts else name


def write_map() -> int:
    """The perf map of the compiled revolutions() and everything linked into it; its entries."""
    lines = []
    for cres in kernel_figures.revolutions.overloads.values():
        lib = cres.library
        with tempfile.NamedTemporaryFile(suffix=".o") as obj:
            obj.write(lib.kept_object)
            obj.flush()
            table = subprocess.run(["objdump", "-t", obj.name], capture_output=True, text=True, check=True).stdout
        symbols = []
        for line in table.splitlines():
            parts = line.split()
            if ".ltext" in line and len(parts) >= 5 and parts[-1] != ".ltext":
                symbols.append((int(parts[0], 16), int(parts[-2], 16), parts[-1]))
        entry = cres.fndesc.llvm_func_name
        base = lib.get_pointer_to_function(entry) - next(o for o, _, name in symbols if name == entry)
        for offset, size, name in symbols:
            short = _demangled(name)
            lines.append(f"{base + offset:x} {size:x} {short}\n")
    Path(f"/tmp/perf-{os.getpid()}.map").write_text("".join(lines))
    return len(lines)


def main() -> None:
    seconds = float(sys.argv[1]) if len(sys.argv) > 1 else 10.0
    scene = load_scene(ROOT / "assets" / "scenes" / "elastic_float.toml")
    names = result_columns(scene)
    rpm = np.linspace(3000.0, 5000.0, 400)[:, None]
    shared = _Shared()
    compute_chunk(scene, ("drive.rpm",), rpm[:2], names, shared)  # loads the kernels
    print(f"perf map: {write_map()} functions", file=sys.stderr)
    t = time.time()
    while time.time() - t < seconds:
        compute_chunk(scene, ("drive.rpm",), rpm, names, shared)


if __name__ == "__main__":
    main()
