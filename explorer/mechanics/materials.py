"""Material tables of the design rules, each row with its source and how firm it is.

Contact (Hertz) allowables: there is no single table for cams (design-rules notes: ISO 6336-5's
sigma_Hlim for the heat treatment, or the Tribology Handbook's hardness curve). The rows here are
the seeds' own allowables (seed 004, in kgf/cm^2, the unit it gives them in) and AGMA's contact
strengths of gear steels as machine-design texts quote them; a design names its pair with the
hertz_stress rule's `material` setting or gives its own figure as the rule's `fail` limit.

Spring wires: the minimum tensile strength of commercial wire S_ut = A / d^m (d in mm, S_ut in
MPa), the classic two-constant fit of the machine-design texts; the static allowable shear stress
as a share of S_ut from a spring maker's data sheet. The five rows are the older table's metric
column (music wire 2060 MPa mm^m, m 0.163 ...; the FE exam's table), as printed at
ncalculators.com (all five, with the kpsi in^m column beside them) and used in engineeringprep.com's
worked problems (music wire 7.25 mm: 1492 MPa; oil-tempered 10 mm: 1032 MPa). That metric column
is not its own kpsi column converted (A_SI = 6.895 (25.4)^m A_kpsi, Shigley's solutions manual,
prob. 10-2): it is 3 % (chrome-silicon) to 17 % (hard-drawn) lower, and
for hard-drawn A227 at 0.106 in it gives 180 ksi where ASTM A227 class I's minimum is 216 ksi
(interwiregroup.com's copy of the standard's table; the kpsi column gives 215). The rules using
it therefore err on the safe side by that much; the current Shigley (8th-11th eds., Table 10-4)
has new fits (music wire 2211 MPa mm^m, m 0.145; oil-tempered 1855, 0.187: both confirmed in
its solutions manuals), not taken here because its other three rows could not be confirmed.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..core.units import AT

PSI = 6894.757293168361  # Pa per lbf/in^2


@dataclass(frozen=True)
class ContactMaterial:
    name: str
    allowable: float  # Pa, peak Hertz pressure
    source: str
    firmness: str


CONTACT_MATERIALS: dict[str, ContactMaterial] = {m.name: m for m in (
    ContactMaterial("large-gas", 3500.0 * AT, "seed 004 ('Oel- und Gasmaschinen', p. 404): 3500 kgf/cm^2 for large "
                    "gas engines", "historical: a cast-iron era allowable, far below modern hardened steel"),
    ContactMaterial("diesel", 4000.0 * AT, "seed 004 ('Oel- und Gasmaschinen', p. 404): about 4000 kgf/cm^2 for "
                    "Diesel engines", "historical, as above"),
    ContactMaterial("through-hardened-300HB", 866e6, "AGMA 2001 via Shigley, Mechanical Engineering Design, "
                    "Fig. 14-5, grade 1: S_c = 2.22 H_B + 200 MPa at 300 HB, 10^7 cycles, 99 % reliability (its "
                    "US form 322 H_B + 29 100 psi = 125 700 psi = 866.7 MPa is printed in the book's continuation "
                    "of Ex. 14-6, holooly.com)", "gear practice, quoted without its life and reliability factors"),
    ContactMaterial("carburized-grade-1", 180e3 * PSI, "AGMA 2001 (ANSI/AGMA 2001-D04 Table 3) via Shigley "
                    "Table 14-6: carburized and hardened, grade 1, S_c = 180 000 psi (engineersedge.com's copy of "
                    "the AGMA table)", "gear practice, 10^7 cycles, 99 % reliability"),
    ContactMaterial("carburized-grade-2", 225e3 * PSI, "AGMA 2001 (ANSI/AGMA 2001-D04 Table 3) via Shigley "
                    "Table 14-6: carburized and hardened, grade 2, S_c = 225 000 psi (engineersedge.com's copy of "
                    "the AGMA table)", "gear practice, 10^7 cycles, 99 % reliability"),
)}


@dataclass(frozen=True)
class SpringWire:
    name: str
    astm: str
    a_mpa: float  # MPa mm^m
    m: float
    allowable_share: float  # static allowable shear stress / S_ut
    source: str = ("S_ut = A/d^m: the older machine-design table's metric column (as printed at ncalculators.com, "
                   "spring material tensile calculator, and in engineeringprep.com's worked problems): 3-17 % "
                   "below its own kpsi column and ASTM A227's minimum, on the safe side (module docstring); "
                   "allowable 45 % of S_ut in torsion: Katy Spring & Mfg., common spring materials data sheet")

    def ultimate_tensile_strength(self, wire_diameter: float) -> float:
        """S_ut (Pa) of a wire of diameter d (m)."""
        return self.a_mpa * 1e6 / (wire_diameter * 1e3) ** self.m


SPRING_WIRES: dict[str, SpringWire] = {w.name: w for w in (
    SpringWire("music-wire", "A228", 2060.0, 0.163, 0.45),
    SpringWire("oil-tempered", "A229", 1610.0, 0.193, 0.45),
    SpringWire("hard-drawn", "A227", 1510.0, 0.201, 0.45),
    SpringWire("chrome-vanadium", "A232", 1790.0, 0.155, 0.45),
    SpringWire("chrome-silicon", "A401", 1960.0, 0.091, 0.45),
)}
