"""`schenker1902` solver: W. Schenker's stepping scheme (Dingler 317, 1902, section 3), as printed.

With s1, v1, p1 known at t1 and h = t2 - t1, the paper predicts the lift from constant
acceleration, corrects it for an acceleration that changes linearly over the step, then takes
the trapezoidal velocity:
    s2' = s1 + v1 h + p1 h^2/2,           p2' = (k/M1)(S2 - S0 - s2')
    s2  = s1 + v1 h + h^2/2 [p1 + k/(3 M1) (S2 - S1 - v1 h - p1 h^2/2)]  = s2' + h^2/6 (p2' - p1)
    p2  = (k/M1)(S2 - S0 - s2),           v2 = v1 + (p1 + p2)/2 h
Here the acceleration is the model's (see model.py): any resistance W(s, v) = preload + rate*s +
friction*sign(v) + closing loads, lash, optional damping (its velocity taken from the predicted
accelerations), separation (p = -W/M while s > S - lash), re-contact and seat landing with
restitution. Events are found at step ends only, as in the paper's table of ordinates: that
limits the order after events and is part of the history this solver shows.

Stability. The printed scheme is the linear-acceleration method (Newmark gamma = 1/2,
beta = 1/6) with p2 in the s2 formula replaced by the explicit prediction p2'. For the free
oscillator (Omega = omega_n h) its amplification matrix has determinant 1 and trace
2 - Omega^2 + Omega^4/6, so it is stable for Omega < sqrt(6), i.e. h/Tn < sqrt(6)/(2 pi) = 0.390
-- a tighter bound than the sqrt(3)/pi = 0.551 of the implicit linear-acceleration method, which
is available as variant="newmark" (exact for this linear model: p2 solved for in closed form).
Beyond the limit the solver refuses (StabilityError) unless allow_unstable=True.
"""

from __future__ import annotations

import math

import numpy as np

from .solver_base import StabilityError
from .model import PHASE_CODES, DynamicsSolution, Drive, LinkageModel
from .phases import rebound_rest_speed, touching
from .reference import CONTACT, FLIGHT, REST, initial_phase

VARIANTS = ("printed", "newmark")
MASS_RULES = ("model", "paper")


def stability_limit(variant: str = "printed") -> float:
    """Largest stable h/Tn for the undamped oscillator: sqrt(6)/(2 pi) printed, sqrt(3)/pi Newmark."""
    if variant == "printed":
        return math.sqrt(6.0) / (2.0 * math.pi)
    if variant == "newmark":
        return math.sqrt(3.0) / math.pi
    raise ValueError(f"unknown variant {variant!r}; known: {', '.join(VARIANTS)}")


def amplification_matrix(omega_h: float, variant: str = "printed") -> np.ndarray:
    """One step of the scheme for s'' = -omega^2 s as a matrix on (s, h v): z2 = A z1."""
    u = omega_h * omega_h
    if variant == "printed":
        a = 1.0 - u / 2.0 + u * u / 12.0
        return np.array([[a, 1.0 - u / 6.0], [-u * (1.0 - u / 4.0 + u * u / 24.0), a]])
    if variant == "newmark":
        # (1 + u/6) s2 = s1 + h v1 - (u/3) s1;  h v2 = h v1 - (u/2)(s1 + s2)
        a11, a12 = (1.0 - u / 3.0) / (1.0 + u / 6.0), 1.0 / (1.0 + u / 6.0)
        return np.array([[a11, a12], [-u / 2.0 * (1.0 + a11), 1.0 - u / 2.0 * a12]])
    raise ValueError(f"unknown variant {variant!r}; known: {', '.join(VARIANTS)}")


def min_stable_steps(model: LinkageModel, omega: float, variant: str = "printed") -> int:
    """Fewest equal steps per camshaft revolution for which the scheme is stable."""
    return math.floor(2.0 * math.pi / omega / (stability_limit(variant) * model.natural_period())) + 1


