"""The residual vibration figures (issue #22.1; docs/theory/residual.md): the dwell of any lift
(explorer.lift.dwell), the free vibration's amplitude about the static equilibrium there
(explorer.dynamics.free_vibration), in simulate's summary, `explorer residual`, sweeps and the
compiled path.

Oracles. A rise of height h and duration T through the linear SDOF (the valve in contact, no
preload, lash, friction or damping: M1 s'' + (k + c) s = k S(t), c the spring rate) leaves in
the dwell a free vibration about the equilibrium k/(k+c) h of amplitude (Duhamel's integral of
the rise's acceleration; derivation in docs/theory/residual.md), r = T/Tn:
    harmonic rise   k/(k+c) h |cos pi r| / |1 - 4 r^2|
    cycloidal rise  k/(k+c) h |sin pi r| / (pi r |r^2 - 1|)
checked here against the Duhamel integral by quadrature as well, and against the figures over
r in [0.5, 5] within 1e-6 h (the exact solver is exact up to rounding: its differences are
~1e-15 h; the tolerance is the issue's).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import explorer
from conftest import SCENES
from explorer.dynamics import kernel_figures
from explorer.dynamics.free_vibration import free_amplitude
from explorer.effects.lift import build_lift
from explorer.effects.pipeline import simulate
from explorer.lift.curves import LawLift
from explorer.lift.dwell import constant_stretches, dwell_after_rise
from explorer.scene.scene import load_scene

H = 10e-3  # m, the rise
K = C = 1e6  # N/m, linkage stiffness and spring rate (the case)
M1 = 0.1  # kg
RISE = math.radians(60.0)
TN = 2.0 * math.pi * math.sqrt(M1 / (K + C))
RATIOS = np.linspace(0.5, 5.0, 10)

SCENE = """name = "residual oracle"
effects = ["kinematics", "lash", "elastic"]
[drive]
rpm = 1000
[lift]
law = "{law}"
height = "10 mm"
start = "30 deg"
rise = "60 deg"
dwell = "60 deg"
return = "60 deg"
[follower]
type = "translating-roller"
base_radius = "30 mm"
roller_radius = "12 mm"
ratio = 1.0
[valve]
mass = "0.1 kg"
lash = "0 mm"
[spring]
preload = "0 N"
rate = "1e6 N/m"
[linkage]
stiffness = "1e6 N/m"
[solver]
method = "exact"
steps_per_revolution = 3600
"""


def closed_form(law: str, r: float) -> float:
    """The residual amplitude after the rise (module doc), in forms without 0/0 at r = 1/2
    (harmonic) and r = 1 (cycloidal): cos(pi r) / (1 - 4r^2) = (pi/2) sinc(x/2) / (1 + 2r) with
    x = 1 - 2r; sin(pi r) / (pi r (r^2 - 1)) = -sinc(y) / (r (1 + r)) with y = 1 - r."""
    gain = K / (K + C) * H
    if law == "harmonic":
        return gain * abs(0.5 * math.pi * np.sinc(0.5 * (1.0 - 2.0 * r)) / (1.0 + 2.0 * r))
    return gain * abs(np.sinc(1.0 - r) / (r * (1.0 + r)))


def duhamel(law: str, r: float) -> float:
    """|int_0^T y''(tau) exp(-i wn tau) dtau| / wn for the equilibrium's rise y = k/(k+c) S:
    the amplitude after the rise of an undamped oscillator starting at rest (quadrature)."""
    from scipy.integrate import quad

    T = r * TN
    wn = 2.0 * math.pi / TN
    gain = K / (K + C) * H
    if law == "harmonic":
        def acc(t):
            return gain * 0.5 * (math.pi / T) ** 2 * math.cos(math.pi * t / T)
    else:
        def acc(t):
            return gain * 2.0 * math.pi / T**2 * math.sin(2.0 * math.pi * t / T)
    tol = 1e-13 * gain * wn  # the integral is ~ gain wn (an amplitude ~ gain) times the closed form's factor
    re = quad(acc, 0.0, T, weight="cos", wvar=wn, epsabs=tol, epsrel=1e-12)[0]
    im = quad(acc, 0.0, T, weight="sin", wvar=wn, epsabs=tol, epsrel=1e-12)[0]
    return math.hypot(re, im) / wn


def rpm_for(r: float) -> float:
    """The speed at which the 60 deg rise lasts r natural periods."""
    return RISE / (r * TN) * 60.0 / (2.0 * math.pi)


@pytest.mark.parametrize("law", ["harmonic", "cycloidal"])
def test_the_closed_forms_are_duhamels_integral(law):
    for r in [0.5, 0.73, 1.0, 1.5, 2.0, 3.3, 5.0]:
        assert closed_form(law, r) == pytest.approx(duhamel(law, r), rel=1e-9, abs=1e-12 * H), r


def _scene(tmp_path, law: str):
    path = tmp_path / f"{law}.toml"
    path.write_text(SCENE.format(law=law))
    return load_scene(path)


@pytest.mark.parametrize("law", ["harmonic", "cycloidal"])
def test_simulate_gives_the_residual_amplitude_of_the_closed_form(tmp_path, law):
    """simulate's summary over r in [0.5, 5]: the valve stays on the cam through the rise and
    the dwell's amplitude is the closed form's within 1e-6 h (measured: ~1e-15 h)."""
    base = _scene(tmp_path, law)
    for r in RATIOS:
        result = simulate(load_scene(tmp_path / f"{law}.toml", [f"drive.rpm={rpm_for(r)}"]))
        s = result.summary
        assert not [e for e in result.events if e.kind == "separation" and e.cam_angle_deg < 150.0], r
        assert abs(s["residual_amplitude_m"] - closed_form(law, r)) <= 1e-6 * H, (r, s["residual_amplitude_m"])
    assert base.lift.law == law


@pytest.mark.parametrize("law", ["harmonic", "cycloidal"])
def test_sweeps_and_the_residual_study_give_the_closed_form(tmp_path, law):
    """The same figure from a sweep over drive.rpm (the compiled path) and from `explorer
    residual`'s table (the same sweep), over r in [0.5, 5]."""
    from explorer.studies.residual import residual_table
    from explorer.studies.sweep_engine import _Shared, engine_for

    scene = _scene(tmp_path, law)
    assert engine_for(scene, _Shared()).name == "compiled"
    speeds = [rpm_for(r) for r in RATIOS]
    swept = explorer.sweep(scene, vary={"drive.rpm": speeds}, workers=1)
    study = residual_table(scene, speeds, workers=1)
    expected = np.array([closed_form(law, r) for r in RATIOS])
    for table in (swept, study):
        got = np.asarray(table.columns["residual_amplitude_m"], dtype=float)
        assert np.all(np.abs(got - expected) <= 1e-6 * H), (got, expected)


