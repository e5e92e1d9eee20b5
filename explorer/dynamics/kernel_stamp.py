"""Keeps numba's cache of the compiled exact solver true to its sources.

numba's cache (cache=True) checks only the file that defines a function: a compiled function
keeps the code it compiled of the functions it calls in other files, and the constants it read
from them. The compiled solver is split over several modules (SOURCES) and reads constants of the
Python solver's, so a change in any of them must discard every cached kernel. Importing this
module (each kernel module does, before anything is compiled) compares a digest of SOURCES with the
one stored beside the cache and, when they differ, deletes the kernels' cache files; numba then
compiles them again (`make` does it once: `python -m explorer.dynamics.exact_kernel --warm`).
Nothing here imports numba.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

HERE = Path(__file__).resolve().parent
# the kernel's modules, whose cache files are discarded together
KERNEL_MODULES = ("kernel_steps", "kernel_events", "kernel_grid", "kernel_phase", "kernel_figures", "free_vibration")
RETIRED = ("exact_kernel",)  # modules that held compiled kernels before (their cache files are dropped too)
# every source the compiled code depends on: the kernel's and those whose constants it reads
SOURCES = tuple(f"{m}.py" for m in KERNEL_MODULES) + (
    "kernel_stamp.py", "kernel_shared.py", "exact.py", "exact_events.py", "exact_grid.py", "exact_phase.py",
    "exact_steps.py", "phases.py")
STAMP = "kernel.stamp"


def cache_directory() -> Path:
    """Where numba keeps the kernels' cache: under NUMBA_CACHE_DIR when it is set (numba's
    caching._CacheLocator.get_suitable_cache_subpath), else __pycache__ beside the sources."""
    root = os.environ.get("NUMBA_CACHE_DIR")
    if root:
        folder = os.path.abspath(str(HERE))
        return Path(os.path.abspath(root)) / f"{os.path.split(folder)[-1]}_{hashlib.sha1(folder.encode()).hexdigest()}"
    return HERE / "__pycache__"


def digest() -> str:
    h = hashlib.sha256()
    for name in SOURCES:
        h.update(name.encode())
        h.update((HERE / name).read_bytes())
    return h.hexdigest()


def refresh() -> bool:
    """Discard the kernels' cache files when the sources changed since they were made; True when
    it did. A cache folder that cannot be written is left as it is (numba then compiles in memory)."""
    directory = cache_directory()
    stamp = directory / STAMP
    current = digest()
    try:
        if stamp.read_text() == current:
            return False
    except OSError:
        pass
    try:
        directory.mkdir(parents=True, exist_ok=True)
        for path in directory.iterdir():
            if path.suffix in (".nbi", ".nbc") and path.name.split(".")[0] in KERNEL_MODULES + RETIRED:
                path.unlink(missing_ok=True)
        tmp = directory / f"{STAMP}.{os.getpid()}"
        tmp.write_text(current)
        tmp.replace(stamp)  # atomic: concurrent processes see one stamp or the other
    except OSError:
        return False
    return True


refresh()
