"""Valve-spring strength (explorer/mechanics/valve_spring.py) against worked numbers and
independent constructions.

Printed digits retrieved with the project's search tool:
- R. L. Norton, Machine Design: An Integrated Approach, Example 14-4 "Design of a helical
  compression spring for cyclic loading" (as reproduced step by step at holooly.com, Question
  14.4): music wire d = 0.207 in, index C = 9, forces 60 lb (initial) and 105 lb (mean); the
  direct-shear factor K_s = 1 + 0.5/C = 1.056 and tau_i = 33 875 psi, tau_m = 59 281 psi.
- Wahl's factor: (4C - 1)/(4C - 4) + 0.615/C = 1.2525 at C = 6 (a valve-spring example, askfilo.com
  "Example 16.5") and 1.1448 at C = 10 (machinecalcs.com's music-wire worked example, which also
  prints 361 MPa for 12.39 N on d = 1 mm, D = 10 mm).
- Zimmerli's endurance data: 241/379 MPa unpeened, 398/534 MPa peened (amesweb.info's table of
  Shigley's spring fatigue formulas).
A worked Goodman factor with its printed digits could not be retrieved; the factor is checked
against the geometric construction it stands for (the load line meeting the Goodman line),
solved here as two linear equations.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from explorer.mechanics import valve_spring as vs
from explorer.mechanics.materials import SPRING_WIRES

INCH, LBF, PSI = 0.0254, 4.4482216152605, 6894.757293168361


def test_norton_example_14_4_stresses():
    d = 0.207 * INCH
    D = 9.0 * d  # C = 9
    assert float(vs.direct_shear_factor(9.0)) == pytest.approx(1.056, abs=5e-4)
    tau_i = vs.shear_stress(60 * LBF, D, d, "direct-shear") / PSI
    tau_m = vs.shear_stress(105 * LBF, D, d, "direct-shear") / PSI
    assert tau_i == pytest.approx(33875, abs=0.5)  # printed: 33875 psi
    assert tau_m == pytest.approx(59281, abs=0.5)  # printed: 59281 psi


def test_wahl_factor_printed_values():
    assert float(vs.wahl_factor(6.0)) == pytest.approx(1.2525, abs=5e-5)
    assert float(vs.wahl_factor(10.0)) == pytest.approx(1.1448, abs=5e-5)
    tau = vs.shear_stress(12.39, 10e-3, 1e-3, "wahl")
    assert tau / 1e6 == pytest.approx(361, abs=0.5)  # "about 361 MPa"


def test_corrections_agree_within_a_few_percent_and_order():
    c = np.linspace(4.0, 12.0, 17)
    kw, kb, ks = vs.wahl_factor(c), vs.bergstrasser_factor(c), vs.direct_shear_factor(c)
    assert np.all(np.abs(kw / kb - 1.0) < 0.015)  # within 1.4 % over C = 4..12 (Shigley: "about 1 %")
    assert np.all(ks < kb) and np.all(ks < kw)  # curvature adds to the direct shear


def test_zimmerli_and_rupture():
    assert vs.ZIMMERLI[False] == (241e6, 379e6)
    assert vs.ZIMMERLI[True] == (398e6, 534e6)
    assert vs.TORSIONAL_RUPTURE == 0.67


@pytest.mark.parametrize("tau_a, tau_m, s_ut", [(150e6, 500e6, 1700e6), (80e6, 300e6, 1600e6), (260e6, 260e6, 2000e6)])
@pytest.mark.parametrize("peened", [False, True])
def test_goodman_factor_is_the_load_line_meeting_the_goodman_line(tau_a, tau_m, s_ut, peened):
    s_sa, s_sm = vs.ZIMMERLI[peened]
    s_su = vs.TORSIONAL_RUPTURE * s_ut
    s_se = vs.goodman_endurance(s_sa, s_sm, s_su)
    # the Goodman line through Zimmerli's point (s_sm, s_sa) and (s_su, 0) meets tau_m = 0 at s_se
    assert s_sa == pytest.approx(s_se * (1.0 - s_sm / s_su), rel=1e-14)
    # load line x = n tau_m, y = n tau_a meets the line through (s_sm, s_sa), (s_su, 0)
    slope = (0.0 - s_sa) / (s_su - s_sm)
    # unknowns (y, n): y - slope n tau_m = s_sa - slope s_sm and y - n tau_a = 0
    a = np.array([[1.0, -slope * tau_m], [1.0, -tau_a]])
    rhs = np.array([s_sa - slope * s_sm, 0.0])
    y, n = np.linalg.solve(a, rhs)
    assert float(vs.goodman_safety_factor(tau_a, tau_m, s_se, s_su)) == pytest.approx(n, rel=1e-12)


def test_coil_bind_margin():
    # L0 50 mm, preload 300 N at 30 N/mm: installed at 40 mm; 9 mm of lift: 31 mm; solid 25 mm: 6 mm left
    assert vs.installed_length(0.050, 300.0, 30e3) == pytest.approx(0.040, abs=1e-15)
    assert float(vs.coil_bind_margin(0.050, 0.025, 300.0, 30e3, 0.009)) == pytest.approx(0.006, abs=1e-15)


def test_wire_strength_table():
    # S_ut = A / d^m, d in mm: chrome-silicon 1960/2^0.091, music wire 2060/7.25^0.163 = 1492 MPa
    # (engineeringprep.com's worked problem prints 1492 MPa)
    assert SPRING_WIRES["chrome-silicon"].ultimate_tensile_strength(2e-3) == pytest.approx(1960e6 / 2**0.091, rel=1e-14)
    assert SPRING_WIRES["music-wire"].ultimate_tensile_strength(7.25e-3) / 1e6 == pytest.approx(1492, abs=0.5)


def test_bad_spring_geometry():
    from explorer.core.errors import InputError

    with pytest.raises(InputError):
        vs.shear_stress(100.0, 2e-3, 3e-3)
    with pytest.raises(InputError):
        vs.goodman_endurance(398e6, 534e6, 500e6)
