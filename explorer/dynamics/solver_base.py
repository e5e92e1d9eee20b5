"""What a solver of the elastic linkage is to the rest of the program: its table entry (SolverInfo),
its options (SolverOption), how it runs as a reference (Reference), and the errors it may raise.

The solver modules import this module, never the table (explorer/dynamics/solvers.py), which
names them: so no module both names and imports the other.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, Mapping

from ..core.plugins import resolve


class StabilityError(ValueError):
    """The step is too long for a fixed-step scheme to be stable (the solution would grow without
    bound). A solver that raises it names, in the table, the option that runs it anyway."""


class UnknownOptionError(TypeError):
    """A solver option the solver does not have (a TypeError, like any unexpected keyword)."""


@dataclass(frozen=True)
class SolverOption:
    """A keyword option of a solver that a scene may set in [solver] (the scene loader parses it
    from this entry: a choice among `choices`, or a number in [minimum, maximum])."""

    name: str
    default: Any
    choices: tuple[str, ...] = ()
    minimum: float | None = None
    maximum: float | None = None

    def check(self, solver: str, value: Any) -> None:
        """ValueError (one line) when `value` is not one this option takes."""
        if self.choices:
            if value not in self.choices:
                raise ValueError(f"solver {solver!r}: unknown {self.name} {value!r}; known: {', '.join(self.choices)}")
            return
        try:
            number = float(value)
        except (TypeError, ValueError):
            raise ValueError(f"solver {solver!r}: {self.name} must be a number, got {value!r}") from None
        if (self.minimum is not None and not number >= self.minimum) or (self.maximum is not None and not number <= self.maximum):
            raise ValueError(f"solver {solver!r}: {self.name} must lie in [{self.minimum:g}, {self.maximum:g}], got {value!r}")


@dataclass(frozen=True)
class Reference:
    """How a reference solver runs at a relative tolerance: the options it always takes (`fixed`,
    its method), `rtol` and `atol = atol_per_rtol * rtol` (m), and `plain`: the options that make it
    a solver as one would use it (no extra care for events), for timing it against another."""

    label: str  # what it is called in tables: "DOP853"
    fixed: Mapping[str, Any] = field(default_factory=lambda: MappingProxyType({}))
    atol_per_rtol: float = 1e-3
    plain: Mapping[str, Any] = field(default_factory=lambda: MappingProxyType({}))

    def options(self, rtol: float, plain: bool = False) -> dict:
        """The options of a run at `rtol` (`plain`: with the plain options too)."""
        out = {**self.fixed, "rtol": rtol, "atol": rtol * self.atol_per_rtol}
        if plain:
            out.update(self.plain)
        return out


@dataclass(frozen=True)
class SolverInfo:
    """One line of the solver table (explorer/dynamics/solvers.py): a solver of the linkage model.

    To add a solver you write its module and add one SolverInfo to the table. The solver must:

    1. Provide `entry`, a "module:function" with the signature
       ``solve(model, drive, t, **options) -> explorer.dynamics.model.DynamicsSolution``: `model`
       a LinkageModel, `drive` the valve-referred drive (drive(t) -> S, S', S'', S'''), `t` the
       sorted output times (s). It starts with the valve at rest on its seat at t[0] unless an
       `initial_state` option says otherwise.
    2. Return, at every output time, the valve's lift, velocity, acceleration and the linkage force
       (>= 0), whether the linkage is loaded, and the events of EVENT_KINDS (explorer.dynamics.model)
       as dicts with kind, time_s and, for impacts, velocity_m_s; optionally the jerk and the phase
       codes (None: the elastic effect derives the jerk from the phase ODEs).
    3. Accept exactly the keyword `options` listed here; `scene_options` are those a scene's
       [solver] table may set (parsed by the scene loader from their SolverOption, passed on by the
       elastic effect under the same name).
    4. Say what it takes: `varying_stiffness` (a LinkageModel whose stiffness_profile k(t) is set),
       `chain_entry` (the spring-chain model, spring.elements > 0; None: it takes only the massless
       spring), `batch_entry` (a module compiled for many runs of one scene at once, with the
       functions explorer.effects.elastic_batch calls; None: a sweep runs it run by run).
    5. Say how it steps (`kind`): "piecewise" (closed forms or series per output step, events to
       machine precision), "fixed-step" (events fall on its steps) or "adaptive" (its own steps to a
       tolerance, events by sign changes). A fixed-step scheme with a stability limit raises
       `stability_error` beyond it, names the option that runs it anyway (`unstable_option`) and
       the function giving its fewest stable steps per revolution (`stable_steps`).
    6. Meet `contract_tolerance_m` on the contract test's smooth cases (tests/test_solver_contract.py
       runs every solver of the table on them).
    7. At most one solver is the `reference`: the converged solution the others are measured
       against (explorer bench, tests); its Reference says how to run it at a tolerance.
    8. Import nothing heavy at module level that the table does not need: the table names the
       module; it is imported when the solver first runs.
    """

    name: str  # [solver] method in a scene, `method=` of solvers.solve
    entry: str  # "module:function" that runs it
    description: str
    varying_stiffness: bool  # accepts a LinkageModel with a stiffness_profile (k(t))
    options: tuple[str, ...]  # keyword options its function accepts
    scene_options: tuple[SolverOption, ...] = ()  # [solver] fields a scene passes on as options of the same name
    stability_error: type[Exception] | None = None  # raised beyond a stability limit, if it has one
    unstable_option: str | None = None  # the option (True) that runs it beyond that limit anyway
    # "module:function" (model, omega) -> the fewest equal steps per revolution it is stable with
    stable_steps: str | None = None
    kind: str = "piecewise"  # "piecewise", "fixed-step" or "adaptive" (item 5)
    # largest difference from the exact solution on the contract test's smooth cases (a rise in
    # contact over 6000 steps, a manufactured k(t) motion over 800) at default settings, m: what
    # this solver claims there (measured: schenker1902 2e-10, scipy 3e-13, taylor 8e-16, exact-compiled
    # 2e-17: the rounding of the same closed forms carried step by step)
    contract_tolerance_m: float = 0.0
    chain_entry: str | None = None  # "module:function" solving the spring-chain model (item 4)
    batch_entry: str | None = None  # "module:" compiled for many runs at once (item 4)
    reference: Reference | None = None  # the reference solver's settings (item 7)

    @property
    def fixed_step(self) -> bool:
        return self.kind == "fixed-step"

    def min_stable_steps(self, model, omega: float) -> int:
        """The fewest equal steps per revolution it is stable with (1: no stability limit)."""
        return 1 if self.stable_steps is None else resolve(self.stable_steps)(model, omega)

    def function(self):
        """The solver's `solve` function (imports its module)."""
        return resolve(self.entry)

    def chain_function(self):
        """The solver's function for the spring-chain model (imports its module), or None."""
        return None if self.chain_entry is None else resolve(self.chain_entry)

    def batch_module(self):
        """The compiled module for many runs at once (imports it, and numba), or None."""
        return None if self.batch_entry is None else resolve(self.batch_entry)

    def check_options(self, options) -> None:
        """UnknownOptionError for an option it does not have; ValueError for a scene option's value
        it does not take."""
        unknown = [name for name in options if name not in self.options]
        if unknown:
            raise UnknownOptionError(f"solver {self.name!r} has no option {unknown[0]!r}; "
                                     f"its options: {', '.join(self.options)}")
        for option in self.scene_options:
            if option.name in options:
                option.check(self.name, options[option.name])

    def unstable_options(self) -> dict:
        """Options that run it beyond its stability limit ({} for a solver without one)."""
        return {self.unstable_option: True} if self.unstable_option else {}