def test_the_compiled_figure_is_the_effects_formula_to_the_bit():
    """The compiled solver (kernel_figures) compiles explorer.dynamics.free_vibration.free_amplitude itself: on the same
    inputs (random, seated and open dwells, both signs of v and v = 0, with and without friction)
    the two give the same float."""
    rng = np.random.default_rng(7)
    for _ in range(2000):
        k, rate = 10 ** rng.uniform(5, 9), 10 ** rng.uniform(3, 6)
        W0, R = rng.uniform(0, 400), rng.choice([0.0, rng.uniform(0, 40)])
        S, lash = rng.uniform(0, 1.2e-2), rng.choice([0.0, rng.uniform(0, 4e-4)])
        s = rng.uniform(0, 1.2e-2)
        v = rng.choice([0.0, rng.normal(0, 2)])
        args = (s, v, S, k, lash, W0, rate, R, rng.uniform(0.03, 0.3))
        assert kernel_figures._free_amplitude(*args) == free_amplitude(*args), args


def test_free_amplitude_is_the_harmonic_amplitude_about_the_equilibrium():
    """Closed form by hand: s = s_eq + A cos(phi), v = -A wn sin(phi) gives A at any phase; with
    friction R about the centre of the half-cycle s_eq - R sgn(v) / (k + rate); at v = 0 the
    half-cycle that begins (0 inside the band: the valve sticks); on a seated dwell about 0."""
    k, rate, M1, W0, lash, S = 2e6, 5e4, 0.08, 250.0, 2e-4, 8e-3
    s_eq = (k * (S - lash) - W0) / (k + rate)
    wn = math.sqrt((k + rate) / M1)
    for phi in np.linspace(0.1, 6.0, 7):
        A = 3e-5
        got = free_amplitude(s_eq + A * math.cos(phi), -A * wn * math.sin(phi), S, k, lash, W0, rate, 0.0, M1)
        assert got == pytest.approx(A, rel=1e-9)
    R, A = 20.0, 3e-5
    band = R / (k + rate)
    assert free_amplitude(s_eq - band + A * math.cos(1.0), A * wn * math.sin(1.0), S, k, lash, W0, rate, R, M1) \
        == pytest.approx(A, rel=1e-9)  # moving up (sin > 0 gives v > 0 here)
    assert free_amplitude(s_eq + band + A * math.cos(1.0), -A * wn * math.sin(1.0), S, k, lash, W0, rate, R, M1) \
        == pytest.approx(A, rel=1e-9)
    assert free_amplitude(s_eq + 0.5 * band, 0.0, S, k, lash, W0, rate, R, M1) == 0.0
    assert free_amplitude(s_eq + band + A, 0.0, S, k, lash, W0, rate, R, M1) == pytest.approx(A, rel=1e-9)
    # the drive too low to open the valve against W0: the seat is the equilibrium
    assert free_amplitude(0.0, 0.0, 1e-4, k, lash, W0, rate, R, M1) == 0.0
    assert free_amplitude(3e-6, 0.0, 1e-4, k, lash, W0, rate, R, M1) == pytest.approx(3e-6, rel=1e-15)


