"""Kernels compiled ahead of time (numba.pycc, `make`): an extension module used only while it was
built from the sources it compiles, else None and the caller runs its numba kernels (issue #27.3).

Why: a process that runs a numba kernel, even one loaded from numba's cache, pays numba's import
and its CPU target's set-up (~0.5 s of CPU: docs/benchmarks/sweep.md, #27.3), ten times the compiled
work of a 10-speed sweep. The same kernels compiled into an extension module load in a few
milliseconds and import no numba.

A module is used only when the digest it was built with (its exported `source_digest()`, baked in
at build time by explorer/core/aot_build.py) equals the digest of the current sources: a module
built from other sources is never used, whatever its file's date. The digest covers the kernel's
sources (the caller's list), the build's code (aot_build.py) and the numba and llvmlite releases
(their _version.py files, read without importing them) and the CPU: the module is compiled for the
host CPU, as numba's JIT compiles, so a module built on another CPU (a copied checkout) is not used
either. EXPLORER_AOT=0 in the environment: never use one (the benchmark and the tests compare the
two paths).

Nothing here imports numba.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import os
import platform
from collections.abc import Iterable
from pathlib import Path

ENV = "EXPLORER_AOT"
HERE = Path(__file__).resolve().parent


def _release_files() -> list[Path]:
    """numba's and llvmlite's _version.py (their release), found without importing them."""
    out = []
    for package in ("numba", "llvmlite"):
        spec = importlib.util.find_spec(package)
        if spec is not None and spec.submodule_search_locations:
            out.append(Path(next(iter(spec.submodule_search_locations))) / "_version.py")
    return out


def _cpu() -> bytes:
    """The host CPU's identity: its model and instruction-set flags (Linux: /proc/cpuinfo's first
    processor), else what the platform module reports."""
    try:
        text = Path("/proc/cpuinfo").read_text()
    except OSError:
        return f"{platform.machine()} {platform.processor()}".encode()
    first = text.split("\n\n", 1)[0].splitlines()
    keep = ("vendor_id", "cpu family", "model", "model name", "flags", "Features", "CPU implementer", "CPU part")
    return "\n".join(line for line in first if line.split(":", 1)[0].strip() in keep).encode()


def digest(sources: Iterable[Path]) -> str:
    """sha256 of the kernel's sources, the build's code, the compiler's releases and the CPU."""
    h = hashlib.sha256(_cpu())
    for path in [*sources, HERE / "aot_build.py", *_release_files()]:
        h.update(path.name.encode())
        try:
            h.update(path.read_bytes())
        except OSError:
            h.update(b"\0missing")
    return h.hexdigest()


def enabled() -> bool:
    return os.environ.get(ENV, "1") != "0"


def load(module: str, sources: Iterable[Path]):
    """The AOT module `module` (dotted name) when it exists and was built from `sources` as they are
    now; else None."""
    if not enabled():
        return None
    try:
        compiled = importlib.import_module(module)
    except ImportError:
        return None
    try:
        built_from = compiled.source_digest()
    except Exception:  # noqa: BLE001 (a module of another layout is as good as none)
        return None
    return compiled if built_from == digest(sources) else None
