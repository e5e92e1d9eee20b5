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


def test_natural_frequency_as_cam_order():
    scene = load_scene(DEMO)
    spectrum = acceleration_spectrum(scene, build_lift(scene), orders=10)
    m = scene.valve.mass
    wn = math.sqrt((scene.linkage.stiffness + scene.spring.rate) / m)
    assert spectrum.natural_order == pytest.approx(wn / scene.omega, rel=1e-14)
    no_linkage = load_scene(SCENES / "cycloidal_demo.toml", ['effects=["kinematics"]'])
    from dataclasses import replace

    assert acceleration_spectrum(replace(no_linkage, linkage=None), build_lift(no_linkage), 5).natural_order is None


def test_spectrum_command(tmp_path, capsys):
    table, plot = tmp_path / "s.csv", tmp_path / "s.png"
    assert cli.main(["spectrum", str(DEMO), "--orders", "30", "-o", str(table), "--plot", str(plot)]) == 0
    lines = table.read_text().splitlines()
    assert "rings at cam order 13.07" in lines[0]
    assert lines[1] == "order,frequency_Hz,amplitude_m_s2,phase_rad" and len(lines) == 32
    assert plot.read_bytes()[:4] == b"\x89PNG"
    for bad in ("0", "100000"):
        assert cli.main(["spectrum", str(DEMO), "--orders", bad, "-o", str(tmp_path / "x.csv")]) == 2
        err = capsys.readouterr().err.strip()
        assert ERROR_LINE.match(err) and ": --orders: " in err
    assert not (tmp_path / "x.csv").exists()
