"""The solver contract: every solver of the registry (explorer/dynamics/solvers.py) on the same few cases.

- its table entry matches its function (the options it declares are the ones it accepts);
- no events: a valve kept in contact through a rise agrees with the exact solver within the
  solver's stated tolerance (registry: contract_tolerance_m);
- seat bounce: a valve thrown up lands at the parabola's root and rebounds with -e v;
- chatter: restitution near 1, the bounces end (Zeno) and the valve rests on its seat after the
  accumulation time 2 v e / (A (1 - e)) of the geometric series;
- k(t): the manufactured solution for solvers that declare support, a one-line refusal otherwise;
- an unknown option is refused with a one-line error naming it.
A new solver added to the table runs all of these without a line here.
"""

from __future__ import annotations

import inspect
from dataclasses import replace

import numpy as np
import pytest

from explorer.dynamics import solvers
from explorer.scene import scene
from explorer.dynamics.model import PHASE_CODES
from explorer.dynamics.solvers import solve

from dynamics_cases import flight_case, rise_in_contact
from test_dynamics_varying import _manufactured

ALL = list(solvers.SOLVERS)

# known departures from the contract, each with what was measured (strict: fixed, they fail)
KNOWN = {
    # the method itself: Schenker's scheme sees an event only at the end of a step (his table of
    # ordinates), so a landing is found below the seat, faster than it was; correcting its speed
    # (phases.seat_speed, as reference and taylor do) would no longer be the 1902 scheme
    ("chatter", "schenker1902"): "the fixed-step scheme does not settle: each late-detected landing "
    "gives back energy, a limit cycle of bounces at 0.035 m/s at this step (0.004 m/s at 10x the "
    "steps) instead of the Zeno accumulation",
}


def _known(case: str):
    return [pytest.param(name, marks=pytest.mark.xfail(reason=KNOWN[case, name], strict=True))
            if (case, name) in KNOWN else name for name in ALL]


@pytest.mark.parametrize("name", ALL)
def test_table_entry_matches_the_function(name):
    info = solvers.SOLVERS[name]
    params = list(inspect.signature(info.function()).parameters)
    assert params[:3] == ["model", "drive", "t"]
    assert tuple(params[3:]) == info.options
    own = {option.name for option in info.scene_options}
    assert own <= set(info.options)
    # a scene option is one the loader parses from the table (scene.Solver.options), not only a key
    # it lets through: a scene with this method holds every one, at its default
    loaded = scene.scene_from_dict({"drive": {"rpm": 100}, "lift": {"law": "cycloidal", "height": "5 mm", "rise": "90 deg"},
                                    "solver": {"method": name}}).solver
    assert set(loaded.options) == own
    assert all(loaded.options[option.name] == option.default for option in info.scene_options)
    assert info.kind in ("piecewise", "fixed-step", "adaptive")
    if info.stability_error is not None:
        assert issubclass(info.stability_error, Exception) and info.unstable_option in info.options
    assert name in solvers.names() and (name in solvers.varying_stiffness()) == info.varying_stiffness


@pytest.mark.parametrize("name", ALL)
def test_no_events_agrees_with_exact(name):
    """A cycloidal rise of 3 natural periods with the valve kept on its raised base circle: no
    separation, no seat; the lift agrees with the exact solver's."""
    case = rise_in_contact("cycloidal", 3.0)
    t = np.linspace(0.0, 1.2 * case.t_dwell, 6001)
    ref = solve(case.model, case.drive, t, method="exact", initial_state=(0.0, 0.0))
    sol = solve(case.model, case.drive, t, method=name, initial_state=(0.0, 0.0))
    assert not [e for e in sol.events if e["kind"] in ("separation", "re-contact", "seat")]
    assert np.all(sol.contact[1:])
    tol = solvers.solver(name).contract_tolerance_m
    assert np.abs(sol.s - ref.s).max() <= max(tol, 1e-15)


def _thrown(e: float, n: int = 8001, span: float = 1.0):
    model, drive, start, g, t_land = flight_case()
    model = replace(model, restitution=e)
    s0, v0 = start
    v_land = v0 - g * t_land
    t_acc = t_land + 2.0 * (-e * v_land) / (g * (1.0 - e))
    t = np.linspace(0.0, span * t_acc * 1.3, n)
    return model, drive, start, g, t_land, v_land, t_acc, t


