"""What every benchmark script here shares: median timing, a machine yardstick and the table.

Each script prints a table whose rows are the median of several runs and their ratio against a
baseline run in the same process (so the ratios compare across machines and load). Importing
this module also puts the checkout first on sys.path, so the scripts run without installing.
"""

from __future__ import annotations

import statistics
import sys
import time
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))


def median_times(functions: dict[str, Callable[[], object]], repeat: int, *, warmup: int = 2,
                 clock: Callable[[], float] = time.perf_counter) -> dict[str, float]:
    """Median time of each function over `repeat` runs, after `warmup` untimed runs (imports,
    caches). The functions take turns run by run, so that a change of machine load hits all alike."""
    for _ in range(warmup):
        for function in functions.values():
            function()
    samples: dict[str, list[float]] = {name: [] for name in functions}
    for _ in range(repeat):
        for name, function in functions.items():
            started = clock()
            function()
            samples[name].append(clock() - started)
    return {name: statistics.median(values) for name, values in samples.items()}


def median_time(function: Callable[[], object], repeat: int, *, warmup: int = 2,
                clock: Callable[[], float] = time.perf_counter) -> float:
    """Median time of one function (see median_times)."""
    return median_times({"": function}, repeat, warmup=warmup, clock=clock)[""]


def baseline_workload() -> float:
    """A fixed numpy job (1e6 sines and a cumulative sum) as the machine's yardstick."""
    import numpy as np

    x = np.linspace(0.0, 100.0, 1_000_000)
    return float(np.cumsum(np.sin(x))[-1])


def print_table(header: Sequence[str], rows: Iterable[Sequence[str]], indent: str = "") -> None:
    """Print already formatted cells in columns as wide as their widest cell: the first column
    (the case's name) left-aligned, the numbers right-aligned."""
    rows = [list(map(str, row)) for row in rows]
    widths = [max(len(cells[i]) for cells in [list(header), *rows]) for i in range(len(header))]
    for cells in [list(header), *rows]:
        first = cells[0].ljust(widths[0])
        print(indent + "  ".join([first, *(cell.rjust(w) for cell, w in zip(cells[1:], widths[1:]))]))
