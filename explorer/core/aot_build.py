"""Builds an ahead-of-time compiled kernel module (numba.pycc) for explorer/core/aot.py: the
exported functions with explicit signatures plus `source_digest()`, which returns the digest of
the sources the module was built from. Run by `make` (the kernels' modules' `--aot`), never at run
time. Compiled for the host CPU, as numba's JIT compiles (the module is built on the machine that
runs it); the floats are the same as the JIT's (tests/test_aot_kernels.py compares them bit for
bit). The module is written beside a temporary name and moved into place in one step, so a
process never imports a half-written file."""

from __future__ import annotations

import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

from .aot import digest


def build(module: str, directory: Path, exports: dict, sources) -> float:
    """Compile `exports` ({name: (signature, numba dispatcher or Python function)}) into the
    extension module `module` (its last dotted part) in `directory`; returns the seconds it took."""
    from numba import types
    from numba.pycc import CC

    start = time.perf_counter()
    name = module.rsplit(".", 1)[-1]
    stamp = digest(sources)
    cc = CC(name)
    cc.target_cpu = "host"
    work = Path(tempfile.mkdtemp(prefix=f".{name}-", dir=directory))
    try:
        cc.output_dir = str(work)
        for symbol, (signature, function) in exports.items():
            cc.export(symbol, signature)(getattr(function, "py_func", function))

        def source_digest():
            return stamp

        cc.export("source_digest", types.unicode_type())(source_digest)
        cc.compile()
        os.replace(work / cc.output_file, directory / cc.output_file)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    seconds = time.perf_counter() - start
    print(f"{module}: compiled ahead of time in {seconds:.1f} s ({directory / cc.output_file})", file=sys.stderr)
    return seconds
