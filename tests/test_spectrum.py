"""`explorer spectrum`: the FFT of the analytic drive acceleration against its closed-form Fourier
series (a cycloidal rise and return: each flank's acceleration is one sine arch, whose Fourier
integral is closed), and the linkage's natural frequency as a cam order."""

from __future__ import annotations

import cmath
import math
import re

import numpy as np
import pytest

from conftest import SCENES
from explorer import cli
from explorer.effects.lift import build_lift
from explorer.scene.scene import load_scene
from explorer.studies.spectrum import acceleration_spectrum

DEMO = SCENES / "cycloidal_demo.toml"
ERROR_LINE = re.compile(r"^error: [^:\n]+: [^:\n]+: .+$")


def arch(n: int, height: float, width: float, start: float) -> complex:
    """(1/2pi) * integral over one flank of h (2 pi / width^2) sin(2 pi x / width) exp(-i n theta):
    with k = 2 pi / width, integral_0^width sin(k x) e^(-i n x) dx = k (1 - e^(-i n width)) / (k^2 - n^2)."""
    k = 2 * math.pi / width
    return height / width**2 * cmath.exp(-1j * n * start) * k * (1 - cmath.exp(-1j * n * width)) / (k * k - n * n)


@pytest.mark.parametrize("overrides", [[], ["lift.return=\"110 deg\"", "lift.dwell=\"25 deg\"", "follower.ratio=1.4"]])
def test_cycloidal_spectrum_matches_the_fourier_series(overrides):
    scene = load_scene(DEMO, overrides)
    spec = scene.lift
    spectrum = acceleration_spectrum(scene, build_lift(scene), orders=200)
    factor = scene.follower.ratio * scene.omega**2
    exact = []
    for n in spectrum.orders:
        c = arch(n, spec.height, spec.rise, spec.start) - arch(n, spec.height, spec.ret, spec.start + spec.rise + spec.dwell)
        exact.append(2 * abs(factor * c))
    exact = np.array(exact)
    # aliasing: the jerk jumps by up to J at the flanks' four ends, so |C_m| <~ 4 J / (2 pi m^2);
    # the orders folded onto n (m = n +- N, n +- 2N, ...) add ~ 2 |C_N|, and the amplitude is 2 |C|:
    # 16 J / (2 pi N^2) with N = 65536 samples, 1.3e-5 m/s^2 on the demo (measured 1.5e-5), 1e-8
    # of the largest harmonic; the bound is twice the estimate
    jerk_jump = factor * spec.height * (2 * math.pi) ** 2 / min(spec.rise, spec.ret) ** 3
    bound = 2 * 16 * jerk_jump / (2 * math.pi * spectrum.samples**2)
    assert np.max(np.abs(spectrum.amplitude - exact)) <= bound
    assert bound < 3e-8 * exact.max()  # so the check is tight
    assert abs(spectrum.mean) <= bound  # a closed event: no mean acceleration


def test_printed_phases_keep_only_the_digits_their_aliasing_error_leaves(tmp_path):
    """Issue #28.9: a phase printed as 2.43e-06 where the exact phase is 0 (elastic_float, order
    90: its acceleration jumps, so the FFT's aliasing error falls only as n/N). The printed phase
    is the FFT's rounded to the decade of its error estimate (core.units.resolved); oracle: the
    closed-form Fourier series of the cycloidal demo, every printed phase within its own rounding
    of the exact one, and the orders whose exact phase is 0 print as 0."""
    table = tmp_path / "s.csv"
    assert cli.main(["spectrum", str(SCENES / "elastic_float.toml"), "--orders", "100", "-o", str(table)]) == 0
    rows = {int(r.split(",")[0]): r.split(",") for r in table.read_text().splitlines()
            if not r.startswith(("#", "order"))}
    assert rows[90][3] == "0" and rows[18][3] == "0" and rows[54][3] == "0"

    scene = load_scene(DEMO)
    spec = scene.lift
    spectrum = acceleration_spectrum(scene, build_lift(scene), orders=200)
    factor = scene.follower.ratio * scene.omega**2
    zeros = 0
    for n, amplitude, phase in zip(spectrum.orders, spectrum.amplitude, spectrum.phase):
        c = factor * (arch(n, spec.height, spec.rise, spec.start)
                      - arch(n, spec.height, spec.ret, spec.start + spec.rise + spec.dwell))
        if 2 * abs(c) < 1e-6 * spectrum.amplitude.max():
            continue  # a zero of the series: its phase is undefined
        exact = cmath.phase(c)
        # the phase prints with d decimals; its distance from the exact phase (mod 2 pi) is at
        # most half the last decimal plus the error, which the rounding keeps below one decimal
        text = f"{phase:.10g}"
        decimals = len(text.split(".")[1]) if "." in text else 0
        miss = abs((phase - exact + math.pi) % (2 * math.pi) - math.pi)
        assert miss <= 10.0 ** -decimals, (n, phase, exact)
        if abs(exact) < 1e-12:
            zeros += 1
            assert phase == 0.0, (n, phase)
    assert zeros >= 10  # orders 8, 16, ...: n * 90 deg (the event's centre) a multiple of 360 deg


