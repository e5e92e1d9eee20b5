"""What the rules judge: a scene and its runs -- the speeds of the operating range, or draws of its
tolerances at a few speeds -- with the quantities several rules share, computed once and cached.

Runs are (draw, speed) pairs: N draws (N = 1 without tolerances) by the speeds a rule asks for.
The draws vary the sweep's keys (explorer.studies.sweep_spec.SWEEP_KEYS: lash, masses, spring
preload and rate, friction, linkage stiffness and damping, seat restitution); the cam is the same
in every run, so the lift and the gear's contact geometry are computed once.

Shared quantities:
- the lift L(theta) and its derivatives on the scene's grid (steps_per_revolution angles);
- the gear's contact (explorer.mechanics.gear_contact.GearContact, from the gear: Gear.cam_contact);
- the rigid contact force F = w^2 A(theta) + G(theta) of every run (explorer.mechanics.forces:
  A = M ratio L'', G = preload + rate s + R sgn v + closing, on the open samples) and the normal
  force on the cam N = F ratio_g / (cos a - mu sin|a| sgn v) of the contact statics, in blocks of
  draws (memory: draws x speeds x angles);
- the elastic figures of the runs (seating velocity, separations, bounces) from the sweep engine
  (explorer.studies.sweep_run.run_plan on the scene with its elastic effect only).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import Callable, Iterator

import numpy as np

from ..core.errors import InputError
from ..effects.contact import DYNAMIC_SOURCE
from ..effects.lift import build_lift
from ..effects.pipeline import RunCache, figures, simulate
from ..mechanics.contact import ContactSpec, WIDTH_RULE_WORDS, effective_modulus, hertz_width
from ..mechanics.forces import friction_direction
from ..mechanics.gear_contact import GearContact, NotApplicable
from ..mechanics.kinematics import lash_crossings
from ..mechanics.moving_mass import RigidMass, rigid_mass
from ..studies.sweep_engine import _Shared, compute_chunk, result_columns
from ..studies.sweep_run import run_plan
from ..studies.sweep_spec import Plan, scene_for

RPM = 2.0 * math.pi / 60.0
BLOCK_CELLS = 4_000_000  # draws x speeds x angles per block of the force arrays (32 MB of float64)
FEW_RUNS = 16  # elastic runs computed in this process with the check's own engine cache (else a sweep)


@dataclass(frozen=True)
class Draws:
    """The tolerance draws: one row per draw, one column per sweep key (SI; drive.rpm excluded)."""

    keys: tuple[str, ...]
    values: np.ndarray  # (N, k)
    text: tuple[str, ...] = ()  # the distributions as given, for the report


class Case:
    def __init__(self, scene, speeds_rpm, draws: Draws | None = None, focus: dict | None = None,
                 workers: int | None = None, progress: Callable | None = None,
                 speeds_from: tuple[str, str] = ("--rpm", "drive.rpm")):
        self.scene = scene
        # (file, key) a failed run at an operating speed is reported against
        self.speeds_from = speeds_from
        self.speeds = np.asarray(speeds_rpm, dtype=float)
        self.draws = draws
        # sampling: rule -> the speeds (rpm) it judges the draws at: where the nominal design is worst
        # (phase one), every speed of the range (phase two: explorer.checks.run)
        self.focus = dict(focus or {})
        self.workers = workers
        self.progress = progress
        self._elastic: dict = {}

    # -- the runs ------------------------------------------------------------------------------
    @property
    def sampling(self) -> bool:
        return self.draws is not None

    @property
    def n(self) -> int:
        return 1 if self.draws is None else int(self.draws.values.shape[0])

    def rule_speeds(self, rule: str, extra=(), ends: bool = False) -> np.ndarray:
        """The speeds a speed-dependent rule judges: the operating range; with tolerance draws the
        speed where the nominal design was worst for that rule, `extra`, and with `ends` the
        range's ends (cheap for the rigid rules; where a quantity that grows with the contact
        force F = w^2 A + G peaks over a range of speeds, at each angle)."""
        if not self.sampling:
            return self.speeds
        base = np.asarray(self.focus.get(rule, self.speeds[-1:]), dtype=float).ravel()
        parts = [base, np.asarray(extra, dtype=float).ravel()] + ([self.speeds] if ends else [])
        return np.unique(np.concatenate(parts))

    def param(self, key: str):
        """A sweep key's value per draw as an (N, 1) array, or the scene's value (float)."""
        if self.draws is not None and key in self.draws.keys:
            return self.draws.values[:, self.draws.keys.index(key)][:, None]
        section, field = key.split(".")
        part = getattr(self.scene, section)
        value = getattr(part, field) if part is not None else None
        if key == "valve.oscillating_mass" and value is None:
            return self.param("valve.mass")
        return value

    def sampled(self, key: str) -> bool:
        return self.draws is not None and key in self.draws.keys

    # -- geometry -----------------------------------------------------------------------------
    @cached_property
    def lift(self):
        return build_lift(self.scene)

    @cached_property
    def theta(self) -> np.ndarray:
        n = self.scene.solver.steps_per_revolution
        return np.arange(n) * (2.0 * math.pi / n)

    @cached_property
    def derivs(self) -> np.ndarray:
        return self.lift.derivatives(self.theta)

    @cached_property
    def theta_deg(self) -> np.ndarray:
        return np.degrees(self.theta)

    @cached_property
    def _contact(self):
        try:
            return self.scene.gear_plugin.cam_contact(self.scene, self.lift, self.theta)
        except NotApplicable as exc:
            return exc

    def contact(self) -> GearContact:
        """The gear's contact (NotApplicable when the scene has no cam contact)."""
        if isinstance(self._contact, NotApplicable):
            raise self._contact
        return self._contact

    @cached_property
    def contact_spec(self):
        return self.scene.contact if self.scene.contact is not None else ContactSpec()

    @cached_property
    def e_star(self) -> float:
        s = self.contact_spec
        return effective_modulus(s.youngs_modulus, s.poisson_ratio, s.roller_youngs_modulus, s.roller_poisson_ratio)

    # -- rigid loads --------------------------------------------------------------------------
    def needs_train(self) -> None:
        if self.scene.valve is None or self.scene.spring is None:
            raise NotApplicable("needs the valve train's loads: [valve] mass and [spring] preload and rate")

    @cached_property
    def rigid_mass(self) -> RigidMass:
        """valve.mass and the parts moving with it, referred to the valve (mechanics.moving_mass)."""
        return rigid_mass(self.scene)

    def valve_lift(self, lash=None) -> np.ndarray:
        """ratio L - lash (N, n) or (1, n): the valve's travel, > 0 where it is open."""
        lash = self.param("valve.lash") if lash is None else lash
        return self.scene.follower.ratio * self.derivs[0][None, :] - np.atleast_2d(np.asarray(lash, dtype=float))

    @cached_property
    def push_factor(self) -> np.ndarray:
        """N / F while the cam pushes (F > 0): ratio_g / (cos|a| - mu sin|a| sgn v); inf where
        the guide would lock (contact statics, explorer.mechanics.contact.contact_loads)."""
        g = self.contact().geometry
        alpha = np.abs(np.asarray(g.pressure_angle, dtype=float))
        v = np.sign(self.derivs[1])
        mu = math.tan(self.contact_spec.friction_angle)
        den = np.cos(alpha) - mu * np.sin(alpha) * v
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(den > 0.0, np.asarray(g.ratio, dtype=float) / np.where(den > 0.0, den, 1.0), np.inf)

    def force_parts(self, rows=slice(None)) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(A, G, open), each (b, n) for the draws `rows`: F = w^2 A + G where open."""
        self.needs_train()
        d = self.derivs
        ratio = self.scene.follower.ratio

        def p(key):
            v = self.param(key)
            return v[rows] if isinstance(v, np.ndarray) else np.float64(v)

        x = ratio * d[0][None, :] - np.atleast_2d(p("valve.lash"))
        is_open = x > 0.0
        s = np.where(is_open, x, 0.0)
        direction = friction_direction(d[1], d[2])[None, :]
        # the rigid train's mass: each draw's valve.mass plus the parts moving with it (the floats
        # of TrainLoads.from_scene's mass for the nominal design)
        a_coef = np.atleast_2d(self.rigid_mass.of_valve(p("valve.mass"))) * (ratio * d[2])[None, :]
        g_part = (np.atleast_2d(p("spring.preload")) + np.atleast_2d(p("spring.rate")) * s
                  + np.atleast_2d(p("loads.friction")) * direction + self.scene.loads.closing_total)
        shape = (max(a_coef.shape[0], g_part.shape[0]), d.shape[1])
        return np.broadcast_to(a_coef, shape), np.broadcast_to(g_part, shape), np.broadcast_to(is_open, shape)

    def blocks(self, speeds) -> Iterator[tuple[slice, np.ndarray, np.ndarray]]:
        """(rows, F (b, S, n) rigid contact force, 0 where closed, open (b, n)) per block of draws."""
        speeds = np.asarray(speeds, dtype=float)
        w2 = (speeds * RPM) ** 2
        n = self.theta.size
        per = max(1, BLOCK_CELLS // max(1, speeds.size * n))
        for start in range(0, self.n, per):
            rows = slice(start, min(self.n, start + per))
            a_coef, g_part, is_open = self.force_parts(rows if self.sampling else slice(None))
            force = w2[None, :, None] * a_coef[:, None, :] + g_part[:, None, :]
            force = np.where(is_open[:, None, :], force, 0.0)
            yield rows, force, is_open

    def normal(self, force: np.ndarray) -> np.ndarray:
        """The cam's normal force for rigid contact forces `force` (loaded only: F > 0, else 0)."""
        with np.errstate(invalid="ignore"):
            return np.where(force > 0.0, force * self.push_factor, 0.0)

    @cached_property
    def width(self) -> tuple[float, str]:
        """(contact width, how it was found): [contact] width, else the contact effect's width rule
        at the scene's own speed (the width the design has; it does not change with speed)."""
        spec = self.contact_spec
        if spec.width is not None:
            return spec.width, "[contact] width"
        a_coef, g_part, is_open = self.force_parts(slice(0, 1))
        force = np.where(is_open[0], self.scene.drive.omega ** 2 * a_coef[0] + g_part[0], 0.0)
        normal = self.normal(force)
        width, rule = hertz_width(normal, self.contact().geometry, spec, self.e_star)
        return width, f"{WIDTH_RULE_WORDS[rule]}, at {self.scene.drive.rpm:g} rpm"

    # -- elastic figures ----------------------------------------------------------------------
    def needs_linkage(self) -> None:
        if self.scene.linkage is None or self.scene.valve is None or self.scene.spring is None:
            raise NotApplicable("needs the elastic linkage: [linkage] stiffness, [valve], [spring]")

    def elastic(self, speeds) -> dict[str, np.ndarray]:
        """The sweep engine's elastic figures of every (draw, speed) run: name -> (N, S).

        Each speed's runs are computed once and kept: the rules that judge the same speeds (the
        seating velocity, the float margin's grid, the seat bounce) share them, and a call runs
        only the speeds not yet run. Many runs go through the sweep (run_plan: its workers and
        progress); a few (a bisection step of the float margin) go through the engine's chunk
        directly with one cache for the whole check (the lift, the lash take-up: a gear's lift is
        built once, not once per step). Either way each run's figures are the engine's, which do
        not depend on how the runs were cut into chunks (tests/test_sweep_engine.py)."""
        self.needs_linkage()
        speeds = np.asarray(speeds, dtype=float).ravel()
        missing = np.array(sorted({float(v) for v in speeds} - set(self._elastic)))
        if missing.size:
            n, s = self.n, missing.size
            keys = ("drive.rpm",) + (self.draws.keys if self.draws is not None else ())
            values = np.empty((n * s, len(keys)))
            values[:, 0] = np.tile(missing, n)
            if self.draws is not None:
                values[:, 1:] = np.repeat(self.draws.values, s, axis=0)
            scene = self.elastic_scene
            names = result_columns(scene)
            if n * s <= FEW_RUNS:
                columns = dict(zip(names, compute_chunk(scene, keys, values, names, self._shared).T))
            else:
                out = run_plan(scene, Plan(keys, values, (), (), None), workers=self.workers, progress=self.progress)
                if not out.complete:
                    raise KeyboardInterrupt
                columns = {name: out.columns[name] for name in names}
            self._refuse_failed(missing, np.asarray(columns["run_failed"], dtype=float).reshape(n, s))
            for j, speed in enumerate(missing):
                self._elastic[float(speed)] = {name: np.asarray(col, dtype=float).reshape(n, s)[:, j]
                                               for name, col in columns.items()}
        names = self._elastic[float(speeds[0])].keys() if speeds.size else ()
        return {name: np.stack([self._elastic[float(v)][name] for v in speeds], axis=1) for name in names}

    def _refuse_failed(self, speeds: np.ndarray, failed: np.ndarray) -> None:
        """A run that raised has NaN figures, which a rule would read as "no seat impact" or drop
        silently: an operating speed whose runs failed is refused (one line, exit 2) naming it.
        Speeds outside the range (the float margin's search above it) keep their NaN: that search
        reads a failed run as no separation found there."""
        bad = [float(v) for j, v in enumerate(speeds) if failed[:, j].any() and np.any(np.isclose(self.speeds, v))]
        if bad:
            shown = ", ".join(f"{v:g}" for v in bad[:6]) + (", ..." if len(bad) > 6 else "")
            file, key = self.speeds_from
            raise InputError(file, key, f"the engine cannot run the scene at {shown} rpm (see `explorer simulate "
                             f"{self.scene.source or 'SCENE'} --set drive.rpm={bad[0]:g}` for why, e.g. a speed too "
                             "slow for the solver's step budget): give a range without it")

    @cached_property
    def elastic_scene(self):
        """The scene with its elastic effect only (the figures the elastic rules read)."""
        return self.scene.with_changes(effects=("elastic",))

    @cached_property
    def _shared(self):
        return _Shared()

    def elastic_cam_force(self, rpm: float) -> np.ndarray | None:
        """The elastic train's cam force referred to the valve (N) at the check's angles, from one
        elastic revolution of the nominal design at `rpm` (the column the contact effect's dynamic
        figures read: effects.contact.DYNAMIC_SOURCE); None when the run is refused."""
        self.needs_linkage()
        effect, column = DYNAMIC_SOURCE
        scene = scene_for(self.scene.with_changes(effects=(effect,)), ("drive.rpm",), (rpm,))
        # the figures-only run (the kinematics without its exact summary peaks, which the
        # elastic effect does not read), the check's lift shared by every speed
        cache = RunCache(lift=self.lift if self.scene.gear_plugin.lift_reads(self.scene) == () else None)
        try:
            return np.asarray(figures(scene, cache).columns[column], dtype=float)
        except (InputError, RuntimeError, ValueError, ArithmeticError):
            return None

    def elastic_event_angle(self, rpm: float, kind: str, pick: str = "first", draw: int = 0) -> float:
        """Cam angle (deg) of an elastic event of one run, from `simulate` (for "where")."""
        scene = self.elastic_scene
        if self.draws is not None:
            scene = scene_for(scene, self.draws.keys, self.draws.values[draw])
        scene = scene_for(scene, ("drive.rpm",), (rpm,))
        # the check's lift when the scene's lift reads none of the run's values (a gear's is costly)
        lift = self.lift if self.draws is None and self.scene.gear_plugin.lift_reads(self.scene) == () else None
        try:
            events = [e for e in simulate(scene, lift=lift).events if e["kind"] == kind
                      and e.get("effect", "elastic") == "elastic"]
        except (InputError, RuntimeError, ValueError, ArithmeticError):
            return math.nan
        if not events:
            return math.nan
        if pick == "hardest":
            return float(min(events, key=lambda e: e.get("velocity_m_s", 0.0))["cam_angle_deg"])
        if pick == "second":
            return float(events[1]["cam_angle_deg"]) if len(events) > 1 else math.nan
        return float(events[0]["cam_angle_deg"])