@pytest.mark.parametrize("name", ALL)
def test_seat_bounce_with_restitution(name):
    """Thrown up from 1 mm at 2 m/s against W/M = 1500 m/s^2, e = 0.5: it lands at the parabola's
    root at -v_land and rebounds to (e v_land)^2 / 2g."""
    e = 0.5
    model, drive, start, g, t_land, v_land, t_acc, t = _thrown(e)
    sol = solve(model, drive, t, method=name, initial_state=start)
    seats = [ev for ev in sol.events if ev["kind"] == "seat"]
    assert seats
    fixed = solvers.solver(name).fixed_step
    dt = float(t[1] - t[0])
    # the landing: at the root, at the parabola's speed (a fixed-step scheme: within its step)
    assert abs(seats[0]["time_s"] - t_land) <= (dt if fixed else 1e-12)
    assert seats[0]["velocity_m_s"] == pytest.approx(v_land, rel=1e-2 if fixed else 1e-9)
    # the first rebound's apex
    after = (t > t_land) & (t < t_land + 2 * e * -v_land / g)
    apex = (e * v_land) ** 2 / (2 * g)
    assert sol.s[after].max() == pytest.approx(apex, rel=2e-2 if fixed else 1e-6)
    assert sol.s.min() >= 0.0


@pytest.mark.parametrize("name", _known("chatter"))
def test_chatter_ends_at_the_zeno_accumulation_time(name):
    """e = 0.8: infinitely many bounces in finite time (Zeno); every solver ends them and leaves
    the valve at rest on its seat past the accumulation time of the geometric series."""
    e = 0.8
    model, drive, start, g, t_land, v_land, t_acc, t = _thrown(e, n=4001, span=1.5)
    sol = solve(model, drive, t, method=name, initial_state=start)
    seats = [ev for ev in sol.events if ev["kind"] == "seat"]
    assert len(seats) >= 5
    assert seats[-1]["time_s"] <= t_acc * (1.0 + 1e-6)
    rest = t > t_acc * 1.01
    assert np.all(sol.s[rest] == 0.0) and np.all(sol.v[rest] == 0.0)
    if sol.phase is not None:
        assert np.all(sol.phase[rest] == PHASE_CODES["seated"])
    zeno = [ev["zeno_accumulation_s"] for ev in seats if "zeno_accumulation_s" in ev]
    for value in zeno:  # where a solver reports the accumulation instant, it is the series' sum
        assert value == pytest.approx(t_acc, rel=1e-9)


@pytest.mark.parametrize("name", ALL)
def test_varying_stiffness_supported_or_refused(name):
    """k(t): the manufactured solution s = A (1 - cos w t) where the solver declares support; a
    one-line ValueError naming the solvers that do otherwise."""
    info = solvers.solver(name)
    model, drive, t, exact_s = _manufactured()
    if not info.varying_stiffness:
        with pytest.raises(ValueError, match="constant linkage stiffness") as err:
            solve(model, drive, t, method=name, initial_state=(0.0, 0.0))
        assert "\n" not in str(err.value)
        assert all(repr(other) in str(err.value) for other in solvers.varying_stiffness())
        return
    sol = solve(model, drive, t, method=name, initial_state=(0.0, 0.0))
    assert not [e for e in sol.events if e["kind"] != "lift-off"]
    assert np.abs(sol.s - exact_s).max() <= max(info.contract_tolerance_m, 1e-15)


@pytest.mark.parametrize("name", ALL)
def test_unknown_option_refused(name):
    model, drive, start, g, t_land = flight_case()
    t = np.linspace(0.0, t_land, 11)
    with pytest.raises(TypeError, match="no option 'bogus_tolerance'") as err:
        solve(model, drive, t, method=name, bogus_tolerance=1.0)
    assert "\n" not in str(err.value)


def test_unknown_method_refused():
    model, drive, start, g, t_land = flight_case()
    with pytest.raises(ValueError, match="unknown solver method 'euler'; known: exact"):
        solve(model, drive, np.linspace(0.0, t_land, 11), method="euler")


def test_registry_is_import_light():
    """explorer.dynamics.solvers imports no scipy and no solver module (the scene loader reads it), nor
does `import explorer`."""
    import subprocess
    import sys

    for head in ("explorer.dynamics.solvers", "explorer"):
        code = (f"import sys, {head}\n"
                "registry = ('explorer.dynamics', 'explorer.dynamics.solvers', 'explorer.dynamics.solver_base')\n"
                "bad = [m for m in sys.modules if m == 'scipy' or (m.startswith('explorer.dynamics') and m not in registry)]\n"
                "assert not bad, bad\n")
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
        assert out.returncode == 0, out.stderr
