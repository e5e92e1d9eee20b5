"""Issue #23: gears, effects and lift laws are plug-ins. A toy gear (a new follower type), a toy
effect and a toy law, each defined entirely in this file and registered with one call (the gear's
drawing with one more, in the view layer), run through simulate, a sweep, the browser's parts and
a rerun recording; the tables tell the browser which laws a scene takes; and no gear or solver name
appears outside its own modules and the tables.

Oracles: closed forms of the laws (a cycloidal rise peaks at v = 2 h w / beta at mid-rise; the toy
cubic 3u^2 - 2u^3 is h/2 at mid-rise with v = 1.5 h w / beta there), the translating roller with the
same ratio for the toy lever (the same lift law times the same ratio), and `simulate` for the
sweeps' rows (the batched engines are checked against it elsewhere; here: the toy's rows are
simulate's).
"""

from __future__ import annotations

import ast
import math
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType

import numpy as np
import pytest

from explorer import InputError, load_scene, simulate, sweep
from explorer.effects.registry import EffectSpec, register_effect
from explorer.gears.base import Gear
from explorer.gears.registry import GEARS, register_gear
from explorer.lift.curves import law_lift
from explorer.lift.registry import LawSpec, register_law
from explorer.result import EffectOutput
from explorer.view.base import GearView
from explorer.view.gear_views import VIEWS, register_view

from conftest import SCENES
from import_cycles import import_graph

PACKAGE = Path(__file__).resolve().parents[1] / "explorer"


# ------------------------------------------------------------------------------------------------
# a toy gear: a knife edge on a straight guide lifts one end of a lever about a fixed pivot, the
# other end pushes the valve: the valve-referred lift is `ratio` times the law's (a gear whose
# linkage sets the ratio), its report the lever's angle and ratio


@dataclass(frozen=True)
class ScaledLift:
    """The valve-referred lift: `ratio` times the follower's law."""

    inner: object
    ratio: float

    def derivatives(self, theta) -> np.ndarray:
        return self.ratio * self.inner.derivatives(theta)

    def breakpoints(self) -> np.ndarray:
        return self.inner.breakpoints()


def toy_lever_keys(t) -> dict:
    t.reject_unknown(("ratio", "arm"))
    return {"ratio": t.number("ratio", minimum=0.1, maximum=10.0), "arm": t.quantity("arm", "length", positive=True)}


class ToyLever(Gear):
    type = "toy-lever"
    description = "a knife edge on a lever of fixed ratio (the plug-in tests' toy)"
    parts = MappingProxyType({"lever": toy_lever_keys})
    linkage_ratio = True
    batch_sweeps = True
    columns = MappingProxyType({"kinematics": ("toy_lever_angle_rad",), "gear": ("toy_ratio",)})

    def check(self, spec, fields) -> None:
        super().check(spec, fields)
        lever = spec.part("lever")
        if fields["lift"].height >= lever["arm"]:
            raise InputError(spec.file, "gear.lever.arm", "the lever must be longer than the follower's lift")

    def build_lift(self, scene) -> ScaledLift:
        return ScaledLift(law_lift(scene.lift), scene.gear.part("lever")["ratio"])

    def kinematics(self, ctx, d):
        lever = ctx.scene.gear.part("lever")
        follower_lift = d[0] / lever["ratio"]
        angle = np.arcsin(follower_lift / lever["arm"])
        return {"toy_lever_angle_rad": angle}, {"max_toy_lever_angle_rad": float(angle.max())}

    def report(self, ctx) -> EffectOutput:
        ratio = ctx.scene.gear.part("lever")["ratio"]
        return EffectOutput(columns={"toy_ratio": np.full(ctx.theta.shape, ratio)}, summary={"ratio": ratio})