def reduce_angles(values: np.ndarray, sense: str, theta_deg: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(worst over the last axis, its angle in degrees); NaN where a row is all NaN."""
    v = np.asarray(values, dtype=float)
    filled = np.where(np.isnan(v), -np.inf if sense == "max" else np.inf, v)
    idx = np.argmax(filled, axis=-1) if sense == "max" else np.argmin(filled, axis=-1)
    worst = np.take_along_axis(v, idx[..., None], axis=-1)[..., 0]
    angle = np.where(np.isnan(worst), np.nan, theta_deg[idx])
    return worst, angle


def lash_crossing_angles(case: Case, kind: str) -> np.ndarray:
    """Cam angle (rad) per draw, (N,), where ratio L crosses the draw's lash: "up" the lash take-up
    (the valve lifts), "down" the seating. The nominal lash's is explorer.mechanics.kinematics.
    lash_crossings' (Brent on the analytic lift); the draws' are Newton steps from it on the same
    lift, vectorised (a draw's lash differs by a tolerance: the crossing moves along the ramp).
    NaN where the valve never opens."""
    lift, ratio = case.lift, case.scene.follower.ratio
    lash0 = case.scene.valve.lash if case.scene.valve is not None else 0.0
    ups, downs = lash_crossings(lift, ratio, lash0)
    roots = ups if kind == "up" else downs
    if roots.size == 0:
        return np.full(case.n, np.nan)
    if kind == "up":
        theta0 = float(roots[0])
    else:  # the seating that closes the first opening
        after = np.mod(roots - float(ups[0]) if ups.size else roots, 2.0 * math.pi)
        theta0 = float(roots[int(np.argmin(after))])
    if not case.sampled("valve.lash"):
        return np.full(case.n, theta0)
    lash = case.param("valve.lash")[:, 0]
    theta = np.full(lash.shape, theta0)
    for _ in range(40):  # Newton on a monotone ramp converges in a few steps; bounded
        d = lift.derivatives(theta)
        slope = ratio * d[1]
        with np.errstate(divide="ignore", invalid="ignore"):
            step = (ratio * d[0] - lash) / slope
        step = np.where(np.isfinite(step), np.clip(step, -0.05, 0.05), np.nan)
        theta = theta - step
        if np.all(~np.isfinite(step) | (np.abs(step) <= 1e-14)):
            break
    d = lift.derivatives(np.where(np.isfinite(theta), theta, theta0))
    ok = np.isfinite(theta) & (np.abs(ratio * d[0] - lash) <= 1e-12 + 1e-9 * abs(lash0))
    return np.where(ok, np.mod(theta, 2.0 * math.pi), np.nan)
