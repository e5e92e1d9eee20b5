"""The hydraulic lash adjuster (HLA): a plunger in a body over a high-pressure oil chamber.

Physics (all SI; the plunger's travel p is positive into the body, "collapse"):
  plunger     m_p p'' = F_load - A P - F_0 - k_s p     (A = pi d^2 / 4, P the chamber's gauge
                                                       pressure, F_0 + k_s p the plunger spring)
  chamber     (V / beta_e) P' = A p' - Q_leak + Q_refill
  leak-down   Q_leak = G_l (P - P_s),  G_l = pi d c^3 (1 + 1.5 e^2) / (12 mu L)
              laminar flow through the plunger's clearance (radial clearance c, length L, oil
              viscosity mu) back to the supply (P_s); e = the plunger's eccentricity in the bore
              (0 concentric, 1 touching), the factor 1 + 1.5 e^2 of the eccentric annulus:
              plane Poiseuille flow through the local gap h = c (1 + e cos t) summed round the
              bore, q = (d/2) dp / (12 mu L) int_0^2pi h^3 dt = pi d c^3 dp (1 + 1.5 e^2) / (12 mu L)
              (the lubrication approximation, c << d; Merritt, Hydraulic Control Systems, Wiley
              1967, chapter 3, leakage past an eccentric piston; tests: the integral by quadrature).
  check valve open while the chamber is below the supply less the valve's cracking pressure
              P_c: Q_refill = G_r (P_s - P_c - P), else 0. It opens when P falls to P_s - P_c and
              closes when the refill flow would reverse (P back at P_s - P_c): the flow is
              continuous across the switch, so the switching does not chatter.
              G_r is the secant conductance of the orifice law Q = C_d A_o sqrt(2 dp / rho) at the
              pressure drop dp_ref: G_r = C_d A_o sqrt(2 / (rho dp_ref)); the linear law agrees with
              the orifice at dp_ref and elsewhere gives G_r dp / (C_d A_o sqrt(2 dp / rho))
              = sqrt(dp / dp_ref) times the orifice's flow: more above dp_ref, less below (what
              keeps each phase linear, hence solved exactly).
  aeration    entrained air of volume fraction X (at the supply pressure) makes the oil softer:
              1 / beta_e = 1 / beta_l + (V_g / V_t) / beta_g, beta_g = n p (Merritt 1967,
              chapter 2, the effective bulk modulus of a liquid with entrained air, the container
              taken rigid). Linear phases need one modulus: the secant modulus over
              the compression from the supply pressure to reference_pressure, the oil by its
              bulk modulus, the air polytropically (p V^n const):
                dV / V_t = (1 - X) (p_r - p_s) / beta_l + X (1 - (p_s,abs / p_r,abs)^(1/n)),
                beta_e = (p_r - p_s) / (dV / V_t);  X = 0 gives beta_l.
              The chord of the mixture's pressure-volume curve: exact at p_s and p_r, too stiff
              between and too soft beyond (the air stiffens as it is compressed: the tangent
              modulus 1 / ((1 - X) / beta_l + X p_s,abs^(1/n) / (n p_abs^(1 + 1/n))) rises from
              20 MPa at 3 bar to 1.1 GPa at 5.7 MPa with 2 % air). reference_pressure is an input
              (default 10 MPa), not fitted to the run: it should sit near the chamber's peak
              pressure, which the summary reports (hla.chamber_pressure_max_Pa, and the secant to
              it, secant_modulus_at_peak_Pa; a run warns where the two secants are over 50 %
              apart: effects/train_elastic.py). Run with the default 10 MPa, finger_hla_pumpup
              peaked at 5.7 MPa: the secant to 5.7 MPa is 243 MPa against 380 MPa, the oil column
              15.6 against 24.3 N/um, the train's lowest mode 2256 against 2528 Hz (tests:
              test_secant_modulus_against_the_scenes_peak); the scene sets 5.7 MPa.
Linearised about the chamber's volume V (the plunger's travel changes it by A p, a few per cent
over a lift). Each phase (check valve shut / open) is linear, so the exact solver's closed forms
apply: the chamber pressure is a first-order state of phase_system.py (Cap = V / beta_e, H = A on
the plunger, G = G_l (+ G_r)).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .phase_system import Event, PhaseModes, Transition, decompose, state_matrix

ATMOSPHERE = 101_325.0  # Pa: absolute = gauge + this (the air's polytropic law needs absolute pressure)


@dataclass(frozen=True)
class HLA:
    plunger_mass: float  # kg
    plunger_diameter: float  # m: the chamber's area and the leak gap's diameter
    clearance: float  # m, radial, plunger in its bore
    leak_length: float  # m, the sealing length of that clearance
    viscosity: float  # Pa*s, the oil's dynamic viscosity
    chamber_volume: float  # m^3, the high-pressure chamber
    supply_pressure: float  # Pa, gauge: the oil gallery's
    bulk_modulus: float = 1.5e9  # Pa, the oil's
    aeration: float = 0.0  # volume fraction of entrained air at the supply pressure
    polytropic_index: float = 1.0  # of the air (1 isothermal, 1.4 adiabatic)
    reference_pressure: float = 10e6  # Pa, gauge: the secant modulus's upper end (~ the chamber's peak)
    eccentricity: float = 0.0  # plunger in its bore: 0 concentric .. 1 touching
    cracking_pressure: float = 0.0  # Pa, the check valve's opening pressure difference
    check_diameter: float = 2e-3  # m, the check valve's orifice
    discharge_coefficient: float = 0.7
    oil_density: float = 850.0  # kg/m^3
    refill_pressure_drop: float = 0.1e6  # Pa, where the linear refill law equals the orifice's
    spring_rate: float = 0.0  # N/m, the plunger spring
    spring_preload: float = 0.0  # N, the plunger spring's force at p = 0 (pushes the plunger out)
    lever: float = 1.0  # valve travel per unit plunger travel at the joint it sits in
    # the plunger's outward travel from its rest on the base circle to its retaining stop (m;
    # None: no stop), and the stop's stiffness and damping
    travel: float | None = None
    stop_stiffness: float = 1e8  # N/m
    stop_damping: float = 0.0  # N*s/m

    @property
    def area(self) -> float:
        return math.pi * self.plunger_diameter**2 / 4.0

    @property
    def leak_conductance(self) -> float:
        """G_l = pi d c^3 (1 + 1.5 e^2) / (12 mu L), m^3/(s Pa)."""
        c = self.clearance
        return (math.pi * self.plunger_diameter * c**3 * (1.0 + 1.5 * self.eccentricity**2)
                / (12.0 * self.viscosity * self.leak_length))

    @property
    def refill_conductance(self) -> float:
        """G_r = C_d A_o sqrt(2 / (rho dp_ref)), m^3/(s Pa): the orifice's secant at dp_ref."""
        area = math.pi * self.check_diameter**2 / 4.0
        return self.discharge_coefficient * area * math.sqrt(2.0 / (self.oil_density * self.refill_pressure_drop))

    @property
    def effective_bulk_modulus(self) -> float:
        """beta_e: the oil-air mixture's secant modulus from the supply to the reference pressure."""
        X = self.aeration
        if X == 0.0:
            return self.bulk_modulus
        ps, pr = self.supply_pressure, self.reference_pressure
        strain = ((1.0 - X) * (pr - ps) / self.bulk_modulus
                  + X * (1.0 - ((ps + ATMOSPHERE) / (pr + ATMOSPHERE)) ** (1.0 / self.polytropic_index)))
        return (pr - ps) / strain

    @property
    def capacitance(self) -> float:
        """V / beta_e, m^3/Pa."""
        return self.chamber_volume / self.effective_bulk_modulus

    @property
    def oil_stiffness(self) -> float:
        """A^2 beta_e / V (N/m): the trapped oil column's stiffness at the plunger."""
        return self.area**2 / self.capacitance

    @property
    def check_threshold(self) -> float:
        """P_s - P_c (Pa, gauge): below it the check valve is open."""
        return self.supply_pressure - self.cracking_pressure

    def leakdown_velocity(self, load: float) -> float:
        """The plunger's steady sinking speed (m/s) under a constant load (N) with the check valve
        shut: A P = load - F_0 (the spring's travel neglected), Q = G_l (P - P_s) = A p'."""
        P = (load - self.spring_preload) / self.area
        return self.leak_conductance * (P - self.supply_pressure) / self.area

    def refill_flow(self, pressure_drop: float) -> float:
        """The linear refill law's flow (m^3/s) at a pressure drop across the check valve."""
        return self.refill_conductance * pressure_drop

    def orifice_flow(self, pressure_drop: float) -> float:
        """The orifice law's flow C_d A_o sqrt(2 dp / rho) (m^3/s): what the linear law stands for."""
        area = math.pi * self.check_diameter**2 / 4.0
        return self.discharge_coefficient * area * math.sqrt(2.0 * pressure_drop / self.oil_density)


