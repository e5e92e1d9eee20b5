"""What accuracy costs in time: every dynamics solver at every resolution on one scene.

For the scene's elastic model (valve, spring, loads, linkage) over one camshaft revolution:
  exact         piecewise-exact, at 90 ... 360 000 steps per revolution
  exact-compiled  the same compiled (the table's other closed-form piecewise solvers), the same grids
  schenker1902  the 1902 scheme at the same steps, where it is stable (h < 0.390 Tn)
  scipy         solve_ivp DOP853 with events, rtol 1e-3 ... 1e-12 (atol = rtol/1000 m), on the
                scene's own output grid; plain sign-change event detection and the step bounded
                by Tn/4 -- solve_ivp as one would use it (the reference also watches the event
                functions' extrema, to catch double crossings)
Each run: the largest valve-lift error against a converged reference computed by the *other*
kind of method, so that nothing is measured against itself -- exact and schenker1902 against
scipy DOP853 at rtol 1e-12, scipy against exact at the finest grid (the two references are
cross-checked against each other) -- CPU time (median over repeats, of time.process_time; wall
time too) and the events found. The speed ratio the project promises --
exact at default settings against scipy DOP853 at rtol 1e-10 -- is measured side by side in
this process, alternating the two. The kinematic side: differentiating a measured (`table`)
lift, the errors of v and p against sample count and noise (explorer.studies.accuracy).

A linkage whose stiffness changes along the cycle (a rolling lever's k(t)) cannot be run by the
exact solver (constant coefficients): the `taylor` solver (the same piecewise idea with
polynomial coefficients) takes its place in every row, the cross-check and the speed ratio, and
the grids stop at 36 000 steps (scipy tabulates the drive and k(t) at 4 nodes a step).

    report = run_bench(scene, quick=True)
    print(report.table()); write_chart(report, "bench.png")
"""

from __future__ import annotations

import math
import statistics
import time
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from ..core.errors import InputError
from ..dynamics import solvers as solver_registry
from ..dynamics.model import Drive
from ..dynamics.solvers import solve
from ..effects.elastic import linkage_model
from ..effects.lift import build_lift
from .accuracy import differentiation_study
from .charts import figure, png

STEPS = (90, 360, 900, 3600, 9000, 36_000, 90_000, 360_000)
VARYING_MAX_STEPS = 36_000
QUICK_STEPS = (90, 900, 3600)
RTOLS = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12)
QUICK_RTOLS = (1e-4, 1e-8)
REFERENCE_RTOL = 1e-12
RATIO_RTOL = 1e-10  # the baseline of the speed target (issue 4): DOP853, events, step bounded
LONG_RUN_S = 0.5  # CPU s: a run this long is timed once; its median would cost minutes for nothing
TARGET_ERROR_M = 1e-8  # the accuracy the default settings must reach on a scene with separation
DIFF_QUICK = dict(samples=(90, 180), noise_m=(0.0, 1e-5))


@dataclass(frozen=True)
class Run:
    method: str  # exact, schenker1902, scipy
    setting: str  # "3600 steps" or "DOP853 rtol 1e-08"
    steps: int  # output points per revolution (the step count for the fixed-step solvers)
    rtol: float | None
    max_error_m: float  # largest |s - s_ref| over the output grid
    cpu_time_s: float  # median of process_time over the repeats
    wall_time_s: float  # median of perf_counter
    repeats: int
    events: int
    event_kinds: str  # e.g. "lift-off separation re-contact seat"
    solver_steps: int | None = None  # internal steps (scipy) or steps (fixed-step solvers)
    nfev: int | None = None  # right-hand-side evaluations (scipy)