class ToyLeverView(GearView):
    """The toy lever as a bar about its pivot over the valve group (the drawing kit's)."""

    colors = MappingProxyType({"toy_lever": (20, 180, 90)})

    def layout(self, scene, result=None, lift=None):
        from explorer.view import translating_roller

        return translating_roller.layout(scene, result)

    def parts(self, scene, result=None, lay=None, lift=None, contour_samples: int = 720, only=None) -> dict:
        import trimesh

        from explorer.view.drawing import valve_group

        lay = lay or self.layout(scene, result)
        bar = trimesh.creation.box(extents=[scene.gear.part("lever")["arm"], 0.005, 0.005])
        parts = {"toy_lever": bar, **valve_group(lay)}
        return {k: v for k, v in parts.items() if only is None or k in only}

    def poses(self, scene, result, magnification: float = 1.0, lay=None, lift=None) -> dict:
        from explorer.view.drawing import quat_about_y
        from explorer.view.gear_parts import valve_poses

        lay = lay or self.layout(scene, result)
        angle = np.asarray(result.columns["toy_lever_angle_rad"])
        n = angle.size
        poses = {"toy_lever": (np.tile([0.0, 0.0, 0.1], (n, 1)), quat_about_y(-angle))}
        poses.update(valve_poses(scene, result, lay, magnification))
        return poses


TOY_SCENE = """
name = "toy lever"
effects = ["kinematics", "lash", "forces", "elastic", "gear"]
[drive]
rpm = 1500
[lift]
law = "{law}"
height = "6 mm"
rise = "90 deg"
dwell = "20 deg"
[follower]
type = "{follower}"
{ratio}
[valve]
mass = "0.25 kg"
lash = "0.1 mm"
[spring]
preload = "300 N"
rate = "30 N/mm"
[linkage]
stiffness = "3e7 N/m"
{gear}
"""
TOY_GEAR_SECTION = '[gear.lever]\nratio = 1.6\narm = "40 mm"'


@pytest.fixture
def toy_gear():
    with register_gear(ToyLever()), register_view("toy-lever", ToyLeverView()):
        yield


def _write(tmp_path, name, **fields) -> Path:
    path = tmp_path / name
    path.write_text(TOY_SCENE.format(**{"law": "cycloidal", "follower": "toy-lever", "ratio": "",
                                        "gear": TOY_GEAR_SECTION, **fields}))
    return path


def test_an_unregistered_gear_is_refused_and_the_registration_is_undone(tmp_path):
    path = _write(tmp_path, "toy.toml")
    with pytest.raises(InputError) as info:
        load_scene(path)
    assert info.value.key == "follower.type"
    with register_gear(ToyLever()):
        assert load_scene(path).gear_plugin.type == "toy-lever"
    assert "toy-lever" not in GEARS


def test_a_toy_gear_runs_through_simulate(tmp_path, toy_gear):
    """The toy lever's valve lift is the translating roller's with the same ratio (the same law
    times the same ratio): its lift curve, its kinematics figures, the generic forces and elastic
    effects on it, its report."""
    toy = load_scene(_write(tmp_path, "toy.toml"))
    plain = load_scene(_write(tmp_path, "plain.toml", follower="translating-roller", ratio="ratio = 1.6", gear=""))
    plain = plain.with_changes(effects=("kinematics", "lash", "forces", "elastic"))
    r_toy, r_plain = simulate(toy), simulate(plain)
    # the rigid motion and forces: the same products in another order (rounding)
    for name in ("rigid_valve_lift_m", "rigid_valve_velocity_m_s", "rigid_valve_accel_m_s2", "contact_force_N"):
        scale = np.abs(r_plain.columns[name]).max()
        np.testing.assert_allclose(r_toy.columns[name], r_plain.columns[name], rtol=0, atol=1e-13 * scale)
    # the elastic valve from drives that differ by that rounding: 1e-12 m of lift, the acceleration
    # of the vibrating valve within 1e-8 of its peak (the solver's sensitivity, not the gear's)
    np.testing.assert_allclose(r_toy.columns["valve_lift_m"], r_plain.columns["valve_lift_m"], rtol=0, atol=1e-12)
    scale = np.abs(r_plain.columns["valve_accel_m_s2"]).max()
    np.testing.assert_allclose(r_toy.columns["valve_accel_m_s2"], r_plain.columns["valve_accel_m_s2"], rtol=0,
                               atol=1e-8 * scale)
    assert r_toy.summary["gear"] == {"type": "toy-lever", "ratio": 1.6}
    assert np.all(r_toy.columns["toy_ratio"] == 1.6)
    angle = r_toy.columns["toy_lever_angle_rad"]
    assert float(angle.max()) == pytest.approx(math.asin(0.006 / 0.040), rel=1e-9)  # full lift: sin = h / arm
    assert r_toy.summary["max_valve_lift_m"] == pytest.approx(1.6 * 0.006 - 1e-4, rel=1e-12)
    # the gear's own check, at load time, naming the key
    with pytest.raises(InputError) as info:
        load_scene(_write(tmp_path, "short.toml", gear='[gear.lever]\nratio = 1.6\narm = "5 mm"'))
    assert info.value.key == "gear.lever.arm"
    # a column the gear did not declare is refused
    undeclared = ToyLever()
    undeclared.columns = MappingProxyType({})
    with register_gear(undeclared, replace=True):
        with pytest.raises(RuntimeError, match="toy_lever_angle_rad"):
            simulate(toy)


