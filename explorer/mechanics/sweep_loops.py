"""The rigid sweep figures' three compiled loops (mechanics/sweep_kernels.py: piece_minima,
peak_torques, zoom_minima) from the module compiled ahead of time by `make` when it was built from
sweep_kernels.py as it is now (explorer/core/aot.py: then the process loads no numba), else from
numba (sweep_kernels, loaded from numba's cache). The same floats either way
(tests/test_sweep_kernel.py). Imported only by the compiled sweep's rigid figures
(forces.min_contact_forces and its _zoom_minima; contact.peak_torques with compiled=True)."""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np

from ..core import aot

AOT_MODULE = "explorer.mechanics._sweep_kernels_aot"
SOURCE = Path(__file__).resolve().parent / "sweep_kernels.py"
# the module is current when built from both: the loops, and the exported signature below
SOURCES = (SOURCE, Path(__file__).resolve())


@functools.cache
def kernels() -> tuple:
    """(piece_minima, peak_torques, zoom_minima): the ahead-of-time module's when current, else
    sweep_kernels' (numba)."""
    module = aot.load(AOT_MODULE, list(SOURCES))
    if module is not None:
        return module.piece_minima, module.peak_torques, module.zoom_minima
    from .sweep_kernels import peak_torques, piece_minima, zoom_minima  # numba: only without a current AOT module

    return piece_minima, peak_torques, zoom_minima


def piece_minima(w2, a_coef, g_part, lows, highs):
    """sweep_kernels.piece_minima (the exported signature's types and layout)."""
    c = np.ascontiguousarray
    return kernels()[0](c(w2, dtype=float), c(a_coef, dtype=float), c(g_part, dtype=float), c(lows, dtype=np.intp),
                        c(highs, dtype=np.intp))


def peak_torques(w2, a_coef, g_part, push, pull, floor):
    """sweep_kernels.peak_torques (the exported signature's types and layout)."""
    c = np.ascontiguousarray
    return kernels()[1](c(w2, dtype=float), c(a_coef, dtype=float), c(g_part, dtype=float), c(push, dtype=float),
                        c(pull, dtype=float), float(floor))


def zoom_minima(lift_at, accel_at, w2, direction, ratio, lash, mass_ratio, preload, rate, friction, closing):
    """sweep_kernels.zoom_minima (the exported signature's types and layout)."""
    c = np.ascontiguousarray
    return kernels()[2](c(lift_at, dtype=float), c(accel_at, dtype=float), c(w2, dtype=float),
                        c(direction, dtype=float), float(ratio), float(lash), float(mass_ratio), float(preload),
                        float(rate), float(friction), float(closing))


def build_aot() -> float:
    """Compile sweep_kernels' three loops ahead of time (explorer/core/aot.py) for the argument types
    the functions above pass (sweep_kernels.aot_exports); the seconds it took. Here rather than in
    sweep_kernels so that the kernels' module does not import this one (which imports it)."""
    from ..core.aot_build import build
    from .sweep_kernels import aot_exports

    return build(AOT_MODULE, SOURCE.parent, aot_exports(), list(SOURCES))


if __name__ == "__main__":
    import sys

    if "--aot" in sys.argv[1:]:
        build_aot()
