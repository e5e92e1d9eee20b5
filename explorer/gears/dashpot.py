"""Buffers that cushion a trip gear's valve as it seats: air and oil dashpots.

Schenker announced a comparison of the two buffer systems of free-fall gears (air cushioning,
liquid cushioning) for part 2 of his paper, which is not in our text ("Schluss folgt"). These
models follow from first principles instead:

Air: a piston of area A on the valve spindle closes a pocket when the valve is within `stroke`
of its seat. The trapped air, volume V = A (s + clearance), is compressed polytropically
(p / rho^n constant for the gas that stays) and escapes through an orifice of area a_o
(isentropic nozzle flow, choked below the critical pressure ratio). Mass balance:
V drho/dt = -rho A ds/dt - mdot_out. Force on the valve (upwards, resisting closure): (p - p_a) A.
The cushion is elastic: it can throw the valve back. How air gets back in is the `inlet`:
  "check-valve"  (the usual buffer design, the default) the pocket refills through a non-return
                 valve, so it never pulls on the valve: the pressure never falls below ambient.
                 While the pocket expands at ambient pressure the inflow is free and the density
                 stays the ambient density; force max(p - p_a, 0) A. The orifice only throttles
                 the escaping air.
  "orifice"      the orifice is the only passage, both ways: below ambient air flows back in
                 through it (the same nozzle law from ambient), so an expanding pocket sucks:
                 lifting the valve off its seat pulls it down, and a rebound inside the pocket
                 is braked by suction.

Oil: incompressible oil displaced by the piston leaves through an orifice: flow Q = A |v|,
pressure drop (rho_oil / 2) (Q / (C_d a_o))^2, force c v^2 with c = rho_oil A^3 / (2 C_d^2 a_o^2),
resisting the closing stroke only (a check valve refills the cylinder on the way up). Purely
dissipative: no rebound. Under a constant net force F the closed form is
    v^2(y) = F/c + (v_in^2 - F/c) exp(-2 c y / M)        (y: travel into the cushion)
which the tests use as an oracle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

STANDARD_PRESSURE = 101_325.0  # Pa
STANDARD_TEMPERATURE = 293.15  # K
AIR_GAS_CONSTANT = 287.05  # J/(kg K)
INLETS = ("check-valve", "orifice")


@dataclass(frozen=True)
class AirDashpot:
    area: float  # A, m^2
    stroke: float  # m: the pocket closes when the valve is this far from its seat
    clearance: float  # m: dead volume / A left at the seat
    orifice_area: float  # a_o, m^2 (0: sealed)
    discharge: float = 0.62  # C_d
    exponent: float = 1.4  # polytropic n of the trapped air (1 isothermal ... 1.4 adiabatic)
    ambient_pressure: float = STANDARD_PRESSURE
    ambient_temperature: float = STANDARD_TEMPERATURE
    gamma: float = 1.4  # ratio of specific heats, for the orifice flow
    gas_constant: float = AIR_GAS_CONSTANT
    inlet: str = "check-valve"  # how air gets back in (module docstring): "check-valve" | "orifice"

    kind = "air"
    has_state = True

    def __post_init__(self) -> None:
        if self.inlet not in INLETS:
            raise ValueError(f"AirDashpot.inlet must be one of {INLETS}, not {self.inlet!r}")

    @property
    def check_valve(self) -> bool:
        return self.inlet == "check-valve"

    @property
    def ambient_density(self) -> float:
        return self.ambient_pressure / (self.gas_constant * self.ambient_temperature)

    def pressure(self, rho):
        return self.ambient_pressure * (rho / self.ambient_density) ** self.exponent

    def volume(self, s):
        return self.area * (s + self.clearance)

    def gauge_force(self, rho):
        """(p - p_a) A, N: the closed pocket's force, continued smoothly below ambient (the
        integrator's right-hand side inside a closed stretch, which ends where a check valve opens)."""
        return (self.pressure(rho) - self.ambient_pressure) * self.area

    def force(self, s, v, rho):
        """Upward force on the valve, N: (p - p_a) A; never a pull with a check valve."""
        f = self.gauge_force(rho)
        if self.check_valve:
            f = np.maximum(f, 0.0)
            return float(f) if np.ndim(f) == 0 else f
        return f

    def force_partials(self, s, v, rho):
        """(dF/ds, dF/dv, dF/drho) at fixed other state."""
        d_rho = self.area * self.exponent * self.pressure(rho) / rho
        if self.check_valve:
            d_rho = np.where(self.pressure(rho) >= self.ambient_pressure, d_rho, 0.0)
            d_rho = float(d_rho) if np.ndim(d_rho) == 0 else d_rho
        return 0.0, 0.0, d_rho

    def mass_outflow(self, rho):
        """Mass flow out of the pocket through the orifice (negative: inflow), kg/s. With a check
        valve the orifice only lets air out: the refill below ambient is density_rate's."""
        if np.ndim(rho) == 0:  # the ODE's right-hand side: plain floats, no array overhead
            return self._mass_outflow_scalar(float(rho))
        rho = np.asarray(rho, dtype=float)
        p = self.pressure(rho)
        pa = self.ambient_pressure
        temperature = p / (rho * self.gas_constant)
        area = self.orifice_area * self.discharge
        out = nozzle_flow(p, temperature, pa, area, self.gamma, self.gas_constant)
        back = 0.0 if self.check_valve else nozzle_flow(pa, self.ambient_temperature, p, area, self.gamma,
                                                        self.gas_constant)
        flow = np.where(p >= pa, out, -back)
        return float(flow) if flow.ndim == 0 else flow

    def _mass_outflow_scalar(self, rho: float) -> float:
        p = self.ambient_pressure * (rho / self.ambient_density) ** self.exponent
        pa = self.ambient_pressure
        area = self.orifice_area * self.discharge
        if p >= pa:
            return _nozzle_scalar(p, p / (rho * self.gas_constant), pa, area, self.gamma, self.gas_constant)
        if self.check_valve:
            return 0.0
        return -_nozzle_scalar(pa, self.ambient_temperature, p, area, self.gamma, self.gas_constant)

    def pocket_density_rate(self, s, v, rho):
        """drho/dt of the closed pocket, the check valve shut: (-rho A v - mdot_out) / V. For a check
        valve this continues smoothly below ambient (no orifice flow there), so that the opening of
        the check valve is a clean sign change of rho - rho_a for the integrator's event."""
        return (-rho * self.area * v - self.mass_outflow(rho)) / self.volume(s)

    def density_rate(self, s, v, rho):
        """drho/dt of the pocket, kg/(m^3 s). With a check valve the pocket at (or below) ambient
        that expands refills freely: the density is held at the ambient density (rate 0)."""
        rate = self.pocket_density_rate(s, v, rho)
        if self.check_valve:
            held = (np.asarray(rho) <= self.ambient_density) & (np.asarray(rate) < 0.0)
            rate = np.where(held, 0.0, rate)
            return float(rate) if np.ndim(rate) == 0 else rate
        return rate

    def sealed_work(self, travel: float) -> float:
        """Work done on a sealed pocket (no leak) compressed from the entry over `travel`, J:
        the closed form of the integral of (p - p_a) A dy for p V^n = p_a V0^n."""
        v0 = self.volume(self.stroke)
        v1 = self.volume(self.stroke - travel)
        n, pa = self.exponent, self.ambient_pressure
        if abs(n - 1.0) < 1e-12:
            polytropic = pa * v0 * math.log(v0 / v1)
        else:
            polytropic = pa * v0 * ((v0 / v1) ** (n - 1.0) - 1.0) / (n - 1.0)
        return polytropic - pa * (v0 - v1)