def test_a_toy_gear_runs_through_a_sweep(tmp_path, toy_gear):
    """Its runs share one lift (batch_sweeps): the compiled path takes them; each row equals
    simulate's to the compiled path's stated tolerance (tests/test_sweep_kernel.py)."""
    from explorer.studies.sweep_engine import engine_for, _Shared, reference_row, result_columns

    scene = load_scene(_write(tmp_path, "toy.toml"), ['effects=["forces", "elastic"]'])
    assert engine_for(scene, _Shared()).name == "compiled"
    speeds = [1200.0, 1500.0, 1900.0]
    table = sweep(scene, vary={"drive.rpm": speeds}, workers=1)
    names = result_columns(scene)
    for i, rpm in enumerate(speeds):
        expected = reference_row(scene.with_changes(drive=type(scene.drive)(rpm=rpm)), names)
        for name, value in expected.items():
            got = float(table.columns[name][i])
            assert got == pytest.approx(value, rel=1e-8, abs=1e-10) or (math.isnan(got) and math.isnan(value)), name
        assert table.columns["run_failed"][i] == 0


def test_a_toy_gear_is_drawn_by_the_browser_and_recorded(tmp_path, toy_gear):
    """The browser's bundle (explorer.view.browser.model.prepare: layout, meshes, poses) and a rerun
    recording hold the toy lever's part, posed at its lever angle, coloured from its view."""
    from explorer.view import parts as meshes
    from explorer.view.browser.model import Request, prepare
    from explorer.view.rerun.read import read_rrd
    from explorer.view.rerun.recording import with_parts, write_recordings

    path = _write(tmp_path, "toy.toml")
    bundle = prepare(Request(str(path)))
    assert {"toy_lever", "valve", "spring", "seat"} <= set(bundle.meshes) == set(bundle.poses)
    angle = bundle.result.columns["toy_lever_angle_rad"]
    wxyz = bundle.poses["toy_lever"][1]
    np.testing.assert_allclose(2.0 * np.arctan2(-wxyz[:, 2], wxyz[:, 0]), angle, atol=1e-12)
    assert meshes.PART_COLORS["toy_lever"] == (20, 180, 90)
    assert meshes.parts_follow_cam(bundle.scene) is False

    out = tmp_path / "toy.rrd"
    write_recordings(out, [with_parts("toy", simulate(load_scene(path)))])
    (run,) = read_rrd(out)
    quaternion = run.temporal["/parts/toy_lever"]["Transform3D:quaternion"]  # x y z w
    np.testing.assert_allclose(2.0 * np.arctan2(-quaternion[:, 1], quaternion[:, 3]), angle, atol=1e-6)
    assert "/other/toy_ratio" in run.series or any("toy_ratio" in p for p in run.series)


# ------------------------------------------------------------------------------------------------
# a toy effect: the square of the valve's speed, and its peak as a sweep figure


def toy_effect(ctx) -> EffectOutput:
    v = np.asarray(ctx.columns["valve_velocity_m_s"])
    return EffectOutput(columns={"toy_speed_squared_m2_s2": v * v},
                        summary={"toy_peak_speed_m_s": float(np.abs(v).max())})


def toy_row(result) -> dict:
    return {"toy_peak_speed_m_s": result.summary["toy_peak_speed_m_s"]}


TOY_EFFECT = EffectSpec("toy-peak", toy_effect, depends=("kinematics",), columns=("toy_speed_squared_m2_s2",),
                        sweep_figures=("toy_peak_speed_m_s",), row=toy_row, description="the plug-in tests' toy")