def test_natural_frequency_as_cam_order():
    scene = load_scene(DEMO)
    spectrum = acceleration_spectrum(scene, build_lift(scene), orders=10)
    m = scene.valve.mass
    wn = math.sqrt((scene.linkage.stiffness + scene.spring.rate) / m)
    assert spectrum.natural_order == pytest.approx(wn / scene.omega, rel=1e-14)
    no_linkage = load_scene(SCENES / "cycloidal_demo.toml", ['effects=["kinematics"]'])
    from dataclasses import replace

    assert acceleration_spectrum(replace(no_linkage, linkage=None), build_lift(no_linkage), 5).natural_order is None


def test_the_springs_surge_frequencies_as_cam_orders():
    """Against the closed forms: the chain's 2 (N+1) sqrt(k/m_s) sin(j pi / (2 (N+1))) when the
    scene cuts the spring into N masses, the continuous spring's (j/2) sqrt(k/m_s) otherwise."""
    from dataclasses import replace

    scene = load_scene(SCENES / "spring_surge.toml")
    spring, w = scene.spring, scene.omega
    N, k, m = spring.elements, spring.rate, spring.mass
    spectrum = acceleration_spectrum(scene, build_lift(scene), orders=200)
    chain = [2 * (N + 1) * math.sqrt(k / m) * math.sin(j * math.pi / (2 * (N + 1))) / w for j in range(1, N + 1)]
    assert spectrum.spring_orders == pytest.approx([o for o in chain if o <= 200], rel=1e-13)
    assert spectrum.spring_orders  # the scene's spring surges within 200 orders
    massless_chain = replace(scene, spring=replace(spring, elements=0))
    continuous = acceleration_spectrum(massless_chain, build_lift(scene), orders=200).spring_orders
    f1 = 0.5 * math.sqrt(k / m)  # Hz
    expected = [j * f1 * 2 * math.pi / w for j in range(1, 1000) if j * f1 * 2 * math.pi / w <= 200]
    assert continuous == pytest.approx(expected, rel=1e-13)
    no_mass = replace(scene, spring=replace(spring, mass=0.0, elements=0))
    assert acceleration_spectrum(no_mass, build_lift(scene), orders=200).spring_orders == ()


def test_spectrum_command(tmp_path, capsys):
    table, plot = tmp_path / "s.csv", tmp_path / "s.png"
    assert cli.main(["spectrum", str(DEMO), "--orders", "30", "-o", str(table), "--plot", str(plot)]) == 0
    lines = table.read_text().splitlines()
    assert "rings at cam order 13.07" in lines[0]
    assert lines[1].startswith("# S''(theta) = ") and "amplitude cos(n theta + phase)" in lines[1]
    assert lines[2] == "order,frequency_Hz,amplitude_m_s2,phase_rad" and len(lines) == 33
    assert plot.read_bytes()[:4] == b"\x89PNG"
    for bad in ("0", "100000"):
        assert cli.main(["spectrum", str(DEMO), "--orders", bad, "-o", str(tmp_path / "x.csv")]) == 2
        err = capsys.readouterr().err.strip()
        assert ERROR_LINE.match(err) and ": --orders: " in err
    assert not (tmp_path / "x.csv").exists()
