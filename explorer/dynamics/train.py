"""The valve train as lumped masses (issue #25): the chain from the cam to the valve -- lifter,
pushrod, rocker or finger -- as masses joined by springs and dampers, contacts that can open,
the valve on its seat with its spring (massless, or a chain of masses: chain.py), and
optionally a hydraulic lash adjuster under the lever (hla.py).

Everything is referred to the valve (the scene does the referring: a mass m moving r times
slower than the valve counts m / r^2, a stiffness measured along a part's own motion k / r^2, a
rocker's inertia J about its pivot J / a^2 with a its arm to the valve). Degrees of freedom
    x = [s, u_1 .. u_N, q_1 .. q_L, p]
the valve's lift, the spring's coil masses (chain.py), the parts from the cam side (q_1: the
follower) to the valve side (q_L), and the adjuster's plunger travel p (into its body, its own
coordinate). Joint j (j = 0 .. L) joins the cam (j = 0) or part j to part j + 1 (the valve for
j = L); its compression is
    delta_j = alpha_j S + a_j . x - lash_j,     force f_j = k_j delta_j + c_j delta_j'
with alpha_0 = 1 (the cam's drive S, referred to the valve), a_j = e_(cam side) - e_(valve side),
and at the cam joint, under an adjuster, -g on p (g = hla.lever: the valve's travel per unit
plunger travel with the cam still; r - 1 for an end-pivot finger of ratio r). A one-sided joint
carries load only while closed (f > 0: it separates where f falls to 0, closes again where
delta rises through 0, as the linkage of model.py, or -- damped, in a train with parts -- where
the force it would carry turns positive while delta is still > 0: a part pushed back within the
remainder a damped separation leaves); a bonded one always. The seat is one-sided
at the valve (chain.py's elastic seat, the same rules: released where its force falls to 0,
closed again where s falls through 0 or, still below it, where its force turns positive:
chain_exact.seat_events), the spring acts on the valve, Coulomb friction on the
valve as in chain.py. The adjuster's chamber pressure P is a first-order state (hla.py):
    m_p p'' = (g f_0) - A P - F_0 - k_s p,      (V / beta_e) P' = A p' - G_l (P - P_s) [+ G_r (P_s - P_c - P)]
the bracket while its check valve is open.

Phase types: which one-sided joints are closed, the seat engaged or not, the valve moving up or
down or held by friction, the check valve shut or open. Each is linear with constant
coefficients, so chain_exact's solver runs it exactly (phase_system.py's contract), and
chain_reference's scipy run takes the same model. Events: separation and re-contact of each
one-sided joint (with its name), lift-off and seat, the valve's stops with friction, coil
clashes, and the check valve's opening and closing (P crossing P_s - P_c down or up).

A train without parts and adjuster is the spring-chain model itself: the same matrices, event
functions and outputs, computed the same way (bit for bit: tests), and solved with the chain's
own policies (its structured decomposition and half-mode stepping beyond 24 coil elements).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np

from .chain import ChainModel
from .chain_exact import STRUCTURED_FROM, seat_closes, seat_events, valve_derivatives
from .chain_kernels import NOISE
from .chain_modes import chain_phase_modes
from .hla import HLA
from .phase_system import Event, PhaseModes, Transition, decompose_free, held_modes, state_matrix

@dataclass(frozen=True)
class Part:
    """A lumped mass between the cam and the valve, referred to the valve."""

    name: str
    mass: float  # kg


@dataclass(frozen=True)
class Joint:
    """A spring and a damper in parallel between two neighbours of the chain, referred to the valve."""

    name: str
    stiffness: float  # N/m
    damping: float = 0.0  # N*s/m
    lash: float = 0.0  # m: the gap before it takes load (one-sided joints)
    one_sided: bool = True


@dataclass(frozen=True)
class TrainSolution:
    """The train's motion at the output times (referred to the valve, SI)."""

    t: np.ndarray
    s: np.ndarray  # valve lift
    v: np.ndarray
    a: np.ndarray
    jerk: np.ndarray
    linkage_force: np.ndarray  # the cam joint's force (>= 0), referred to the valve
    contact: np.ndarray  # bool: the cam joint closed
    phase: np.ndarray  # PHASE_CODES: seated 0, cam contact 1, flight 2, held by friction 3
    events: tuple
    stats: dict
    coils: np.ndarray  # (N, T)
    coil_velocities: np.ndarray
    retainer_force: np.ndarray  # the spring's force on the retainer
    seat_force: np.ndarray
    parts: np.ndarray  # (L, T): each part's displacement
    part_velocities: np.ndarray
    part_accelerations: np.ndarray
    joint_forces: dict = field(default_factory=dict)  # name -> (T,) N (one-sided: 0 while open)
    joint_closed: dict = field(default_factory=dict)  # name -> (T,) bool
    plunger: np.ndarray | None = None  # (T,) m, into the body (None without an adjuster)
    plunger_velocity: np.ndarray | None = None
    chamber_pressure: np.ndarray | None = None  # (T,) Pa, gauge
    check_open: np.ndarray | None = None  # (T,) bool


