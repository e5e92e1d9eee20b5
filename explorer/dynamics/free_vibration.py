"""The valve's free vibration about its static equilibrium while the drive stands still (a dwell):
the residual vibration's amplitude (docs/theory/residual.md).

With the drive held at S (valve-referred: ratio times the follower lift) the contact equation of
the LinkageModel (explorer.dynamics.model) is

    M1 s'' + c s' + (k + rate) s = k (S - lash) - W0 - R sgn(s'),   W0 = preload + closing loads

so the valve rests at s_eq = (k (S - lash) - W0) / (k + rate) (Coulomb friction R widens that
point to the band s_eq +- R / (k + rate)), and a half-cycle of its free motion in one direction
is a harmonic oscillation about the band's far edge, s_eq - R sgn(s') / (k + rate), with the
undamped natural frequency wn = sqrt((k + rate) / M1): its amplitude is sqrt(z^2 + (s'/wn)^2),
z = s - that centre, the same at every instant of the half-cycle (undamped) -- the energy of the
motion as a distance. Where s_eq <= 0 the valve's equilibrium is its seat (a base-circle dwell):
z = s, 0 for a valve resting there.

Plain scalar arithmetic, so that the compiled solver (explorer.dynamics.exact_kernel) compiles
this very function and its figures are the elastic effect's (explorer.effects.residual) to the
bit (tests/test_residual.py).
"""

from __future__ import annotations

import math


def free_amplitude(s: float, v: float, S: float, k: float, lash: float, W0: float, rate: float, R: float,
                   M1: float) -> float:
    """The amplitude (m) of the valve's free vibration at lift s (m) and velocity v (m/s) with the
    drive held at S (m) (module doc). At v = 0 the half-cycle that begins: |s - s_eq| less the
    friction band's half-width, 0 inside the band (the valve sticks)."""
    kr = k + rate
    s_eq = (k * (S - lash) - W0) / kr
    y = v / math.sqrt(kr / M1)
    if not s_eq > 0.0:  # the seat holds the valve: the equilibrium is s = 0
        return math.sqrt(s * s + y * y)
    band = R / kr
    if v > 0.0:
        z = s - (s_eq - band)
    elif v < 0.0:
        z = s - (s_eq + band)
    else:
        return max(abs(s - s_eq) - band, 0.0)
    return math.sqrt(z * z + y * y)