@dataclass(frozen=True)
class SpeedRatio:
    steps: int
    repeats: int
    exact_cpu_s: float
    scipy_cpu_s: float
    exact_error_m: float
    scipy_error_m: float
    method: str = solver_registry.DEFAULT  # the piecewise solver timed ("taylor" for a stiffness k(t))
    baseline: str = ""  # the reference solver and its method, as the table names them ("scipy DOP853")

    @property
    def ratio(self) -> float:
        return self.scipy_cpu_s / self.exact_cpu_s if self.exact_cpu_s > 0 else math.inf

    @property
    def equal_or_better(self) -> bool:
        """exact at least as accurate as the baseline (up to the reference's own 1e-12 m noise)."""
        return self.exact_error_m <= max(self.scipy_error_m, 1e-12)

    def text(self) -> str:
        verdict = "equal or better accuracy" if self.equal_or_better else "LESS accurate than the baseline"
        return (
            f"speed ratio at {self.steps} steps, median of {self.repeats} alternating runs: "
            f"{self.method} {1e3 * self.exact_cpu_s:.2f} ms (error {self.exact_error_m:.2e} m) vs {self.baseline} rtol "
            f"{RATIO_RTOL:g} {1e3 * self.scipy_cpu_s:.2f} ms (error {self.scipy_error_m:.2e} m): "
            f"{self.ratio:.1f}x faster, {verdict}"
            + (" (target >= 30x, goal 100x)" if self.method == solver_registry.DEFAULT else "")
        )


@dataclass(frozen=True)
class BenchReport:
    scene: str
    rpm: float
    default_steps: int
    natural_period_s: float
    revolution_s: float
    reference: str
    reference_check_m: float  # max |scipy reference - exact at the finest grid| (the two references)
    reference_events: tuple[str, ...]
    runs: tuple[Run, ...]
    ratio: SpeedRatio | None  # None when no ratio was measured
    notes: tuple[str, ...] = ()
    differentiation: Any = None  # explorer.studies.accuracy.DifferentiationStudy, or None
    check_method: str = solver_registry.DEFAULT  # what the reference solver was cross-checked against
    reference_solver: str = ""  # the reference solver's name in the table ("scipy")

    def table(self) -> str:
        lines = [
            f"explorer bench: {self.scene} at {self.rpm:g} rpm (revolution {1e3 * self.revolution_s:.3f} ms, "
            f"natural period Tn {1e3 * self.natural_period_s:.4f} ms)",
            f"reference: {self.reference}",
            f"references cross-checked: |{self.reference_solver} rtol {REFERENCE_RTOL:g} - {self.check_method}| <= "
            f"{self.reference_check_m:.1e} m",
            f"reference events: {' '.join(self.reference_events) or 'none'}",
            "",
            f"{'method':<15} {'setting':<20} {'max error m':>12} {'CPU ms':>10} {'wall ms':>10} {'runs':>4} {'events':>6} {'steps':>8} {'nfev':>8}",
        ]
        for r in self.runs:
            lines.append(
                f"{r.method:<15} {r.setting:<20} {r.max_error_m:12.2e} {1e3 * r.cpu_time_s:10.2f} {1e3 * r.wall_time_s:10.2f} "
                f"{r.repeats:4d} {r.events:6d} {r.solver_steps if r.solver_steps is not None else '':>8} "
                f"{r.nfev if r.nfev is not None else '':>8}"
            )
        lines += ["", self.ratio.text() if self.ratio is not None else
                  "speed ratio: not measured (no exact solver for a stiffness that changes along the cycle)"]
        lines += [f"note: {n}" for n in self.notes]
        if self.differentiation is not None:
            lines += ["", self.differentiation.format()]
        return "\n".join(lines) + "\n"

    def csv_text(self) -> str:
        names = [f for f in Run.__dataclass_fields__]
        out = [",".join(names)]
        for r in self.runs:
            out.append(",".join(_csv_cell(getattr(r, n)) for n in names))
        return "\n".join(out) + "\n"

    def pareto(self) -> list[Run]:
        """Runs that no other run beats in both CPU time and error (sorted by time)."""
        front, best = [], math.inf
        for r in sorted(self.runs, key=lambda r: (r.cpu_time_s, r.max_error_m)):
            if r.max_error_m < best:
                front.append(r)
                best = r.max_error_m
        return front