def _cycloidal_scene(tmp_path, effects='["toy-peak"]', law="cycloidal") -> Path:
    path = tmp_path / "cycloidal.toml"
    path.write_text(f'effects = {effects}\n[drive]\nrpm = 1200\n[lift]\nlaw = "{law}"\nheight = "8 mm"\n'
                    'rise = "90 deg"\ndwell = "30 deg"\n[follower]\nbase_radius = "30 mm"\nroller_radius = "8 mm"\n'
                    '[valve]\nmass = "0.3 kg"\n[spring]\npreload = "200 N"\nrate = "20 N/mm"\n')
    return path


def test_a_toy_effect_runs_through_simulate_a_sweep_the_browser_and_a_recording(tmp_path):
    """Closed form: a cycloidal rise of h over beta peaks at v = 2 h w / beta, at mid-rise (45 deg:
    a sample of the 3600-step grid)."""
    from explorer.studies.sweep_engine import engine_for, _Shared
    from explorer.view.browser.model import Request, prepare
    from explorer.view.rerun.read import read_rrd
    from explorer.view.rerun.recording import with_parts, write_recordings

    path = _cycloidal_scene(tmp_path)
    with pytest.raises(InputError):
        load_scene(path)  # not registered: an unknown effect
    with register_effect(TOY_EFFECT):
        scene = load_scene(path)
        result = simulate(scene)
        w, h, beta = scene.omega, 0.008, math.pi / 2
        assert result.summary["toy_peak_speed_m_s"] == pytest.approx(2.0 * h * w / beta, rel=1e-12)
        assert result.columns["toy_speed_squared_m2_s2"].max() == pytest.approx((2.0 * h * w / beta) ** 2, rel=1e-12)
        assert result.timings["toy-peak"].requested and not result.timings["kinematics"].requested
        # a sweep: the shared engine (the compiled one does not know the figure), rows = the closed form
        assert engine_for(scene, _Shared()).name == "shared"
        speeds = [600.0, 1200.0, 2400.0]
        table = sweep(scene, vary={"drive.rpm": speeds}, workers=1)
        np.testing.assert_allclose(table.columns["toy_peak_speed_m_s"],
                                   [2.0 * h * (rpm * math.pi / 30.0) / beta for rpm in speeds], rtol=1e-12)
        # the browser's bundle reads it out; a recording has it as a series
        bundle = prepare(Request(str(path)))
        assert "| toy peak speed | 1.28 m/s |" in bundle.readout
        out = tmp_path / "effect.rrd"
        write_recordings(out, [with_parts("toy effect", result)])
        (run,) = read_rrd(out)
        recorded = [p for p in run.series if "toy_speed_squared" in p]
        assert recorded
        np.testing.assert_allclose(run.series[recorded[0]]["value"], result.columns["toy_speed_squared_m2_s2"], rtol=1e-12)
    with pytest.raises(InputError):
        load_scene(path)  # undone


# ------------------------------------------------------------------------------------------------
# toy laws: a closed form (3u^2 - 2u^3) and one with its own key, parser and builder


def toy_cubic(u):
    u = np.asarray(u, dtype=float)
    return np.stack([3.0 * u**2 - 2.0 * u**3, 6.0 * u - 6.0 * u**2, 6.0 - 12.0 * u, np.full(u.shape, -12.0)])


@dataclass(frozen=True)
class EccentricLift:
    """L = a (1 - cos theta) / 2: a plain eccentric (the toy law's builder)."""

    amplitude: float

    def derivatives(self, theta) -> np.ndarray:
        theta = np.asarray(theta, dtype=float)
        a = 0.5 * self.amplitude
        return np.stack([a * (1.0 - np.cos(theta)), a * np.sin(theta), a * np.cos(theta), -a * np.sin(theta)])

    def breakpoints(self) -> np.ndarray:
        return np.zeros(0)


@dataclass(frozen=True)
class EccentricOptions:
    amplitude: float


def parse_eccentric(table, fields) -> EccentricOptions:
    return EccentricOptions(table.quantity("amplitude", "length", positive=True))


def build_eccentric(scene) -> EccentricLift:
    return EccentricLift(scene.lift.options.amplitude)


