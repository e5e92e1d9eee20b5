"""Material tables of the design rules, each row with its source and how firm it is.

Contact (Hertz) allowables: there is no single table for cams (design-rules notes: ISO 6336-5's
sigma_Hlim for the heat treatment, or the Tribology Handbook's hardness curve). The rows here are
the seeds' own allowables (seed 004, in kgf/cm^2, the unit it gives them in) and AGMA's contact
strengths of gear steels as machine-design texts quote them; a design names its pair with the
hertz_stress rule's `material` setting or gives its own figure as the rule's `fail` limit.

Spring wires: the minimum tensile strength of commercial wire S_ut = A / d^m (d in mm, S_ut in
MPa), the classic two-constant fit of the machine-design texts (Shigley & Mischke); the static
allowable shear stress as a share of S_ut from a spring maker's data sheet.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..core.units import AT


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
    ContactMaterial("through-hardened-300HB", 866e6, "AGMA 2001: S_c = 2.22 H_B + 200 MPa (grade 1) at 300 HB, "
                    "10^7 cycles, 99 % reliability (Shigley, Mechanical Engineering Design, gear chapter)",
                    "gear practice, quoted here without its life and reliability factors; not confirmed against "
                    "the book in this project"),
    ContactMaterial("carburized-grade-1", 1240e6, "AGMA 2001: carburized and hardened 58-64 HRC, grade 1, "
                    "S_c = 180 kpsi (Shigley, Mechanical Engineering Design, gear chapter)",
                    "gear practice; not confirmed against the book in this project"),
    ContactMaterial("carburized-grade-2", 1550e6, "AGMA 2001: carburized and hardened 58-64 HRC, grade 2, "
                    "S_c = 225 kpsi (Shigley, Mechanical Engineering Design, gear chapter)",
                    "gear practice; not confirmed against the book in this project"),
)}


@dataclass(frozen=True)
class SpringWire:
    name: str
    astm: str
    a_mpa: float  # MPa mm^m
    m: float
    allowable_share: float  # static allowable shear stress / S_ut
    source: str = ("S_ut = A/d^m: the machine-design texts' table (Shigley & Mischke), as reproduced at "
                   "ncalculators.com (spring material tensile calculator); allowable 45 % of S_ut in torsion: Katy "
                   "Spring & Mfg., common spring materials data sheet")

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