def test_the_dwell_of_any_lift():
    """The top dwell of a rise-dwell-return cam; the base circle after the event when there is
    none; the polydyne's dwell where its wanted lift has one; none for a cam nowhere constant."""
    top = LawLift(height=H, start=0.5, rise=1.0, dwell=0.4, ret=1.0, rise_law="polynomial-4567",
                  return_law="polynomial-4567")
    d = dwell_after_rise(top)
    assert d.start == pytest.approx(1.5, abs=1e-15) and d.length == pytest.approx(0.4, abs=1e-15) and d.lift == H
    no_top = LawLift(height=H, start=0.5, rise=1.0, dwell=0.0, ret=1.0, rise_law="polynomial-4567",
                     return_law="polynomial-4567")  # L', L'', L''' all vanish at its top: no dwell
    d = dwell_after_rise(no_top)
    assert d.lift == 0.0 and d.start == pytest.approx(2.5, abs=1e-15)
    assert d.length == pytest.approx(2 * math.pi - 2.0, abs=1e-14)
    assert len(constant_stretches(no_top)) == 1 and len(constant_stretches(top)) == 2
    demo = build_lift(load_scene(SCENES / "polydyne_demo.toml"))
    d = dwell_after_rise(demo)
    assert d.start == pytest.approx((demo.start + demo.wanted.dwell_start()) % (2 * math.pi), abs=1e-12)
    assert d.length == pytest.approx(demo.wanted.dwell, abs=1e-12)
    table = build_lift(load_scene(SCENES / "table_demo.toml"))
    assert dwell_after_rise(table) is None  # a periodic spline through measured lifts is nowhere flat


def test_every_law_with_a_dwell_gives_a_figure_in_simulate_and_the_compiled_path():
    """The issue's case (harmonic rise, 60 deg dwell, linkage and spring 1e6 N/m): a finite
    residual_amplitude_m at every speed, the compiled path's equal to simulate's (the valve's
    state at the sample differs by rounding only)."""
    from explorer.studies.sweep_engine import _Shared, compute_chunk, result_columns

    base = load_scene(SCENES / "elastic_float.toml", ['lift.law="harmonic"', 'lift.dwell="60 deg"',
                                                       'linkage.stiffness="1e6 N/m"', 'spring.rate="1e6 N/m"'])
    names = result_columns(base)
    speeds = np.array([[500.0], [1500.0], [3000.0], [4500.0]])
    table = compute_chunk(base, ("drive.rpm",), speeds, names, _Shared())
    got = table[:, names.index("residual_amplitude_m")]
    for rpm, value in zip(speeds[:, 0], got):
        expected = simulate(load_scene(SCENES / "elastic_float.toml",
                                       ['lift.law="harmonic"', 'lift.dwell="60 deg"', 'linkage.stiffness="1e6 N/m"',
                                        'spring.rate="1e6 N/m"', f"drive.rpm={rpm}"])).summary["residual_amplitude_m"]
        assert math.isfinite(expected) and value == pytest.approx(expected, rel=1e-9, abs=1e-14), rpm
