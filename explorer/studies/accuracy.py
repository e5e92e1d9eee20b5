"""Accuracy studies: what measuring and differentiating a lift costs in accuracy and time.

`differentiation_study` answers "how noisy and how dense may a measured lift be?": it samples an
analytic lift (default: the cycloidal demo cam, 10.3 mm over 70 deg + 70 deg at 3000 rpm) at N
equally spaced angles, adds Gaussian noise of standard deviation sigma, fits it exactly as the
`table` law does (explorer.lift.table.fit_periodic_spline) and compares the spline's velocity and
acceleration with the analytic ones over the whole revolution. The fit's time is measured too.

    from explorer.studies.accuracy import differentiation_study
    study = differentiation_study(samples=(90, 360, 1440), noise_m=(0.0, 1e-6, 1e-5))
    print(study.format())            # a text table
    study.columns()                  # dict of numpy arrays, one entry per row
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, fields

import numpy as np

from ..lift.curves import LawLift
from ..lift.table import fit_periodic_spline

DEFAULT_SAMPLES = (90, 180, 360, 720, 1440)
DEFAULT_NOISE_M = (0.0, 1e-6, 1e-5, 1e-4)
SMOOTHING = ("auto", "known")  # lambda by cross-validation, or from the true noise level


@dataclass(frozen=True)
class DifferentiationCase:
    samples: int  # measured points over one revolution, equally spaced
    noise_m: float  # standard deviation of the added lift noise
    max_velocity_error_m_s: float  # max over the revolution of |v_fit - v_exact|, mean over repeats
    max_accel_error_m_s2: float  # max over the revolution of |p_fit - p_exact|, mean over repeats
    relative_velocity_error: float  # max_velocity_error / max |v_exact|
    relative_accel_error: float  # max_accel_error / max |p_exact|
    smoothing_lambda: float  # the fit's smoothing weight (last repeat)
    cpu_time_s: float  # process CPU time of one fit (median over repeats; all threads)
    wall_time_s: float  # elapsed time of one fit (median over repeats)


@dataclass(frozen=True)
class DifferentiationStudy:
    reference: str  # what the analytic lift is
    rpm: float
    smoothing: str  # "auto" or "known"
    repeats: int
    seed: int
    rows: tuple[DifferentiationCase, ...]

    def columns(self) -> dict[str, np.ndarray]:
        """One array per field of DifferentiationCase (for plots and CSV)."""
        return {f.name: np.array([getattr(r, f.name) for r in self.rows]) for f in fields(DifferentiationCase)}

    def format(self) -> str:
        head = (
            f"Differentiating a measured lift: {self.reference}, {self.rpm:g} rpm, smoothing {self.smoothing}, "
            f"{self.repeats} noise draw(s) per row\n"
            f"{'samples':>8} {'noise mm':>9} {'max dv m/s':>11} {'rel':>8} {'max dp m/s2':>12} {'rel':>8} {'CPU ms':>8}"
        )
        lines = [head]
        for r in self.rows:
            lines.append(
                f"{r.samples:8d} {1e3 * r.noise_m:9.4f} {r.max_velocity_error_m_s:11.3g} {r.relative_velocity_error:8.2%} "
                f"{r.max_accel_error_m_s2:12.3g} {r.relative_accel_error:8.2%} {1e3 * r.cpu_time_s:8.1f}"
            )
        return "\n".join(lines)


def default_reference():
    """The cycloidal demo cam (assets/scenes/cycloidal_demo.toml) as an analytic LiftCurve."""
    return LawLift(
        height=0.0103, start=math.radians(20.0), rise=math.radians(70.0), dwell=0.0, ret=math.radians(70.0),
        rise_law="cycloidal", return_law="cycloidal",
    )


def differentiation_study(
    samples=DEFAULT_SAMPLES,
    noise_m=DEFAULT_NOISE_M,
    *,
    lift=None,
    rpm: float = 3000.0,
    smoothing: str = "auto",
    repeats: int = 1,
    seed: int = 0,
    check_points: int = 7200,
    reference: str | None = None,
) -> DifferentiationStudy:
    """Fit noisy samples of `lift` (any LiftCurve; default `default_reference()`) for every
    combination of sample count and noise level; errors of v and p against the exact ones.

    smoothing "auto" chooses lambda by cross-validation as the `table` law does by default;
    "known" tells the fit the true noise level (the law's `smoothing = "<sigma>"`)."""
    if smoothing not in SMOOTHING:
        raise ValueError(f"smoothing must be one of {SMOOTHING}, got {smoothing!r}")
    if repeats < 1:
        raise ValueError("repeats must be at least 1")
    if lift is None:
        lift = default_reference()
        reference = reference or "cycloidal 10.3 mm, 70 deg + 70 deg"
    reference = reference or type(lift).__name__
    omega = rpm * 2.0 * math.pi / 60.0
    check = np.arange(check_points) * (2.0 * math.pi / check_points)
    exact = lift.derivatives(check)
    v_exact, p_exact = omega * exact[1], omega**2 * exact[2]
    v_scale, p_scale = float(np.abs(v_exact).max()), float(np.abs(p_exact).max())
    rng = np.random.default_rng(seed)
    rows = []
    for n in samples:
        n = int(n)
        angles = np.arange(n) * (2.0 * math.pi / n)
        clean = lift.derivatives(angles)[0]
        for sigma in noise_m:
            sigma = float(sigma)
            dv, dp, cpu, wall = [], [], [], []
            lam = float("nan")
            for _ in range(repeats):
                measured = clean + sigma * rng.standard_normal(n) if sigma > 0 else clean
                c0, w0 = time.process_time(), time.perf_counter()
                fit = fit_periodic_spline(angles, measured, noise=sigma if smoothing == "known" else None)
                cpu.append(time.process_time() - c0)
                wall.append(time.perf_counter() - w0)
                d = fit.derivatives(check)
                dv.append(float(np.abs(omega * d[1] - v_exact).max()))
                dp.append(float(np.abs(omega**2 * d[2] - p_exact).max()))
                lam = fit.lam
            rows.append(
                DifferentiationCase(
                    samples=n, noise_m=sigma,
                    max_velocity_error_m_s=float(np.mean(dv)), max_accel_error_m_s2=float(np.mean(dp)),
                    relative_velocity_error=float(np.mean(dv)) / v_scale, relative_accel_error=float(np.mean(dp)) / p_scale,
                    smoothing_lambda=lam, cpu_time_s=float(np.median(cpu)), wall_time_s=float(np.median(wall)),
                )
            )
    return DifferentiationStudy(reference=reference, rpm=float(rpm), smoothing=smoothing, repeats=int(repeats),
                                seed=int(seed), rows=tuple(rows))