class LeakdownRig:
    """An adjuster alone on a leak-down tester: a constant load W on its plunger (its body held),
    the chamber fed at the supply pressure through the check valve. A PhaseSystem (phase_system.py)
    of one mass and one first-order state, y = [p, p', P], phase key = the check valve open; the
    drive is not used. Its closed-form travel (a linear system with a constant load: the matrix
    exponential) and its leak-down rate (Poiseuille) are the oracles of the adjuster's equations
    as the valve train solves them (tests)."""

    def __init__(self, hla: HLA, load: float):
        self.hla, self.load = hla, load
        self.n, self.r, self.size, self.velocity_index = 1, 1, 3, 1

    def matrices(self, open_: bool):
        h = self.hla
        M = np.array([h.plunger_mass])
        K = np.array([[h.spring_rate]])
        C = np.zeros((1, 1))
        H = np.array([[h.area]])
        cap = np.array([h.capacitance])
        G = np.array([[h.leak_conductance + (h.refill_conductance if open_ else 0.0)]])
        return M, K, C, H, cap, G

    def forcing(self, open_: bool) -> np.ndarray:
        """B (3, 3): the state's sources per unit S, S', 1 (only the constant)."""
        h = self.hla
        M, _, _, _, cap, _ = self.matrices(open_)
        B = np.zeros((3, 3))
        B[1, 2] = (self.load - h.spring_preload) / M[0]
        B[2, 2] = (h.leak_conductance * h.supply_pressure
                   + (h.refill_conductance * h.check_threshold if open_ else 0.0)) / cap[0]
        return B

    def phase_modes(self, key):
        M, K, C, H, cap, G = self.matrices(key)
        lam, phys, inv = decompose(M, K, C, H, cap, G)
        B = self.forcing(key)
        return PhaseModes(key, lam, phys, inv, inv @ B, state_matrix(M, K, C, H, cap, G), B, 1)

    def event_functions(self, key):
        e_w = np.array([0.0, 0.0, 1.0])
        if key:
            return [Event("check-valve-close", e_w, 0.0, 0.0, -self.hla.check_threshold, +1.0)]
        return [Event("check-valve-open", e_w, 0.0, 0.0, -self.hla.check_threshold, -1.0)]

    def apply_event(self, key, event, y, S, S1):
        return Transition({"kind": event.kind}, event.kind == "check-valve-open", y)

    def start_state(self, drive, t0: float):
        """The plunger at p = 0 at rest, the chamber at the supply pressure, the load just put on."""
        return np.array([0.0, 0.0, self.hla.supply_pressure]), False

    def outputs(self, t, y, keys, codes, events, stats, matrices, D):
        from types import SimpleNamespace

        open_ = np.array([bool(k) for k in keys], dtype=bool)[np.asarray(codes)]
        return SimpleNamespace(t=t, plunger=y[0], plunger_velocity=y[1], chamber_pressure=y[2], check_open=open_,
                               events=tuple(events), stats=stats)
