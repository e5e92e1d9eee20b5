"""The valve spring as a body (issue #15): the valve plus the spring cut into N masses.

The massless model (model.py) lumps the spring into a force and its mass into Schenker's M/M1
split. Here the spring of rate k and mass m_s is a chain of N + 1 equal elements of stiffness
k_e = (N + 1) k between the seat (fixed) and the retainer (on the valve); its mass is lumped
m_e = m_s / (N + 1) at the N coil nodes and half an element at each end (the seat's half is
held, the retainer's half moves with the valve). The half-end lumping makes the chain's
eigenfrequencies converge to the continuous spring's at second order in 1/N (tests).

Degrees of freedom x = [s, u_1, ..., u_N]: the valve lift and the coil displacements (in the
lift direction), u_1 next to the retainer, u_N next to the seat. Element j (0..N) is compressed
by x_j - x_{j+1} beyond its installed state (x_{N+1} = 0, the seat). Equations:
    M x'' + C x' + K x = f(t)
with K the chain's stiffness, plus the linkage's k_l on s while the linkage is loaded (contact:
force k_l (S - lash - s) + c_l (S' - s') > 0) and the seat's k_seat on s while it is engaged
(a Kelvin-Voigt seat, force -k_seat s - c_seat s' >= 0: engaged where the valve comes down
through s = 0, released where that force falls to 0 -- with damping a little below s = 0, as a
seat cannot pull -- and engaged again where it turns positive while the valve is still below
s = 0: chain_exact.seat_events). f holds preload and closing loads on the valve and the drive.
The spring's own damping: modal damping ratio zeta on the chain's modes relative to its
quasi-static shape (u_j = s (1 - j/(N+1))), so the quasi-static compression is not damped and
each mode of the chain with its ends held has exactly the ratio zeta.

Coulomb friction R on the valve (optional): moving, the valve feels -sign(v) R (a constant in
the forcing, so each direction is its own phase type); where v reaches 0 it sticks if the net
force on it (net_force_row) is within [-R, R], else turns; held, s stays fixed and v = 0 while
the coils go on moving, until the net force leaves the band (a phase type whose valve rows are
0). The coils' contact after a clash and a rigid (restitution) seat are not modelled.

Each combination (linkage loaded or not) x (seat engaged or not) x (valve moving up, down, or
held) is a linear phase with constant coefficients; chain_exact.py solves it with the
eigen-decomposition of the phase's state matrix (once per phase type and speed),
chain_reference.py with scipy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

# events of the chain model: those of the massless model and the spring reaching solid length
CHAIN_EVENT_KINDS = ("lift-off", "separation", "re-contact", "seat", "coil-clash")
# with friction the valve also stops: it sticks (held by friction at v = 0), turns (its velocity
# changes sign), or is released (its net force leaves the friction band)
FRICTION_EVENT_KINDS = ("stick", "turn", "release")


@dataclass(frozen=True)
class ChainModel:
    valve_mass: float  # kg: valve and retainer without the spring
    spring_mass: float  # kg: the active coils
    elements: int  # N coil masses
    spring_rate: float  # N/m
    preload: float  # N at the closed valve
    stiffness: float  # N/m, linkage, referred to the valve
    seat_stiffness: float  # N/m
    damping: float = 0.0  # N*s/m, linkage
    lash: float = 0.0  # m
    closing_load: float = 0.0  # N
    seat_damping: float = 0.0  # N*s/m
    damping_ratio: float = 0.0  # of the spring's own modes
    # compression of one element (beyond its installed state) at which its coils touch: inf when
    # the spring's lengths are not given
    clash_compression: float = math.inf
    friction: float = 0.0  # N, Coulomb, on the valve (its stem in the guide), opposes its motion

    @staticmethod
    def from_scene(scene) -> "ChainModel":
        sp, v = scene.spring, scene.valve
        clash = math.inf
        if sp.free_length is not None and sp.solid_height is not None:
            clash = solid_travel(sp) / (sp.elements + 1)
        return ChainModel(
            valve_mass=v.mass, spring_mass=sp.mass, elements=sp.elements, spring_rate=sp.rate,
            preload=sp.preload, stiffness=scene.linkage.stiffness, damping=scene.linkage.damping,
            lash=v.lash, closing_load=scene.loads.closing_total, seat_stiffness=scene.seat.stiffness,
            seat_damping=scene.seat.damping, damping_ratio=sp.damping_ratio, clash_compression=clash,
            friction=scene.loads.friction,
        )

    # -- the chain --------------------------------------------------------------------------
    @property
    def n(self) -> int:
        return self.elements + 1  # degrees of freedom

    @property
    def element_stiffness(self) -> float:
        return (self.elements + 1) * self.spring_rate

    @property
    def element_mass(self) -> float:
        return self.spring_mass / (self.elements + 1)

    @cached_property
    def masses(self) -> np.ndarray:
        m = np.full(self.n, self.element_mass)
        m[0] = self.valve_mass + 0.5 * self.element_mass
        return m

    @cached_property
    def spring_stiffness_matrix(self) -> np.ndarray:
        """K of the chain alone (valve node 0 joined to the seat through N + 1 elements)."""
        n, ke = self.n, self.element_stiffness
        K = np.zeros((n, n))
        idx = np.arange(n)
        K[idx, idx] = 2.0 * ke
        K[0, 0] = ke
        K[idx[:-1], idx[1:]] = K[idx[1:], idx[:-1]] = -ke
        return K

    @cached_property
    def coil_modes(self) -> tuple[np.ndarray, np.ndarray]:
        """(omega (N,), mass-normalised shapes (N, N)) of the coils with both ends held."""
        N = self.elements
        ke, me = self.element_stiffness, self.element_mass
        Kc = self.spring_stiffness_matrix[1:, 1:].copy()
        Kc[0, 0] = 2.0 * ke
        w2, Q = np.linalg.eigh(Kc / me)
        return np.sqrt(np.maximum(w2, 0.0)), Q / math.sqrt(me) if N else Q

    @cached_property
    def spring_damping_matrix(self) -> np.ndarray:
        """C = T' C_c T: modal damping zeta of the held-ends coil modes, acting on the coils'
        motion relative to the quasi-static shape, w = u - r s (r_j = 1 - j/(N+1))."""
        n, N = self.n, self.elements
        if self.damping_ratio == 0.0 or N == 0:
            return np.zeros((n, n))
        w, Phi = self.coil_modes
        me = self.element_mass
        Cc = (me * Phi) @ np.diag(2.0 * self.damping_ratio * w) @ (me * Phi).T
        T = np.zeros((N, n))
        T[:, 0] = -(1.0 - np.arange(1, N + 1) / (N + 1))
        T[:, 1:] = np.eye(N)
        return T.T @ Cc @ T

    def phase_matrices(self, contact: bool, seat: bool) -> tuple[np.ndarray, np.ndarray]:
        """(K, C) of a phase: the chain plus the linkage (contact) and the seat (seat)."""
        K = self.spring_stiffness_matrix.copy()
        C = self.spring_damping_matrix.copy()
        if contact:
            K[0, 0] += self.stiffness
            C[0, 0] += self.damping
        if seat:
            K[0, 0] += self.seat_stiffness
            C[0, 0] += self.seat_damping
        return K, C

    def forcing_vectors(self, contact: bool, sigma: float = 1.0) -> np.ndarray:
        """(n, 3): f = F[:, 0] S + F[:, 1] S' + F[:, 2] (forces on the degrees of freedom), the
        valve moving in the direction sigma (its friction -sigma R; without friction the same
        numbers for either sign)."""
        F = np.zeros((self.n, 3))
        F[0, 2] = -self.preload - self.closing_load - sigma * self.friction
        if contact:
            F[0, 0] = self.stiffness
            F[0, 1] = self.damping
            F[0, 2] -= self.stiffness * self.lash
        return F

    def net_force_row(self, contact: bool, seat: bool) -> tuple[np.ndarray, float, float, float]:
        """The force on the valve other than friction, linear in the state y = [x, x'] and the
        drive: (coef (2n,), alpha, beta, const) with force = coef . y + alpha S + beta S' + const:
        the linkage (contact), the seat (seat), the spring's end element, preload and loads.
        A valve at rest (v = 0) sticks while |force| <= friction."""
        n = self.n
        coef = np.concatenate([-self.spring_stiffness_matrix[0], -self.spring_damping_matrix[0]])
        alpha = beta = 0.0
        const = -self.preload - self.closing_load
        if contact:
            coef[0] -= self.stiffness
            coef[n] -= self.damping
            alpha, beta, const = self.stiffness, self.damping, const - self.stiffness * self.lash
        if seat:
            coef[0] -= self.seat_stiffness
            coef[n] -= self.seat_damping
        return coef, alpha, beta, const

    # -- what is reported ---------------------------------------------------------------------
    def spring_modal_frequencies(self) -> np.ndarray:
        """The spring's own frequencies (Hz), ends held: the chain's, closed form."""
        return chain_frequencies(self.elements, self.spring_rate, self.spring_mass) / (2.0 * math.pi)

    def retainer_force(self, x: np.ndarray, xd: np.ndarray) -> np.ndarray:
        """Force of the spring on the retainer (N, compressive), x and xd (n, T)."""
        K, C = self.spring_stiffness_matrix, self.spring_damping_matrix
        return self.preload + K[0] @ x + C[0] @ xd

    def static_retainer_force(self, s: np.ndarray) -> np.ndarray:
        return self.preload + self.spring_rate * np.asarray(s)



def chain_frequencies(N: int, k: float, m_s: float) -> np.ndarray:
    """omega_j (rad/s, j = 1..N) of N masses m_s/(N+1) between held ends through N + 1 springs
    (N + 1) k: 2 sqrt(k_e/m_e) sin(j pi / (2 (N + 1)))."""
    j = np.arange(1, N + 1)
    return 2.0 * (N + 1) * math.sqrt(k / m_s) * np.sin(j * math.pi / (2.0 * (N + 1)))


def continuous_frequencies(count: int, k: float, m_s: float) -> np.ndarray:
    """The continuous spring's f_j = (j / 2) sqrt(k / m_s) (Hz), ends held."""
    return 0.5 * np.arange(1, count + 1) * math.sqrt(k / m_s)


def solid_travel(spring) -> float:
    """Valve lift at which the spring's static length reaches its solid height (m)."""
    return spring.free_length - spring.preload / spring.rate - spring.solid_height


def static_equilibrium(model: ChainModel, S: float, S1: float = 0.0) -> tuple[np.ndarray, bool, bool]:
    """(x, contact, seat) of the valve at rest with the drive at S (S' = S1 ignored by the
    displacement; the damper's c S' is a force): the first consistent phase."""
    for contact, seat in ((False, True), (True, True), (True, False), (False, False)):
        K, _ = model.phase_matrices(contact, seat)
        F = model.forcing_vectors(contact, 0.0)  # at rest: no friction force
        x = np.linalg.solve(K, F[:, 0] * S + F[:, 1] * S1 + F[:, 2])
        s = x[0]
        gap = S - model.lash - s
        force = model.stiffness * gap + model.damping * S1
        if (seat == (s < 0.0)) and (contact == (gap >= 0.0 and force > 0.0)):
            return x, contact, seat
    raise ValueError("no static equilibrium of the valve on its seat")
