"""The registry of the elastic-linkage solvers (explorer/dynamics/): one table, read by the scene
loader, the model's `solve()`, the elastic effect, the gears' k(t) check, the scipy solver's
method check and the benchmark (`explorer bench`: which solver it times as the piecewise one,
the fixed-step ones and their stability limit).

Adding a solver: write its module (a `solve(model, drive, t, **options) -> DynamicsSolution`) and
add one line to SOLVERS below. Every solver in the table runs the solver contract test
(tests/test_solver_contract.py).

The module imports nothing heavy (no numpy, no scipy, no other module of explorer.dynamics, whose
__init__ imports nothing): the scene loader reads it when it parses a [solver] table (`import
explorer` does not load it), and a scene without the elastic effect loads no solver module
(tests/test_elastic_effect.py). A solver's module is imported when it first runs.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass


class StabilityError(ValueError):
    """The step is too long for a fixed-step scheme to be stable (the solution would grow without
    bound). A solver that raises it names, in the table, the option that runs it anyway."""


class UnknownOptionError(TypeError):
    """A solver option the solver does not have (a TypeError, like any unexpected keyword)."""


@dataclass(frozen=True)
class SolverInfo:
    name: str  # [solver] method in a scene, `method=` of model.solve
    entry: str  # "module:function" that runs it
    description: str
    varying_stiffness: bool  # accepts a LinkageModel with a stiffness_profile (k(t))
    options: tuple[str, ...]  # keyword options its function accepts
    scene_options: tuple[str, ...] = ()  # [solver] fields a scene passes on as options of the same name
    stability_error: type[Exception] | None = None  # raised beyond a stability limit, if it has one
    unstable_option: str | None = None  # the option (True) that runs it beyond that limit anyway
    # "module:function" (model, omega) -> the fewest equal steps per revolution it is stable with
    stable_steps: str | None = None
    # how it steps: "piecewise" (closed forms or series per step of the output grid, events to
    # machine precision), "fixed-step" (events fall on its steps, located within one step, not at
    # their instant), "adaptive" (its own steps to a tolerance, events by sign changes)
    kind: str = "piecewise"
    # largest difference from the exact solution on the contract test's smooth cases (a rise in
    # contact over 6000 steps, a manufactured k(t) motion over 800) at default settings, m: what
    # this solver claims there (measured: schenker1902 2e-10, scipy 3e-13, taylor 8e-16)
    contract_tolerance_m: float = 0.0
    # "module:function" that solves the spring-chain model (spring.elements > 0), None when this
    # solver takes only the massless spring
    chain_entry: str | None = None

    @property
    def fixed_step(self) -> bool:
        return self.kind == "fixed-step"

    def min_stable_steps(self, model, omega: float) -> int:
        """The fewest equal steps per revolution it is stable with (1: no stability limit)."""
        if self.stable_steps is None:
            return 1
        module, _, name = self.stable_steps.partition(":")
        return getattr(importlib.import_module(module), name)(model, omega)

    def function(self):
        """The solver's `solve` function (imports its module)."""
        module, _, name = self.entry.partition(":")
        return getattr(importlib.import_module(module), name)

    def chain_function(self):
        """The solver's function for the spring-chain model (imports its module), or None."""
        if self.chain_entry is None:
            return None
        module, _, name = self.chain_entry.partition(":")
        return getattr(importlib.import_module(module), name)

    def check_options(self, options) -> None:
        unknown = [name for name in options if name not in self.options]
        if unknown:
            raise UnknownOptionError(f"solver {self.name!r} has no option {unknown[0]!r}; "
                                     f"its options: {', '.join(self.options)}")

    def unstable_options(self) -> dict:
        """Options that run it beyond its stability limit ({} for a solver without one)."""
        return {self.unstable_option: True} if self.unstable_option else {}


# solve_ivp methods the scipy solver offers (its scipy_method option, a scene's [solver] scipy_method)
SCIPY_METHODS = ("RK45", "DOP853", "Radau", "LSODA", "BDF", "RK23")

SOLVERS: dict[str, SolverInfo] = {info.name: info for info in (
    SolverInfo("exact", "explorer.dynamics.exact:solve",
               "piecewise-exact closed forms per step, events to machine precision (constant k)",
               varying_stiffness=False, options=("initial_state", "zeno_height", "max_events", "chunk"),
               contract_tolerance_m=0.0, chain_entry="explorer.dynamics.chain_exact:solve"),
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
               scene_options=("scipy_method", "rtol", "atol"), kind="adaptive", contract_tolerance_m=1e-11,
               chain_entry="explorer.dynamics.chain_reference:solve"),
    SolverInfo("taylor", "explorer.dynamics.taylor:solve",
               "Taylor-series steps with polynomial k(t), events as polynomial roots",
               varying_stiffness=True, options=("initial_state", "zeno_height", "max_events", "max_rho_h"),
               contract_tolerance_m=1e-13),
)}


def solver(name: str) -> SolverInfo:
    """The table entry of `name`; ValueError (one line, the known names) if there is none."""
    try:
        return SOLVERS[name]
    except KeyError:
        raise ValueError(f"unknown solver method {name!r}; known: {', '.join(SOLVERS)}") from None


def names() -> tuple[str, ...]:
    return tuple(SOLVERS)


def varying_stiffness() -> tuple[str, ...]:
    """The methods that accept a stiffness k(t) changing along the cycle."""
    return tuple(name for name, info in SOLVERS.items() if info.varying_stiffness)


def of_kind(kind: str, varying: bool = False) -> tuple[str, ...]:
    """The methods of a kind ("piecewise", "fixed-step", "adaptive") in table order; varying: only
    those that accept a stiffness k(t)."""
    return tuple(name for name, info in SOLVERS.items() if info.kind == kind and (info.varying_stiffness or not varying))


def scene_options() -> tuple[str, ...]:
    """The [solver] fields of a scene that some solver takes as its options (table order)."""
    return tuple(dict.fromkeys(name for info in SOLVERS.values() for name in info.scene_options))