def test_a_toy_closed_form_law_runs_through_simulate_a_sweep_the_gears_and_the_browser(tmp_path):
    """3u^2 - 2u^3: h/2 at mid-rise with v = 1.5 h w / beta (closed form); its smoothness (1: the
    acceleration jumps at the ends) is what the law table says; the pivoted roller lever, which
    synthesises its cam through closed forms, takes it; the browser's law list offers it."""
    from explorer.view.browser.model import offered_laws

    spec = LawSpec("toy-cubic", normalised=toy_cubic, shaped=True, smoothness=1, description="the tests' toy")
    path = _cycloidal_scene(tmp_path, effects='["kinematics", "forces"]', law="toy-cubic")
    with pytest.raises(InputError):
        load_scene(path)
    with register_law(spec):
        scene = load_scene(path)
        result = simulate(scene)
        i = 450  # mid-rise: 45 deg on the 3600-step grid
        assert result.columns["valve_lift_m"][i] == pytest.approx(0.004, rel=1e-12)
        assert result.columns["valve_velocity_m_s"][i] == pytest.approx(1.5 * 0.008 * scene.omega / (math.pi / 2), rel=1e-12)
        ends = toy_cubic(np.array([0.0, 1.0]))
        assert np.all(ends[1] == 0.0) and np.all(ends[2] != 0.0)  # smoothness 1
        table = sweep(scene, vary={"drive.rpm": [1000.0, 1400.0]}, workers=1)
        for k, rpm in enumerate((1000.0, 1400.0)):
            assert table.columns["min_contact_force_N"][k] == simulate(
                scene.with_changes(drive=type(scene.drive)(rpm=rpm))).summary["min_contact_force_N"]
        pivoted = load_scene(SCENES / "pivoted_roller_lever.toml", ['lift.law="toy-cubic"'])
        assert simulate(pivoted).columns["valve_lift_m"].max() > 0.0
        assert "toy-cubic" in offered_laws(str(SCENES / "cycloidal_demo.toml"), (), "cycloidal")
        assert "toy-cubic" in offered_laws(str(SCENES / "pivoted_roller_lever.toml"), (), "cycloidal")
    assert "toy-cubic" not in offered_laws(str(SCENES / "cycloidal_demo.toml"), (), "cycloidal")
    from explorer.lift import laws

    assert "toy-cubic" not in laws.LAWS  # the closed forms' store is undone with the table


def test_a_toy_law_with_its_own_keys_parser_and_builder(tmp_path):
    """law = "toy-eccentric", amplitude = ...: its key is refused for other laws and required for
    it; the lift is its builder's (L(pi) = amplitude, L'(pi/2) = amplitude / 2)."""
    path = tmp_path / "eccentric.toml"
    path.write_text('[drive]\nrpm = 600\n[lift]\nlaw = "toy-eccentric"\namplitude = "5 mm"\n'
                    '[follower]\nbase_radius = "40 mm"\nroller_radius = "10 mm"\n')
    spec = LawSpec("toy-eccentric", builder=build_eccentric, parser=parse_eccentric, keys=("amplitude",),
                   required=("amplitude",), description="the tests' toy")
    with register_law(spec):
        result = simulate(load_scene(path))
        assert result.columns["follower_lift_m"][1800] == pytest.approx(0.005, rel=1e-12)  # theta = pi
        assert result.columns["follower_velocity_m_s"][900] == pytest.approx(0.0025 * load_scene(path).omega, rel=1e-12)
        with pytest.raises(InputError) as info:
            load_scene(path, ['lift.law="cycloidal"'])  # its key is no other law's
        assert info.value.key in ("lift.amplitude", "lift.height")
        missing = tmp_path / "missing.toml"
        missing.write_text(path.read_text().replace('amplitude = "5 mm"\n', ""))
        with pytest.raises(InputError) as info:
            load_scene(missing)
        assert info.value.key == "lift.amplitude"


# ------------------------------------------------------------------------------------------------
# the browser's law list, from the tables


def test_the_offered_laws_are_those_that_load_on_every_builtin_scene():
    """model.offered_laws reads the tables (LawSpec.fits, Gear.accepts_law) instead of trying each
    law; oracle: try each law (load and build the lift), as the dropdown used to."""
    from explorer.effects.lift import build_lift
    from explorer.lift.registry import names
    from explorer.view.browser.model import offered_laws

    def loads(path, law):
        try:
            build_lift(load_scene(path, [f'lift.law="{law}"']))
            return True
        except Exception:  # noqa: BLE001 - the oracle: what fails is not offered
            return False

    for path in sorted(SCENES.glob("*.toml")):
        current = load_scene(path).lift.law
        expected = tuple(law for law in names() if law == current or loads(path, law))
        assert offered_laws(str(path), (), current) == expected, path.name


