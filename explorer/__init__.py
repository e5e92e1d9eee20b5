"""Valve-Gear Explorer: cam and valve-train motion, forces and elastic dynamics.

    from explorer import load_scene, simulate
    result = simulate(load_scene("assets/scenes/schenker1902_fig2.toml"))
    result.columns["valve_lift_m"], result.summary["impact_velocity_opening_m_s"]

Viewers (viser, rerun) are imported only by the commands that use them.
"""

from .core.errors import InputError
from .core.version import __version__
from .scene.scene import Scene, load_scene, loads_scene

__all__ = ["InputError", "Scene", "check", "load_scene", "loads_scene", "simulate", "sweep", "__version__"]


def simulate(scene):
    """Compute the scene's effects over one revolution; returns a Result (.columns, .summary)."""
    from .effects.pipeline import simulate as _simulate

    return _simulate(scene)


def sweep(scene, vary=None, sample=None, **options):
    """Many runs of a scene, one row of figures each (explorer.studies.sweep_run.sweep):
    explorer.sweep("assets/scenes/valve_float_demo.toml", vary={"drive.rpm": "1000:6000:500"})"""
    from .studies.sweep_run import sweep as _sweep

    return _sweep(scene, vary, sample, **options)


def check(scene, rpm=None, sample=None, **options):
    """Design checks over the operating range and the tolerances (explorer.checks.run.check); a
    CheckReport (.results, .verdict, .to_json(), .to_csv(), .table_text()):
    explorer.check("assets/scenes/valve_float_demo.toml", rpm="800:6500:200")"""
    from .checks.run import check as _check

    return _check(scene, rpm, sample, **options)