@dataclass(frozen=True)
class TrainModel:
    """The valve and its spring (chain: its valve, spring, seat, loads and friction; its linkage
    fields are not used -- joints[-1] is the joint at the valve), the parts from the cam side and
    the joints: joints[j] between (the cam if j == 0 else parts[j - 1]) and (parts[j], or the valve
    for the last), and the adjuster under the cam joint."""

    chain: ChainModel
    parts: tuple = ()  # Part, from the cam to the valve
    joints: tuple = ()  # Joint, len(parts) + 1
    hla: HLA | None = None

    def __post_init__(self):
        if len(self.joints) != len(self.parts) + 1:
            raise ValueError(f"a train of {len(self.parts)} parts has {len(self.parts) + 1} joints, "
                             f"got {len(self.joints)}")
        if not self.joints[0].one_sided:
            raise ValueError("the cam joint (the follower on the cam) is one-sided")
        if self.hla is not None and not self.parts:
            raise ValueError("the lash adjuster sits under a lever: the train needs a part (the finger or rocker)")

    @staticmethod
    def from_scene(scene) -> "TrainModel":
        """The scene's train: its [[linkage.elements]] (each part's mass and its cam-side joint
        referred to the valve: mass / ratio^2 or inertia / arm^2, stiffness and damping / ratio^2,
        lash * ratio), [linkage] as the joint at the valve (valve.lash its gap), the valve, spring,
        seat and loads as the spring-chain model takes them, and [hla] under the first part."""
        chain = ChainModel.from_scene(scene)
        link = scene.linkage
        parts, joints = [], []
        for i, e in enumerate(link.elements):
            r2 = e.ratio * e.ratio
            parts.append(Part(e.name, e.referred_mass))
            joints.append(Joint("cam" if i == 0 else e.name, e.stiffness / r2, e.damping / r2, e.lash * e.ratio,
                                e.one_sided))
        joints.append(Joint("valve" if link.elements else "cam", link.stiffness, link.damping, scene.valve.lash,
                            link.one_sided))
        section = getattr(scene, "hla", None)
        return TrainModel(chain, tuple(parts), tuple(joints), section.hla if section is not None else None)

    # -- layout ------------------------------------------------------------------------------------
    @property
    def bare(self) -> bool:
        """Without parts and adjuster: the spring-chain model."""
        return not self.parts and self.hla is None

    @property
    def n(self) -> int:
        return self.chain.n + len(self.parts) + (1 if self.hla is not None else 0)

    @property
    def r(self) -> int:
        return 1 if self.hla is not None else 0

    @property
    def size(self) -> int:
        return 2 * self.n + self.r

    @property
    def velocity_index(self) -> int:
        return self.n

    @property
    def plunger_index(self) -> int:
        return self.chain.n + len(self.parts)

    @property
    def reduce_pairs(self) -> bool:
        return self.chain.elements >= STRUCTURED_FROM if self.bare else True

    @cached_property
    def masses(self) -> np.ndarray:
        extra = [p.mass for p in self.parts] + ([self.hla.plunger_mass] if self.hla is not None else [])
        return np.concatenate([self.chain.masses, np.array(extra, dtype=float)])

    @cached_property
    def all_joints(self) -> tuple:
        """The chain's joints, then the plunger's stop (a one-sided joint between the adjuster's
        body and its plunger, closing where the plunger has travelled hla.travel out of its rest
        on the base circle)."""
        if self.hla is None or self.hla.travel is None:
            return tuple(self.joints)
        rest = replace(self, hla=replace(self.hla, travel=None))
        y, _ = rest.static_state(0.0)
        p_rest = float(y[self.plunger_index])
        return tuple(self.joints) + (Joint("plunger-stop", self.hla.stop_stiffness, self.hla.stop_damping,
                                           self.hla.travel - p_rest, True),)

    @cached_property
    def one_sided(self) -> tuple:
        """Indices of the one-sided joints (their open/closed state is part of the phase key)."""
        return tuple(j for j, jt in enumerate(self.all_joints) if jt.one_sided)

    def joint_terms(self, j: int) -> tuple:
        """(alpha, ((index, coefficient), ...)) of joint j's compression alpha S + a . x - lash,
        the terms in the order of their indices."""
        L, nc = len(self.parts), self.chain.n
        if j > L:  # the plunger's stop: compressed as the plunger goes out (p falls)
            return 0.0, ((self.plunger_index, -1.0),)
        terms = {}
        if j > 0:
            terms[nc + j - 1] = 1.0
        terms[nc + j if j < L else 0] = -1.0
        if j == 0 and self.hla is not None:
            terms[self.plunger_index] = -self.hla.lever
        return (1.0 if j == 0 else 0.0), tuple(sorted(terms.items()))

    def free_groups(self, key, held: bool = False) -> tuple:
        """The groups of parts (their DOF indices) that nothing holds in phase `key`: connected by
        closed joints only among themselves, not to the cam (a closed cam joint), the valve (its
        spring and seat; or held by friction), the coils or the plunger (its spring)."""
        nc = self.chain.n
        L = len(self.parts)
        parent = list(range(self.n + 1))  # the last: the ground
        ground = self.n

        def find(i):
            while parent[i] != i:
                parent[i] = parent[parent[i]]
                i = parent[i]
            return i

        def join(i, k):
            parent[find(i)] = find(k)

        for i in range(nc):
            join(i, ground)
        if self.hla is not None:
            join(self.plunger_index, ground)
        for j in self.closed_joints(key):
            alpha, terms = self.joint_terms(j)
            idx = [i for i, _ in terms]
            if alpha != 0.0:
                join(idx[0], ground)
            for i in idx[1:]:
                join(idx[0], i)
        groups: dict = {}
        for i in range(nc, nc + L):
            if find(i) != find(ground):
                groups.setdefault(find(i), []).append(i)
        return tuple(tuple(g) for g in groups.values())

    def closed_joints(self, key) -> tuple:
        """The joints that carry load in phase `key`: the closed one-sided ones and the bonded ones."""
        contacts = key[0]
        closed = dict(zip(self.one_sided, contacts))
        return tuple(j for j in range(len(self.all_joints)) if closed.get(j, True))

    # -- a phase's matrices -----------------------------------------------------------------------
    def phase_matrices(self, key):
        """(K, C, H, cap, G) of phase `key` = (contacts, seat, mode, check)."""
        contacts, seat, mode, check = key
        n, nc = self.n, self.chain.n
        c = self.chain
        K = np.zeros((n, n))
        C = np.zeros((n, n))
        K[:nc, :nc] = c.spring_stiffness_matrix
        C[:nc, :nc] = c.spring_damping_matrix
        for j in self.closed_joints(key):
            jt = self.all_joints[j]
            _, terms = self.joint_terms(j)
            for i, ai in terms:
                for k, ak in terms:
                    K[i, k] += jt.stiffness * ai * ak
                    C[i, k] += jt.damping * ai * ak
        if seat:
            K[0, 0] += c.seat_stiffness
            C[0, 0] += c.seat_damping
        if self.hla is None:
            return K, C, None, None, None
        h = self.hla
        ip = self.plunger_index
        K[ip, ip] += h.spring_rate
        H = np.zeros((n, 1))
        H[ip, 0] = h.area
        G = np.array([[h.leak_conductance + (h.refill_conductance if check else 0.0)]])
        return K, C, H, np.array([h.capacitance]), G

    def forcing(self, key, sigma: float):
        """(F (n, 3), F_w (r, 3)): the forces on the masses and the first-order states' sources per
        unit S, S', 1; the valve moving in the direction sigma (its friction -sigma R)."""
        contacts, seat, mode, check = key
        c = self.chain
        F = np.zeros((self.n, 3))
        F[0, 2] = -c.preload - c.closing_load - sigma * c.friction
        for j in self.closed_joints(key):
            jt = self.all_joints[j]
            alpha, terms = self.joint_terms(j)
            for i, ai in terms:
                F[i, 0] -= jt.stiffness * alpha * ai
                F[i, 1] -= jt.damping * alpha * ai
                F[i, 2] += jt.stiffness * jt.lash * ai
        if self.hla is None:
            return F, np.zeros((0, 3))
        h = self.hla
        F[self.plunger_index, 2] -= h.spring_preload
        Fw = np.zeros((1, 3))
        Fw[0, 2] = h.leak_conductance * h.supply_pressure + (h.refill_conductance * h.check_threshold if check else 0.0)
        return F, Fw

    def phase_modes(self, key) -> PhaseModes:
        contacts, seat, mode, check = key
        n = self.n
        M = self.masses
        K, C, H, cap, G = self.phase_matrices(key)
        F, Fw = self.forcing(key, float(mode))
        B = np.zeros((self.size, 3))
        B[n:2 * n] = F / M[:, None]
        if self.r:
            B[2 * n:] = Fw / cap[:, None]
        groups = self.free_groups(key)
        if mode == 0:
            return held_modes(key, M, K, C, B, 0, H, cap, G, groups)
        A = state_matrix(M, K, C, H, cap, G)
        structured = None
        if self.bare and self.reduce_pairs:
            structured = chain_phase_modes(self.chain, bool(contacts[0]), seat)
        if structured is not None:
            lam, phys, inv = structured
            rigid = ()
        else:
            lam, phys, inv, rigid = decompose_free(M, K, C, H, cap, G, groups)
        mB = inv @ B
        for a, b in rigid:  # nothing acts on a free group as a whole (its X' = V: the solver's)
            mB[a] = mB[b] = 0.0
        return PhaseModes(key, lam, phys, inv, mB, A, B, mode, rigid)

    # -- events -----------------------------------------------------------------------------------
    def _e(self, i: int) -> np.ndarray:
        e = np.zeros(self.size)
        e[i] = 1.0
        return e

    def joint_rows(self, j: int):
        """(gap row, force row) of joint j over y, each (coef, alpha, beta, const)."""
        jt = self.all_joints[j]
        alpha, terms = self.joint_terms(j)
        n = self.n
        gap = np.zeros(self.size)
        force = np.zeros(self.size)
        for i, ai in terms:
            gap[i] = ai
            force[i] = jt.stiffness * ai
            force[n + i] = jt.damping * ai
        return ((gap, alpha, 0.0, -jt.lash),
                (force, jt.stiffness * alpha, jt.damping * alpha, -jt.stiffness * jt.lash))

    def net_force_row(self, key):
        """The force on the valve other than friction, linear in y and the drive: (coef, alpha,
        beta, const) (chain.net_force_row's, for the whole train)."""
        n = self.n
        K, C, H, _, _ = self.phase_matrices(key)
        F, _ = self.forcing(key, 0.0)
        coef = np.zeros(self.size)
        coef[:n] = -K[0]
        coef[n:2 * n] = -C[0]
        if H is not None:
            coef[2 * n:] = -H[0]
        return coef, F[0, 0], F[0, 1], F[0, 2]

    def event_functions(self, key) -> list[Event]:
        contacts, seat, mode, check = key
        c = self.chain
        n = self.n
        ev = []
        for j, closed in zip(self.one_sided, contacts):
            gap, force = self.joint_rows(j)
            if closed:  # its force falls to 0
                ev.append(Event("separation", *force, -1.0, index=j))
            else:  # its gap closes
                ev.append(Event("re-contact", *gap, +1.0, index=j, guard=True))
                if not self.bare and self.all_joints[j].damping > 0.0:  # (undamped: no remainder)
                    # or, still compressed after a damped separation (the damper had cancelled the
                    # spring: the gap > 0), the force it would carry turns positive again: a part
                    # pushed back by a neighbour or the adjuster turns round within that remainder.
                    # (A bare train keeps the spring-chain model's convention, bit for bit: there
                    # the valve leaves faster than the remainder closes.)
                    ev.append(Event("re-contact-force", *force, +1.0, index=j))
        e_s, e_v = self._e(0), self._e(n)
        if mode == 0:
            coef, alpha, beta, const = self.net_force_row(key)
            ev.append(Event("release", coef, alpha, beta, const - c.friction, +1.0, index=+1))
            ev.append(Event("release", coef, alpha, beta, const + c.friction, -1.0, index=-1))
        else:
            ev.extend(seat_events(c, self.size, n, seat))
        if mode != 0 and c.friction > 0.0:
            ev.append(Event("velocity-zero", -mode * e_v, 0.0, 0.0, 0.0, +1.0))
        if self.hla is not None:
            e_w = self._e(2 * n)
            if check:  # open: shuts where the refill flow would reverse
                ev.append(Event("check-valve-close", e_w, 0.0, 0.0, -self.hla.check_threshold, +1.0))
            else:  # shut: opens where the chamber falls below the supply less the cracking pressure
                ev.append(Event("check-valve-open", e_w, 0.0, 0.0, -self.hla.check_threshold, -1.0))
        if math.isfinite(c.clash_compression):
            for j in range(c.n):
                coef = np.zeros(self.size)
                coef[j] = 1.0
                if j + 1 < c.n:
                    coef[j + 1] = -1.0
                ev.append(Event("coil-clash", coef, 0.0, 0.0, -c.clash_compression, +1.0, index=j, grouped=True))
        return ev

    def apply_event(self, key, e: Event, y: np.ndarray, S: float, S1: float) -> Transition:
        contacts, seat, mode, check = key
        kind = e.kind
        n = self.n
        if kind == "seat-force":
            if not seat_closes(y):
                return Transition(None, key, y)
            kind = "seat"
        item: dict = {"kind": kind}
        if kind == "re-contact-force":
            gap, _ = self.joint_rows(e.index)
            coef, alpha, _, const = gap
            value = float(coef @ y) + alpha * S + const
            size = float(np.abs(coef) @ np.abs(y)) + abs(alpha * S) + abs(const)
            if value < -NOISE * size:  # the gap is open (beyond a rounding): a damper's pull, no contact
                return Transition(None, key, y)
            kind = item["kind"] = "re-contact"
        if kind in ("separation", "re-contact"):
            contacts = tuple((kind == "re-contact") if j == e.index else closed
                             for j, closed in zip(self.one_sided, contacts))
            item["contact"] = self.all_joints[e.index].name
        elif kind == "velocity-zero":
            coef, alpha, beta, const = self.net_force_row(key)
            yy = y.copy()
            yy[n] = 0.0
            net = float(coef @ yy) + alpha * S + beta * S1 + const
            if abs(net) <= self.chain.friction:
                kind, mode = "stick", 0
            else:
                kind, mode = "turn", (1 if net > 0.0 else -1)
            item["kind"] = kind
            y[n] = 0.0
        elif kind == "release":
            mode = e.index
        elif kind == "lift-off":
            seat = False
            item["velocity_m_s"] = float(y[n])  # the speed the valve leaves its seat with
        elif kind == "seat":
            seat = True
            item["velocity_m_s"] = float(y[n])
        elif kind == "coil-clash":
            item["element"] = e.index
        elif kind == "check-valve-open":
            check = True
        elif kind == "check-valve-close":
            check = False
        disarm = ("velocity-zero",) if kind in ("release", "turn") else ()
        return Transition(item, (contacts, seat, mode, check), y, disarm)

    # -- start ------------------------------------------------------------------------------------
    def static_state(self, S: float, S1: float = 0.0):
        """(y, key): at rest in static equilibrium with the drive at S (S' = S1: the dampers'
        forces), the first consistent phase: a closed one-sided joint compressed with a positive
        force, an open one not (as chain.static_equilibrium); failing that, parts resting against a
        neighbour with no force between them (a train with lash on the base circle: nothing else
        places its loose parts), within rounding. The chamber at the supply pressure, its check
        valve shut (on its threshold when it has no cracking pressure)."""
        n = self.n
        mode = 0 if self.chain.friction > 0.0 else 1
        J = len(self.one_sided)
        orders = (sorted(itertools.product((False, True), repeat=J), key=sum),
                  sorted(itertools.product((False, True), repeat=J), key=lambda c: -sum(c)))
        for relaxed in (False, True):
            for seat, order in zip((True, False), orders):
                for contacts in order:
                    key = (tuple(contacts), seat, mode, False if self.hla is not None else None)
                    if self.free_groups(key):
                        continue  # a part free of its neighbours has no rest position
                    K, _, H, _, _ = self.phase_matrices(key)
                    F, _ = self.forcing(key, 0.0)
                    rhs = F[:, 0] * S + F[:, 1] * S1 + F[:, 2]
                    w = np.zeros(self.r)
                    if self.hla is not None:
                        w[0] = self.hla.supply_pressure
                        rhs = rhs - H[:, 0] * w[0]
                    x = np.linalg.solve(K, rhs)
                    ok = (seat == (x[0] < 0.0))
                    scale = 1e-9 * max(float(np.max(np.abs(x))), abs(S), 1e-6)
                    for j, closed in zip(self.one_sided, contacts):
                        jt = self.all_joints[j]
                        alpha, terms = self.joint_terms(j)
                        gap = alpha * S - jt.lash
                        for i, ai in terms:
                            gap += ai * x[i]
                        force = jt.stiffness * gap + jt.damping * alpha * S1
                        if not relaxed:
                            ok = ok and (closed == (gap >= 0.0 and force > 0.0))
                        elif closed:
                            ok = ok and gap >= -scale and force >= -jt.stiffness * scale
                        else:
                            ok = ok and (gap <= scale or force <= jt.stiffness * scale)
                    if ok:
                        return np.concatenate([x, np.zeros(n), w]), key
        raise ValueError("no static equilibrium of the valve train at rest")

    def start_state(self, drive, t0: float):
        D = np.asarray(drive(np.array([t0])), dtype=float)[:, 0]
        return self.static_state(float(D[0]), float(D[1]))

    # -- outputs ----------------------------------------------------------------------------------
    def joint_force(self, j: int, D: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Joint j's force k delta + c delta' over the samples (whether it is closed or not)."""
        jt = self.all_joints[j]
        alpha, terms = self.joint_terms(j)
        n = self.n
        gap = alpha * D[0] - jt.lash
        rate = alpha * D[1]
        for i, ai in terms:
            gap = gap + ai * y[i]
            rate = rate + ai * y[n + i]
        return jt.stiffness * gap + jt.damping * rate

    def outputs(self, t, y, keys, codes, events, stats, matrices, D) -> TrainSolution:
        n, nc, L = self.n, self.chain.n, len(self.parts)
        c = self.chain
        codes = np.asarray(codes)
        table = np.array([[k[1], k[2] == 0] for k in keys], dtype=bool).reshape(-1, 2)
        seat, held = table[codes, 0], table[codes, 1]
        closed_by_key = [set(self.closed_joints(k)) for k in keys]
        closed = {j: np.array([j in cl for cl in closed_by_key], dtype=bool)[codes]
                  for j in range(len(self.all_joints))}
        rows_only = self.reduce_pairs or not self.bare
        acc, jerk = valve_derivatives(y, codes, keys, matrices, D, n, rows_only)
        s, v = y[0], y[n]
        forces = {}
        for j, jt in enumerate(self.all_joints):
            f = self.joint_force(j, D, y)
            if jt.one_sided:
                f = np.maximum(np.where(closed[j], f, 0.0), 0.0)
            forces[jt.name] = f
        contact = closed[0]
        phase = np.where(seat, 0, np.where(held, 3, np.where(contact, 1, 2)))
        seat_force = np.where(seat, -c.seat_stiffness * s - c.seat_damping * v, 0.0)
        parts_acc = np.empty((L, y.shape[1]))
        for i in range(L):
            parts_acc[i] = valve_derivatives(y, codes, keys, matrices, D, n + nc + i, True)[0]
        out = dict(
            t=t, s=s, v=v, a=acc, jerk=jerk, linkage_force=forces[self.joints[0].name], contact=contact, phase=phase,
            events=tuple(events), stats=stats, coils=y[1:nc], coil_velocities=y[n + 1:n + nc],
            retainer_force=c.retainer_force(y[:nc], y[n:n + nc]), seat_force=seat_force,
            parts=y[nc:nc + L], part_velocities=y[n + nc:n + nc + L], part_accelerations=parts_acc,
            joint_forces=forces, joint_closed={jt.name: closed[j] for j, jt in enumerate(self.all_joints)},
        )
        if self.hla is not None:
            ip = self.plunger_index
            check = np.array([bool(k[3]) for k in keys], dtype=bool)[codes]
            out.update(plunger=y[ip], plunger_velocity=y[n + ip], chamber_pressure=y[2 * n], check_open=check)
        return TrainSolution(**out)

    # -- reported figures ---------------------------------------------------------------------------
    def natural_frequencies(self, key) -> np.ndarray:
        """The undamped natural frequencies (Hz) of phase `key`'s masses (the adjuster's chamber
        shut and leak-free: its oil column a spring A^2 / cap on the plunger), ascending."""
        K, _, H, cap, _ = self.phase_matrices(key)
        if H is not None:
            K = K + (H / cap[None, :]) @ H.T
        mh = 1.0 / np.sqrt(self.masses)
        w2 = np.linalg.eigvalsh(mh[:, None] * K * mh[None, :])
        return np.sqrt(np.maximum(w2, 0.0)) / (2.0 * math.pi)

    def running_key(self):
        """The phase of the train in normal running, whose modes natural_frequencies reports: the
        load path closed -- every joint from the cam to the valve (self.joints) carries the cam's
        force while the valve is open --, the valve off its seat and moving, the check valve shut
        (the oil column a spring: natural_frequencies). The plunger's retaining stop is not in the
        load path: the lever's load pushes the plunger into its body, away from the stop, which
        carries load only where the plunger has come out by hla.travel (the cam contact lost or the
        adjuster pumped up to its limit: transient, not normal running). So the stop is as it is at
        rest on the base circle (static_state): closed only if the plunger rests on it with a
        positive force there -- never with a positive hla.travel (the scene's rule), which puts
        the stop that far beyond the plunger's rest. Closing it anyway (1e8 N/m) made
        finger_hla_pumpup's modes 3116 / 15958 / 17987 Hz instead of 2528 / 9277 / 16863 Hz (with
        the oil's secant to 10 MPa, before the scene set its reference pressure)."""
        load_path = len(self.joints)
        extra = [j for j in self.one_sided if j >= load_path]
        at_rest = {}
        if extra:
            _, rest = self.static_state(0.0)
            at_rest = dict(zip(self.one_sided, rest[0]))
        contacts = tuple(bool(j < load_path or at_rest[j]) for j in self.one_sided)
        return (contacts, False, 1, False if self.hla is not None else None)
