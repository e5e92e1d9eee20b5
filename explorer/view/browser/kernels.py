"""The compiled solvers (numba), prepared after the page is up instead of before it (issue #27.2).

The first page needs none of them: `simulate` of every built-in scene but the spring chain's runs
in Python. The speed sweep's 500 elastic speeds at once (explorer.effects.elastic_batch) and the
spring-chain scene call numba kernels, which compile for ~30 s on an idle 2-core machine the
first time after an install (numba then caches them on disk: later starts load them in about a
second). So `explorer serve` starts the server first and then `KernelWarmup`: one background
process, at low priority, that compiles (or loads) every kernel. Until it is done the speed sweep
computes its elastic figures one speed at a time in Python and says so on the page; once done,
the open pages sweep again with the compiled solver.
"""

from __future__ import annotations

import os
import subprocess
import sys
import threading
import time
from pathlib import Path

# compile (or load from numba's cache) every kernel the explorer calls, the spring chain's first
# (a scene's first result needs them; the sweep's only its later steps); nice: the page's own
# computations come first
WARM_CODE = (
    "import os; os.nice(10)\n"
    "from explorer.dynamics.chain_exact import warm as chain; chain()\n"
    "from explorer.dynamics.exact_kernel import warm; warm()\n"
)


class KernelWarmup:
    """One background process compiling the numba kernels; `ready()` once it has succeeded.
    `start(spawn)` takes the function that starts the child (a Supervisor's, so that the child
    ends with the server on every path)."""

    def __init__(self):
        self._proc: subprocess.Popen | None = None
        self._started = 0.0
        self._finished: float | None = None
        self._failed = False
        self._lock = threading.Lock()

    def start(self, spawn) -> "KernelWarmup":
        env = dict(os.environ)
        root = str(Path(__file__).resolve().parents[3])  # this package, wherever it was found
        env["PYTHONPATH"] = os.pathsep.join(p for p in (root, env.get("PYTHONPATH")) if p)
        with self._lock:
            self._started = time.monotonic()
            self._proc = spawn([sys.executable, "-c", WARM_CODE], env=env, stdin=subprocess.DEVNULL,
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        return self

    def _poll(self) -> None:
        with self._lock:
            if self._proc is None or self._finished is not None:
                return
            code = self._proc.poll()
            if code is not None:
                self._finished = time.monotonic()
                self._failed = code != 0

    def ready(self) -> bool:
        """Whether the kernels are compiled (False while compiling, and if compiling failed: the
        Python solvers then keep serving the sweep, one speed at a time)."""
        self._poll()
        return self._finished is not None and not self._failed

    def note(self) -> str:
        """A line for the page while the kernels compile ("" once done)."""
        self._poll()
        if self._proc is None or (self._finished is not None and not self._failed):
            return ""
        if self._failed:
            return "the compiled solver could not be prepared: the speed sweep stays at one speed at a time"
        seconds = time.monotonic() - self._started
        return (f"preparing the compiled solver in the background (first start after an install: about 30 s "
                f"on an idle machine; {seconds:.0f} s so far)")
