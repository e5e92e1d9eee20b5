"""Valve-Gear Explorer: cam and valve-train motion, forces and elastic dynamics.

    from explorer import load_scene, simulate
    result = simulate(load_scene("assets/scenes/schenker1902_fig2.toml"))
    result.columns["valve_lift_m"], result.summary["impact_velocity_opening_m_s"]

Viewers (viser, rerun) are imported only by the commands that use them. The API's names are
loaded when first used (PEP 562): `import explorer` itself reads no table and no numpy, so a
command's help or a tool that only needs InputError starts at once.
"""

from importlib import import_module
from typing import TYPE_CHECKING

from .core.errors import InputError
from .core.version import __version__

__all__ = ["InputError", "Scene", "check", "load_scene", "loads_scene", "simulate", "sweep", "__version__"]

if TYPE_CHECKING:  # for type checkers and the API reference (mkdocstrings); at run time: __getattr__
    from .checks.run import check
    from .effects.pipeline import simulate
    from .scene.scene import Scene, load_scene, loads_scene
    from .studies.sweep_run import sweep

# name -> the module that defines it (relative to this package)
_API = {
    "Scene": ".scene.scene",
    "load_scene": ".scene.scene",
    "loads_scene": ".scene.scene",
    "simulate": ".effects.pipeline",
    "sweep": ".studies.sweep_run",
    "check": ".checks.run",  # design checks over the speed range and tolerances: a CheckReport
}


def __getattr__(name: str):
    if name not in _API:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(import_module(_API[name], __name__), name)
    globals()[name] = value  # once: later lookups find it directly
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_API))
