"""The table of the elastic-linkage solvers (explorer/dynamics/), and `solve`, which runs one.

One line per solver (a SolverInfo: explorer/dynamics/solver_base.py lists, numbered, what a solver
must provide). Everyone who needs a fact about solvers reads it here: the scene loader (the
[solver] methods and their options), `solve`, the elastic effects, the gears' k(t) check, the
sweep engine's compiled path (batch_entry) and the benchmark (`explorer bench`: the piecewise
solver it times, the fixed-step ones and their stability limit, the reference). Adding a solver:
its module and one line of SOLVERS (or `register_solver(info)`); every solver in the table runs
the solver contract test (tests/test_solver_contract.py).

The module imports nothing heavy (no scipy, no solver module): the scene loader reads it while
parsing [solver], and a scene without the elastic effect loads no solver module
(tests/test_elastic_effect.py). A solver's module is imported when it first runs.
"""

from __future__ import annotations

from types import MappingProxyType

import numpy as np

from ..core.plugins import Registration, Registry
from .solver_base import Reference, SolverInfo, SolverOption, StabilityError, UnknownOptionError  # noqa: F401 (the solvers' API)

# solve_ivp methods the scipy solver offers (its scipy_method option, a scene's [solver] scipy_method)
_SOLVE_IVP_METHODS = ("RK45", "DOP853", "Radau", "LSODA", "BDF", "RK23")

SOLVERS: Registry[SolverInfo] = Registry("solver", {info.name: info for info in (
    SolverInfo("exact", "explorer.dynamics.exact:solve",
               "piecewise-exact closed forms per step, events to machine precision (constant k)",
               varying_stiffness=False, options=("initial_state", "zeno_height", "max_events", "chunk"),
               contract_tolerance_m=0.0, chain_entry="explorer.dynamics.chain_exact:solve",
               batch_entry="explorer.dynamics.exact_kernel:"),
    SolverInfo("exact-compiled", "explorer.dynamics.exact_kernel:solve",
               "the exact solver compiled: the same grid, closed forms, events and output (constant k)",
               varying_stiffness=False, options=("initial_state", "zeno_height", "max_events"),
               contract_tolerance_m=1e-15, batch_entry="explorer.dynamics.exact_kernel:"),
    SolverInfo("schenker1902", "explorer.dynamics.schenker1902:solve",
               "Schenker's 1902 fixed-step scheme (printed or Newmark), second order",
               varying_stiffness=True,
               options=("substeps", "variant", "masses", "allow_unstable", "initial_state", "rest_height"),
               stability_error=StabilityError, unstable_option="allow_unstable",
               stable_steps="explorer.dynamics.schenker1902:min_stable_steps", kind="fixed-step",
               contract_tolerance_m=1e-9),
    SolverInfo("scipy", "explorer.dynamics.reference:solve",
               "scipy solve_ivp with event detection: the reference",
               varying_stiffness=True,
               options=("scipy_method", "rtol", "atol", "max_step_fraction", "initial_state", "rest_height",
                        "watch_extrema", "tabulate"),
               scene_options=(SolverOption("scipy_method", "DOP853", choices=_SOLVE_IVP_METHODS),
                              SolverOption("rtol", 1e-10, minimum=1e-14, maximum=1e-1),
                              SolverOption("atol", 1e-13, minimum=1e-20, maximum=1e-1)),
               kind="adaptive", contract_tolerance_m=1e-11,
               chain_entry="explorer.dynamics.chain_reference:solve",
               reference=Reference("DOP853", fixed=MappingProxyType({"scipy_method": "DOP853"}),
                                   plain=MappingProxyType({"watch_extrema": False}))),
    SolverInfo("taylor", "explorer.dynamics.taylor:solve",
               "Taylor-series steps with polynomial k(t), events as polynomial roots",
               varying_stiffness=True, options=("initial_state", "zeno_height", "max_events", "max_rho_h"),
               contract_tolerance_m=1e-13),
)})

DEFAULT = "exact"  # the [solver] method of a scene that names none


def register_solver(info: SolverInfo, *, replace: bool = False) -> Registration:
    """Add a solver to the table (one call; `.undo()` removes it again)."""
    return SOLVERS.register(info.name, info, replace=replace)


def solver(name: str) -> SolverInfo:
    """The table entry of `name`; ValueError (one line, the known names) if there is none."""
    if name not in SOLVERS:
        raise ValueError(f"unknown solver method {name!r}; known: {', '.join(SOLVERS)}")
    return SOLVERS[name]


def names() -> tuple[str, ...]:
    return SOLVERS.names()


def varying_stiffness() -> tuple[str, ...]:
    """The methods that accept a stiffness k(t) changing along the cycle."""
    return tuple(name for name, info in SOLVERS.items() if info.varying_stiffness)


def of_kind(kind: str, varying: bool = False) -> tuple[str, ...]:
    """The methods of a kind ("piecewise", "fixed-step", "adaptive") in table order; varying: only
    those that accept a stiffness k(t)."""
    return tuple(name for name, info in SOLVERS.items() if info.kind == kind and (info.varying_stiffness or not varying))


def scene_options() -> dict[str, SolverOption]:
    """The [solver] fields of a scene that some solver takes as its options, by name (table
    order; the first solver that declares a name gives its parsing)."""
    out: dict[str, SolverOption] = {}
    for info in SOLVERS.entries():
        for option in info.scene_options:
            out.setdefault(option.name, option)
    return out


def reference() -> SolverInfo:
    """The reference solver (the one whose entry has a Reference)."""
    found = [info for info in SOLVERS.entries() if info.reference is not None]
    if len(found) != 1:
        raise RuntimeError(f"the solver table must have exactly one reference solver, has {len(found)}")
    return found[0]


def solve(model, drive, t, method: str = DEFAULT, **options):
    """Solve the linkage model with the table's solver `method` (ValueError: unknown method, an
    option value it does not take, or k(t) given to a solver that needs a constant stiffness;
    UnknownOptionError, a TypeError: an option the solver does not have)."""
    info = solver(method)
    if model.stiffness_profile is not None and not info.varying_stiffness:
        raise ValueError(f"method {method!r} needs a constant linkage stiffness; for a stiffness that changes "
                         f"along the cycle use {' or '.join(map(repr, varying_stiffness()))}")
    info.check_options(options)
    return info.function()(model, drive, np.asarray(t, dtype=float), **options)