def solve(
    model: LinkageModel,
    drive: Drive,
    t: np.ndarray,
    substeps: int = 1,
    variant: str = "printed",
    masses: str = "model",
    allow_unstable: bool = False,
    initial_state: tuple[float, float] | None = None,
    rest_height: float = 1e-12,
) -> DynamicsSolution:
    """Step the model over the output times t (one step per interval, or `substeps` per interval).

    variant: "printed" (the paper's formulas) or "newmark" (implicit linear acceleration).
    masses: "model" uses M1 in contact and M in flight, like the other solvers; "paper" follows
    the text literally: M1 only while the linkage force exceeds the resistance, M from the point
    where it has fallen to W (Schenker's C) until it exceeds W again after re-contact (his F).
    The valve starts at rest on its seat at t[0] unless initial_state = (s, v) is given.
    rest_height: a seat rebound that would rise less than this (m) ends the bouncing.
    """
    if variant not in VARIANTS:
        raise ValueError(f"unknown variant {variant!r}; known: {', '.join(VARIANTS)}")
    if masses not in MASS_RULES:
        raise ValueError(f"unknown mass rule {masses!r}; known: {', '.join(MASS_RULES)}")
    t = np.asarray(t, dtype=float)
    if t.size < 2 or np.any(np.diff(t) <= 0.0):
        raise ValueError("output times must be an increasing array of at least two times")
    substeps = int(substeps)
    if substeps < 1:
        raise ValueError("substeps must be >= 1")
    if substeps > 1:
        frac = np.arange(substeps) / substeps
        tt = np.append((t[:-1, None] + np.diff(t)[:, None] * frac[None, :]).ravel(), t[-1])
    else:
        tt = t
    h_max = float(np.max(np.diff(tt)))
    period = model.natural_period()
    ratio, limit = h_max / period, stability_limit(variant)
    warnings = []
    if ratio >= limit:
        message = (
            f"schenker1902 ({variant}) is unstable for a step over {limit:.4f} of the natural period "
            f"Tn = {period:.6g} s; this step is {ratio:.4f} Tn. Use at least "
            f"{min_stable_steps(model, drive.omega, variant)} equal steps per revolution."
        )
        if not allow_unstable:
            raise StabilityError(message)
        warnings.append(message)

    D = drive(tt)
    S_all, Sd_all = D[0].tolist(), D[1].tolist()
    # k at every node (a stiffness that changes along the cycle: the value at the step's end, where
    # the scheme evaluates the force)
    K_all = model.stiffness_at(tt).tolist() if model.stiffness_profile is not None else [model.stiffness] * len(tt)
    c, lash = model.damping, model.lash
    rate, mu = model.spring_rate, model.friction
    m1, m = model.oscillating_mass, model.mass
    w_const = model.preload + model.closing_load
    e = model.restitution
    rest_speed = rebound_rest_speed(model.seated_resistance, model.friction, model.mass, rest_height)
    seat_deceleration = (model.seated_resistance + model.friction) / model.mass
    newmark, paper = variant == "newmark", masses == "paper"

    def acc(phase: str, S: float, Sd: float, s: float, v: float, d: float, k: float) -> float:
        resistance = w_const + rate * s + mu * d
        if phase == FLIGHT:
            return -resistance / m
        force = k * (S - lash - s) + c * (Sd - v)
        return (force - resistance) / (m if paper and force <= resistance else m1)

    def push_on_held(S: float, Sd: float, s: float, k: float) -> float:
        x = S - lash - s
        return max(0.0, k * x + c * Sd) if x >= 0.0 else 0.0

    n_steps = len(tt)
    s_out, v_out, a_out, f_out = [0.0] * n_steps, [0.0] * n_steps, [0.0] * n_steps, [0.0] * n_steps
    contact_out = [False] * n_steps
    phase_out = [0] * n_steps
    events: list[dict] = []

    if initial_state is None:
        phase, s, v, d = REST, 0.0, 0.0, 0.0
    else:
        s, v = (float(x) for x in initial_state)
        phase, d = initial_phase(model, S_all[0], Sd_all[0], s, v, K_all[0])
    p = 0.0 if phase == REST else acc(phase, S_all[0], Sd_all[0], s, v, d, K_all[0])

    def record(i: int) -> None:
        S, Sd, k = S_all[i], Sd_all[i], K_all[i]
        if phase == CONTACT:
            force = max(0.0, k * (S - lash - s) + c * (Sd - v))
        elif phase == REST:
            force = push_on_held(S, Sd, s, k)
        else:
            force = 0.0
        s_out[i], v_out[i], a_out[i], f_out[i], contact_out[i] = s, v, p, force, force > 0.0
        phase_out[i] = PHASE_CODES[phase] if phase != REST else PHASE_CODES["seated" if s == 0.0 else "stuck"]

    record(0)
    for i in range(1, n_steps):
        t2, S2, Sd2, k = tt[i], S_all[i], Sd_all[i], K_all[i]
        if phase == REST:
            net = push_on_held(S2, Sd2, s, k) - (w_const + rate * s)
            if net > mu or (s > 0.0 and net < -mu):
                d = 1.0 if net > 0.0 else -1.0
                if s == 0.0:
                    events.append({"kind": "lift-off", "time_s": float(t2), "velocity_m_s": 0.0})
                phase = CONTACT if push_on_held(S2, Sd2, s, k) > 0.0 else FLIGHT
                v, p = 0.0, acc(phase, S2, Sd2, s, 0.0, d, k)
            record(i)
            continue

        h = t2 - tt[i - 1]
        if newmark:
            a_part = s + h * v + h * h / 3.0 * p
            b_part = v + 0.5 * h * p
            if phase == FLIGHT:
                p2 = -(w_const + rate * a_part + mu * d) / (m + rate * h * h / 6.0)
            else:
                mass = m1  # the paper rule judged at the step start, so p2 stays linear
                if paper and K_all[i - 1] * (S_all[i - 1] - lash - s) + c * (Sd_all[i - 1] - v) <= w_const + rate * s + mu * d:
                    mass = m
                rhs0 = k * (S2 - lash) + c * Sd2 - w_const - mu * d
                p2 = (rhs0 - (k + rate) * a_part - c * b_part) / (mass + (k + rate) * h * h / 6.0 + c * h / 2.0)
            s2 = a_part + h * h / 6.0 * p2
            v2 = b_part + 0.5 * h * p2
        else:
            s_pred = s + v * h + 0.5 * p * h * h
            p_pred = acc(phase, S2, Sd2, s_pred, v + p * h, d, k)
            s2 = s_pred + h * h / 6.0 * (p_pred - p)
            p2 = acc(phase, S2, Sd2, s2, v + 0.5 * h * (p + p_pred), d, k)
            v2 = v + 0.5 * h * (p + p2)

        # events, seen at the end of the step only
        if s2 < 0.0:
            events.append({"kind": "seat", "time_s": float(t2), "velocity_m_s": v2})
            s2, v2 = 0.0, -e * v2
            # a rebound that would land again within this step, or rise less than rest_height, ends the bouncing
            if v2 <= max(rest_speed, 0.5 * h * seat_deceleration):
                phase, s, v, p, d = REST, 0.0, 0.0, 0.0, 0.0
                record(i)
                continue
            d = 1.0
            phase = CONTACT if touching(S2, Sd2, k, c, lash, 0.0, v2) else FLIGHT
        elif phase == CONTACT and k * (S2 - lash - s2) + c * (Sd2 - v2) < 0.0:
            events.append({"kind": "separation", "time_s": float(t2), "velocity_m_s": v2})
            phase = FLIGHT
        elif phase == FLIGHT and S2 - lash - s2 > 0.0 and k * (S2 - lash - s2) + c * (Sd2 - v2) > 0.0:
            # with damping the linkage lets go while still compressed: contact resumes only where
            # it would push again, not where the (already positive) gap is
            events.append({"kind": "re-contact", "time_s": float(t2), "velocity_m_s": v2})
            phase = CONTACT
        if mu > 0.0 and v2 * d <= 0.0:  # velocity reversed in this step: friction flips or holds
            force = max(0.0, k * (S2 - lash - s2) + c * Sd2) if phase == CONTACT else 0.0
            net = force - (w_const + rate * s2)
            if abs(net) <= mu:
                phase, s, v, p, d = REST, s2, 0.0, 0.0, 0.0
                record(i)
                continue
            d = 1.0 if (v2 > 0.0 or (v2 == 0.0 and net > 0.0)) else -1.0
        s, v, p = s2, v2, acc(phase, S2, Sd2, s2, v2, d, k)
        record(i)

    keep = slice(None, None, substeps)
    stats = {
        "variant": variant, "masses": masses, "steps": n_steps - 1, "substeps": substeps,
        "step_over_period": ratio, "stability_limit": limit, "warnings": warnings,
    }
    return DynamicsSolution(
        t=t, s=np.array(s_out)[keep], v=np.array(v_out)[keep], a=np.array(a_out)[keep],
        linkage_force=np.array(f_out)[keep], contact=np.array(contact_out)[keep], events=tuple(events), stats=stats,
        phase=np.array(phase_out, dtype=np.int64)[keep],
    )