# ------------------------------------------------------------------------------------------------
# no gear or solver name outside its own modules and the tables


def _module_of(reference: str) -> str:
    return reference.partition(":")[0]


def _owned(graph, roots: dict[str, set[str]], families: bool = False) -> dict[str, frozenset[str]]:
    """module -> the plug-ins that own it: a plug-in's own modules, and the modules of the package
    that only that plug-in's modules reach through their imports (its helpers). families: plug-ins
    that share an own module are one family and own together what only they reach (the solver
    table's exact-compiled is the exact solver's batch module run as a solver: it reaches the exact
    solver's modules, which may still name "exact"; a helper every solver reaches, phases.py, no
    solver's name)."""
    reach: dict[str, set[str]] = {}
    for plugin, modules in roots.items():
        seen, stack = set(), list(modules)
        while stack:
            m = stack.pop()
            if m in seen:
                continue
            seen.add(m)
            stack.extend(graph.get(m, ()))
        for m in seen:
            reach.setdefault(m, set()).add(plugin)
    family = {plugin: {plugin} for plugin in roots}
    if families:
        for a in roots:
            for b in roots:
                if a != b and roots[a] & roots[b]:
                    joined = family[a] | family[b]
                    for plugin in joined:
                        family[plugin] = joined
    return {m: frozenset(p) for m, p in reach.items() if all(family[q] == family[next(iter(p))] for q in p)}


def _string_literals(path: Path):
    tree = ast.parse(path.read_text(encoding="utf-8"))
    docs = {id(n.value) for n in ast.walk(tree) if isinstance(n, ast.Expr) and isinstance(n.value, ast.Constant)}
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docs:
            yield node.lineno, node.value


def name_leaks(package: Path = PACKAGE) -> list[str]:
    """Every string literal (not a docstring) equal to a gear's follower type or a solver's name,
    in a module that is neither that plug-in's own (its module, its view, their private helpers)
    nor a table (the registries)."""
    from explorer.dynamics.solvers import SOLVERS
    from explorer.gears.registry import GEARS

    graph = import_graph(package)
    gear_roots = {name: {_module_of(GEARS.raw(name)), _module_of(VIEWS.raw(name))} for name in GEARS.names()}
    solver_roots = {info.name: {_module_of(t) for t in (info.entry, info.chain_entry, info.batch_entry, info.stable_steps)
                                if t} for info in SOLVERS.entries()}
    owners = {**_owned(graph, gear_roots), **_owned(graph, solver_roots, families=True)}
    tables = {"explorer.gears.registry", "explorer.view.gear_views", "explorer.dynamics.solvers"}
    problems = []
    for module, path in sorted(_modules(package).items()):
        if module in tables:
            continue
        for line, value in _string_literals(path):
            if value in GEARS or value in SOLVERS:
                if value not in owners.get(module, ()):
                    problems.append(f"{module}:{line} names {value!r}")
    return problems


def _modules(package: Path) -> dict[str, Path]:
    from import_cycles import module_names

    return module_names(package)


def test_no_gear_or_solver_name_outside_its_own_modules_and_the_tables():
    assert name_leaks() == []


def test_the_name_check_sees_a_planted_name(tmp_path, monkeypatch):
    """A copy of the package with `if follower.type == "rocking-cam":` planted in an effect."""
    import shutil

    copy = tmp_path / "explorer"
    shutil.copytree(PACKAGE, copy, ignore=shutil.ignore_patterns("__pycache__"))
    target = copy / "effects" / "kinematics.py"
    target.write_text(target.read_text() + '\n\ndef _planted(scene):\n    return scene.follower.type == "rocking-cam"\n')
    solver = copy / "effects" / "forces.py"
    solver.write_text(solver.read_text() + '\n\n_PLANTED = {"method": "scipy"}\n')
    leaks = name_leaks(copy)
    assert any(leak.startswith("explorer.effects.kinematics:") and "'rocking-cam'" in leak for leak in leaks)
    assert any(leak.startswith("explorer.effects.forces:") and "'scipy'" in leak for leak in leaks)
    assert len(leaks) == 2


# ------------------------------------------------------------------------------------------------
# a toy solver: the exact solver's function under another name, without a compiled batch module