@dataclass(frozen=True)
class OilDashpot:
    area: float  # A, m^2
    stroke: float  # m
    orifice_area: float  # a_o, m^2
    discharge: float = 0.62
    density: float = 880.0  # kg/m^3

    kind = "oil"
    has_state = False

    @property
    def coefficient(self) -> float:
        """c in F = c v^2, N s^2/m^2."""
        return self.density * self.area**3 / (2.0 * (self.discharge * self.orifice_area) ** 2)

    def force(self, s, v, rho=None):
        v = np.asarray(v, dtype=float)
        f = np.where(v < 0.0, self.coefficient * v * v, 0.0)
        return float(f) if f.ndim == 0 else f

    def force_partials(self, s, v, rho=None):
        v = np.asarray(v, dtype=float)
        dv = np.where(v < 0.0, 2.0 * self.coefficient * v, 0.0)
        return 0.0, (float(dv) if dv.ndim == 0 else dv), 0.0


def nozzle_flow(p_up, t_up, p_down, effective_area: float, gamma: float, gas_constant: float):
    """Isentropic nozzle mass flow, kg/s, choked when p_down / p_up falls below the critical ratio;
    zero where p_up <= p_down (arrays or floats)."""
    p_up, p_down = np.asarray(p_up, dtype=float), np.asarray(p_down, dtype=float)
    if effective_area <= 0.0:
        return np.zeros(np.broadcast_shapes(p_up.shape, p_down.shape))
    ratio = np.clip(p_down / p_up, 0.0, 1.0)
    critical = (2.0 / (gamma + 1.0)) ** (gamma / (gamma - 1.0))
    scale = effective_area * p_up / np.sqrt(gas_constant * np.asarray(t_up, dtype=float))
    choked = math.sqrt(gamma) * (2.0 / (gamma + 1.0)) ** ((gamma + 1.0) / (2.0 * (gamma - 1.0)))
    r = np.maximum(ratio, critical)
    subsonic = np.sqrt(2.0 * gamma / (gamma - 1.0) * np.maximum(r ** (2.0 / gamma) - r ** ((gamma + 1.0) / gamma), 0.0))
    flow = scale * np.where(ratio <= critical, choked, subsonic)
    return np.where(p_up > p_down, flow, 0.0)


def _nozzle_scalar(p_up, t_up, p_down, effective_area, gamma, gas_constant) -> float:
    """nozzle_flow for floats (same formula)."""
    if effective_area <= 0.0 or p_up <= p_down:
        return 0.0
    ratio = p_down / p_up
    critical = (2.0 / (gamma + 1.0)) ** (gamma / (gamma - 1.0))
    scale = effective_area * p_up / math.sqrt(gas_constant * t_up)
    if ratio <= critical:
        return scale * math.sqrt(gamma) * (2.0 / (gamma + 1.0)) ** ((gamma + 1.0) / (2.0 * (gamma - 1.0)))
    return scale * math.sqrt(2.0 * gamma / (gamma - 1.0) * (ratio ** (2.0 / gamma) - ratio ** ((gamma + 1.0) / gamma)))


def oil_seating_velocity(mass: float, net_force: float, coefficient: float, entry_speed: float, travel: float) -> float:
    """Closed form: speed after `travel` into an oil cushion under a constant net closing force."""
    terminal = net_force / coefficient
    return math.sqrt(terminal + (entry_speed**2 - terminal) * math.exp(-2.0 * coefficient * travel / mass))


def cylinder_area(diameter: float) -> float:
    return math.pi * diameter**2 / 4.0