def _csv_cell(value) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return repr(value)
    text = str(value)
    return f'"{text}"' if "," in text else text


def model_and_drive(scene):
    """The LinkageModel and Drive of a scene (needs [valve], [spring] and [linkage])."""

    for section in ("valve", "spring", "linkage"):
        if getattr(scene, section) is None:
            raise InputError(scene.source, section, f"missing section: explorer bench times the elastic model, which needs [{section}]")
    lift = build_lift(scene)  # a gear's own elasticity (k(t)) is part of the model, as in the elastic effect
    return linkage_model(scene, lift, scene.drive.omega), Drive(lift, scene.follower.ratio, scene.drive.omega)


def _timed(fn: Callable[[], Any], repeats: int):
    """(result, median CPU s, median wall s, runs): a run longer than LONG_RUN_S is not repeated."""
    cpu, wall = [], []
    result = None
    for i in range(max(1, repeats)):
        c0, w0 = time.process_time(), time.perf_counter()
        result = fn()
        cpu.append(time.process_time() - c0)
        wall.append(time.perf_counter() - w0)
        if cpu[-1] > LONG_RUN_S:
            break
    return result, statistics.median(cpu), statistics.median(wall), len(cpu)


def run_bench(
    scene,
    quick: bool = False,
    repeats: int = 3,
    progress: Callable[[int, int, str], None] | None = None,
    differentiation: bool = True,
) -> BenchReport:
    """Time every method and resolution on the scene; see the module docstring."""
    model, drive = model_and_drive(scene)
    varying = model.stiffness_profile is not None
    revolution = 2.0 * math.pi / drive.omega
    default_steps = scene.solver.steps_per_revolution
    steps = QUICK_STEPS if quick else STEPS
    if varying:  # the tabulated k(t) of the finest reference grows with the grid: stop at 36 000
        steps = tuple(n for n in steps if n <= VARYING_MAX_STEPS)
    rtols = QUICK_RTOLS if quick else RTOLS
    finest = max(steps)
    # the solvers, by their kind in the registry: the first piecewise one that takes this model,
    # every fixed-step one at the steps where it is stable, scipy (the adaptive reference) by rtol
    fast = solver_registry.of_kind("piecewise", varying)[0]
    # the other piecewise solvers of the same model at the same grids: for a constant k those that
    # need it (closed forms: the exact solver compiled), not the k(t) ones (taylor: 100x slower
    # there, it runs in fast's place for a k(t) only)
    also = tuple(name for name in solver_registry.of_kind("piecewise", varying)[1:]
                 if not varying and not solver_registry.solver(name).varying_stiffness)
    fixed = solver_registry.of_kind("fixed-step", varying)
    ref_info = solver_registry.reference()
    ref_name, ref_setting = ref_info.name, ref_info.reference
    ref_label = f"{ref_name} {ref_setting.label}"
    min_stable = {name: solver_registry.solver(name).min_stable_steps(model, drive.omega) for name in fixed}
    stable_steps = {name: [n for n in steps if n >= min_stable[name]] for name in fixed}
    ratio_repeats = max(5, repeats)

    total = (2 + len(steps) * (1 + len(also)) + sum(map(len, stable_steps.values())) + len(rtols) + 1
             + (1 if differentiation else 0))
    done = 0

    def tick(label: str) -> None:
        nonlocal done
        if progress is not None:
            progress(done, total, label)
        done += 1

    # like the elastic effect, start the revolution where the drive is lowest: the valve surely
    # rests on its seat there, so every solver starts from the same, true state
    t_default_grid = np.arange(default_steps) * (revolution / default_steps)
    t0 = float(t_default_grid[int(np.argmin(drive(t_default_grid)[0]))])

    def grid(n: int) -> np.ndarray:
        return t0 + np.arange(n) * (revolution / n)

    tick(f"reference: {ref_label} rtol {REFERENCE_RTOL:g} at {finest} steps")
    t_fine = grid(finest)
    ref = solve(model, drive, t_fine, method=ref_name, **ref_setting.options(REFERENCE_RTOL))
    references = {finest: ref.s}

    def reference_on(n: int) -> np.ndarray:
        if n not in references:
            if finest % n == 0:
                references[n] = ref.s[:: finest // n]
            else:
                references[n] = solve(model, drive, grid(n), method=ref_name, **ref_setting.options(REFERENCE_RTOL)).s
        return references[n]

    def t_on(n: int) -> np.ndarray:
        return t_fine[:: finest // n] if finest % n == 0 else grid(n)

    def record(method, setting, n, rtol, fn) -> Run:
        sol, cpu, wall, runs = _timed(fn, repeats)
        stats = sol.stats or {}
        truth = fast_on(n) if method == ref_name else reference_on(n)
        return Run(
            method=method, setting=setting, steps=n, rtol=rtol,
            max_error_m=float(np.abs(sol.s - truth).max()),
            cpu_time_s=cpu, wall_time_s=wall, repeats=runs, events=len(sol.events),
            event_kinds=" ".join(e["kind"] for e in sol.events),
            solver_steps=int(stats["steps"]) if "steps" in stats else None,
            nfev=int(stats["nfev"]) if "nfev" in stats else None,
        )

    runs: list[Run] = []
    notes: list[str] = []
    # warm-up: the first call of each solver pays for imports and caches, not for the method
    for method in (fast, *also, *fixed, ref_name):
        options = solver_registry.solver(method).unstable_options()
        solve(model, drive, grid(360), method=method, **options)

    for n in steps:
        tick(f"{fast} at {n} steps")
        t = t_on(n)
        runs.append(record(fast, f"{n} steps", n, None, lambda t=t: solve(model, drive, t, method=fast)))
    tick(f"cross-check: {fast} at {finest} steps against the {ref_name} reference")
    fast_fine = solve(model, drive, t_fine, method=fast)
    reference_check = float(np.abs(fast_fine.s - ref.s).max())
    if varying:
        first = solver_registry.of_kind("piecewise")[0]
        notes.append(f"{first} replaced by {fast}: the linkage stiffness changes along the cycle (k(t)) and the {first} "
                     "solver's closed forms need constant coefficients")

    def fast_on(n: int) -> np.ndarray:
        if finest % n == 0:
            return fast_fine.s[:: finest // n]
        return solve(model, drive, grid(n), method=fast).s
    for method in also:
        for n in steps:
            tick(f"{method} at {n} steps")
            t = t_on(n)
            runs.append(record(method, f"{n} steps", n, None, lambda t=t, m=method: solve(model, drive, t, method=m)))
    for method in fixed:
        for n in stable_steps[method]:
            tick(f"{method} at {n} steps")
            t = t_on(n)
            runs.append(record(method, f"{n} steps", n, None, lambda t=t, m=method: solve(model, drive, t, method=m)))
        skipped = [n for n in steps if n < min_stable[method]]
        if skipped:
            notes.append(
                f"{method} skipped at {', '.join(map(str, skipped))} steps: unstable beyond h = "
                f"{revolution / min_stable[method] / model.natural_period():.3f} Tn (needs >= {min_stable[method]} "
                "steps per revolution)"
            )
    t_default = t_on(default_steps)
    for rtol in rtols:
        tick(f"{ref_label} rtol {rtol:g}")
        runs.append(record(
            ref_name, f"{ref_setting.label} rtol {rtol:.0e}", default_steps, rtol,
            lambda rtol=rtol: solve(model, drive, t_default, method=ref_name, **ref_setting.options(rtol, plain=True)),
        ))

    tick(f"speed ratio: {fast} vs {ref_label} rtol 1e-10, alternating")
    ratio = speed_ratio(model, drive, t_default, reference_on(default_steps), ratio_repeats, fast_on(default_steps),
                        method=fast)
    if ratio.exact_error_m > TARGET_ERROR_M:
        notes.append(f"{fast} at {default_steps} steps misses the {TARGET_ERROR_M:g} m target: {ratio.exact_error_m:.2e} m")

    study = None
    if differentiation:
        tick("differentiating a measured lift (samples x noise)")
        options = DIFF_QUICK if quick else {}
        study = differentiation_study(lift=build_lift(scene), rpm=scene.drive.rpm, reference=f"{scene.name} lift", **options)
    if progress is not None:
        progress(total, total, "done")

    return BenchReport(
        scene=scene.name, rpm=scene.drive.rpm, default_steps=default_steps, natural_period_s=model.natural_period(),
        revolution_s=revolution,
        reference=(f"{' and '.join((fast, *also, *fixed))} against {ref_label} rtol {REFERENCE_RTOL:g} atol "
                   f"{ref_setting.options(REFERENCE_RTOL)['atol']:g} m (events, max step Tn/4"
                   f"{', drive and k(t) tabulated' if varying else ''}); {ref_name} against {fast}; both at {finest} steps"),
        reference_check_m=reference_check, reference_events=tuple(e["kind"] for e in ref.events),
        runs=tuple(runs), ratio=ratio, notes=tuple(notes), differentiation=study, check_method=fast,
        reference_solver=ref_name,
    )


def speed_ratio(model, drive, t: np.ndarray, reference: np.ndarray, repeats: int = 7,
                reference_for_scipy: np.ndarray | None = None, method: str = solver_registry.DEFAULT) -> SpeedRatio:
    """`method` (the exact solver) vs the reference solver as one would use it (scipy DOP853)
    at rtol 1e-10 (atol 1e-13, events, step bounded) on the grid t, alternating the two `repeats`
    times in this process; median CPU times and lift errors (`method` against `reference`, the
    reference solver against `reference_for_scipy`, default the same)."""
    ref_info = solver_registry.reference()

    def exact():
        return solve(model, drive, t, method=method)

    def baseline():
        return solve(model, drive, t, method=ref_info.name, **ref_info.reference.options(RATIO_RTOL, plain=True))

    exact(), baseline()  # warm-up
    cpu_exact, cpu_scipy = [], []
    for _ in range(max(1, repeats)):
        c0 = time.process_time()
        sol_exact = exact()
        c1 = time.process_time()
        sol_scipy = baseline()
        c2 = time.process_time()
        cpu_exact.append(c1 - c0)
        cpu_scipy.append(c2 - c1)
    return SpeedRatio(
        steps=t.size, repeats=max(1, repeats),
        exact_cpu_s=statistics.median(cpu_exact), scipy_cpu_s=statistics.median(cpu_scipy),
        exact_error_m=float(np.abs(sol_exact.s - reference).max()),
        scipy_error_m=float(np.abs(sol_scipy.s - (reference if reference_for_scipy is None else reference_for_scipy)).max()),
        method=method, baseline=f"{ref_info.name} {ref_info.reference.label}",
    )


# one style per solver, in the table's order (a solver new to the table gets the next one)
STYLES = (dict(color="#1f77b4", marker="o"), dict(color="#d62728", marker="s"), dict(color="#2ca02c", marker="^"),
          dict(color="#9467bd", marker="D"), dict(color="#8c564b", marker="v"), dict(color="#e377c2", marker="P"))


def style(method: str) -> dict:
    names = solver_registry.names()
    i = names.index(method) if method in names else len(names)
    return STYLES[i % len(STYLES)]


FLOOR_M = 1e-16  # errors of exactly 0 drawn here on the log axis


def chart_png(report: BenchReport) -> bytes:
    """Error versus CPU time, log-log, one series per method, the Pareto front dashed."""
    with figure(figsize=(8.0, 5.6), dpi=110) as (fig, ax):
        for method in dict.fromkeys(r.method for r in report.runs):
            rows = [r for r in report.runs if r.method == method]
            look = style(method)
            x = [max(r.cpu_time_s, 1e-6) for r in rows]
            y = [max(r.max_error_m, FLOOR_M) for r in rows]
            varying = method == report.check_method and "k(t)" in report.reference  # (in exact's place)
            setting = solver_registry.solver(method).reference if method in solver_registry.SOLVERS else None
            label = (f"{method} {setting.label if setting else ''} (rtol)" if rows[0].rtol is not None
                     else f"{method}{', k(t)' if varying else ''} (steps/rev)")
            ax.plot(x, y, linestyle="-", linewidth=1.2, markersize=6, label=label, **look)
            for r, xi, yi in zip(rows, x, y):
                text = f"{r.rtol:.0e}" if r.rtol is not None else f"{r.steps:g}"
                ax.annotate(text, (xi, yi), textcoords="offset points", xytext=(4, 4), fontsize=7, color=look["color"])
        front = report.pareto()
        ax.plot([max(r.cpu_time_s, 1e-6) for r in front], [max(r.max_error_m, FLOOR_M) for r in front],
                linestyle="--", color="0.4", linewidth=1.0, drawstyle="steps-post", label="Pareto front")
        ax.axhline(TARGET_ERROR_M, color="0.6", linewidth=0.8, linestyle=":")
        ax.annotate(f"target at default settings: {TARGET_ERROR_M:g} m", (0.01, TARGET_ERROR_M), xycoords=("axes fraction", "data"),
                    textcoords="offset points", xytext=(0, 3), fontsize=7, color="0.4")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("CPU time per revolution (s, median)")
        ax.set_ylabel("max valve-lift error (m) vs reference")
        ax.set_title(f"What accuracy costs in time: {report.scene}, {report.rpm:g} rpm\n"
                     + (f"{report.ratio.ratio:.0f}x: {report.ratio.method} at {report.ratio.steps} steps vs "
                        f"{report.ratio.baseline.partition(' ')[2]} rtol {RATIO_RTOL:g}" if report.ratio is not None else ""),
                     fontsize=10)
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize=8, loc="upper right")
        return png(fig)


def differentiation_png(study) -> bytes:
    """Errors of v and p from a fitted measured lift against the sample count, one line per noise."""
    cols = study.columns()
    with figure(1, 2, figsize=(9.0, 4.0), dpi=110) as (fig, axes):
        for ax, key, title in ((axes[0], "relative_velocity_error", "velocity v"), (axes[1], "relative_accel_error", "acceleration p")):
            for sigma in sorted(set(cols["noise_m"].tolist())):
                sel = cols["noise_m"] == sigma
                ax.plot(cols["samples"][sel], np.maximum(cols[key][sel], 1e-16), marker="o",
                        label=f"noise {1e3 * sigma:g} mm" if sigma > 0 else "no noise")
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xlabel("measured points per revolution")
            ax.set_ylabel("max error / max value")
            ax.set_title(f"{title} from a measured lift", fontsize=10)
            ax.grid(True, which="major", alpha=0.3)
        axes[1].legend(fontsize=8)
        fig.suptitle(f"Differentiating a measured lift: {study.reference}, {study.rpm:g} rpm", fontsize=10)
        return png(fig)


@dataclass
class ProgressBar:
    """A one-line text bar on a stream (stderr): [#####.....] 12/40 label."""

    stream: Any
    width: int = 30
    _last: int = field(default=-1, repr=False)

    def __call__(self, done: int, total: int, label: str) -> None:
        filled = int(self.width * done / max(total, 1))
        line = f"\r[{'#' * filled}{'.' * (self.width - filled)}] {done}/{total} {label}"
        self.stream.write(line[:110].ljust(110))
        if done >= total:
            self.stream.write("\n")
        self.stream.flush()