def test_a_toy_solver_is_one_table_line(tmp_path):
    """register_solver: the scene loader offers it as solver.method, simulate runs it (equal to the
    exact solver's to the bit: the same function), a sweep runs it run by run (no batch_entry: the
    shared engine, not the compiled path)."""
    from dataclasses import replace

    from explorer.dynamics.solvers import register_solver, solver
    from explorer.studies.sweep_engine import _Shared, engine_for

    path = SCENES / "valve_float_demo.toml"
    toy = replace(solver("exact"), name="toy-exact", description="the plug-in tests' toy", batch_entry=None)
    with pytest.raises(InputError):
        load_scene(path, ['solver.method="toy-exact"'])
    with register_solver(toy):
        scene = load_scene(path, ['solver.method="toy-exact"', 'effects=["elastic"]'])
        exact = simulate(scene.with_changes(solver=replace(scene.solver, method="exact")))
        mine = simulate(scene)
        assert np.array_equal(mine.columns["valve_lift_m"], exact.columns["valve_lift_m"])
        assert mine.summary["elastic_method"] == "toy-exact"
        assert engine_for(scene, _Shared()).name == "shared"
        assert engine_for(scene.with_changes(solver=replace(scene.solver, method="exact")), _Shared()).name == "compiled"


# a toy design rule: the valve's largest travel, defined here and registered with one call


def _toy_travel(case, settings):
    """ratio L - lash at its largest, per run (N, 1): independent of the speed."""
    from explorer.checks.rule import Measure

    travel = case.valve_lift()
    worst = np.argmax(travel, axis=1)
    return Measure.of(travel[np.arange(travel.shape[0]), worst][:, None], case.theta_deg[worst][:, None], None,
                      settings, note="the plug-in tests' toy")


def _toy_rule():
    from explorer.checks.rule import Plotted, RuleSpec, Setting

    return RuleSpec("toy_valve_travel", _toy_travel, "Valve travel (toy)", "largest ratio L - lash", "mm", "max", (
        Setting("fail", 0.020, "length", "mm", "the plug-in tests' toy", "test"),
        Setting("warn", None, "length", "mm", "none by default", "-", minimum=0.0),
    ), "kinematics", (Plotted("rigid_valve_lift_m"),))


def test_a_toy_design_rule_is_one_call_and_is_judged_by_check(tmp_path):
    """register_rule: `explorer.check` judges the rule with the others; its value is the rigid
    valve lift's peak of simulate (the same L - lash on the same grid, to the bit); a rules file
    sets its limits (refused before it is registered: an unknown rule); undone, the table is as it
    was."""
    import explorer
    from explorer.checks.registry import register_rule, rule_names

    path = str(SCENES / "valve_float_demo.toml")
    scene = load_scene(path)
    peak = float(simulate(scene).columns["rigid_valve_lift_m"].max())
    limits = tmp_path / "toy.toml"
    limits.write_text(f'[toy_valve_travel]\nfail = "{peak * 1e3 * 0.99} mm"\nwarn = "{peak * 1e3 * 0.5} mm"\n')
    before = rule_names()
    with pytest.raises(InputError, match="unknown rule"):
        explorer.check(scene, rpm="2000", rules=str(limits), workers=1)
    with register_rule(_toy_rule()):
        assert rule_names() == (*before, "toy_valve_travel")
        report = explorer.check(scene, rpm="2000:4000:3", only=("toy_valve_travel", "pressure_angle"), workers=1)
        toy = report.result("toy_valve_travel")
        assert toy.verdict == "pass" and toy.value == peak  # below the default 20 mm
        assert report.result("seat_bounce").verdict == "off"
        # its own line declares where the viewers draw its limit: the fail line on the lift's plot
        from explorer.checks.viewer import line as check_line
        from explorer.view.verdicts import Threshold

        assert check_line(toy).thresholds == (Threshold("rigid_valve_lift_m", (0.020,), "fail"),)
        strict = explorer.check(scene, rpm="2000:4000:3", rules=str(limits), only=("toy_valve_travel",), workers=1)
        assert strict.result("toy_valve_travel").verdict == "fail" and strict.verdict == "fail"
        with pytest.raises(ValueError, match="registered already"):
            register_rule(_toy_rule())
    assert rule_names() == before
    assert "toy_valve_travel" not in {r.name for r in explorer.check(scene, rpm="2000", workers=1).results}
