"""The spring-chain model (chain.py) with scipy's solve_ivp: the reference for chain_exact.py.

The same phases and rules: in each phase y' = A y + B [S, S', 1] with the analytic drive (not
its step polynomials), integrated by solve_ivp (DOP853 by default) with the phase's event
functions; at an event the phase switches and the integration restarts there. The step is
bounded by a quarter of the fastest period of the phase, and the integration restarts at the
valve's apex in flight and at the gap's minimum while the linkage is unloaded (solve_ivp sees
crossings only between its steps: a hop shorter than a step would go unseen). With friction:
the valve's velocity reaching 0 (stick or turn by chain_exact.stick_or_turn) and the held
valve's release by its net force, the held phase's state matrix that of chain_exact."""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp

from .chain import ChainModel
from .chain_exact import chain_outputs, key_code, phase_modes, start_state, stick_or_turn


def solve(model: ChainModel, drive, t: np.ndarray, scipy_method: str = "DOP853", rtol: float = 1e-10,
          atol: float = 1e-13, max_step_fraction: float = 0.25, initial_state=None, max_events: int = 10_000):
    t = np.asarray(t, dtype=float)
    n = model.n
    x0, v0, key = initial_state if initial_state is not None else start_state(model, drive, float(t[0]))
    y = np.concatenate([x0, v0])
    cache: dict = {}

    def modes(k):
        if k not in cache:
            md = phase_modes(model, *k)
            cache[k] = (md.A, md.B, float(np.max(np.abs(md.lam))))
        return cache[k]

    out = np.empty((2 * n, t.size))
    keys: list = [None] * t.size
    events: list[dict] = []
    t_now = float(t[0])
    out[:, 0] = y
    keys[0] = key
    i_next = 1
    nfev = 0
    last_guard = None
    clashed: set[int] = set()
    while i_next < t.size:
        A, B, rho = modes(key)
        contact, seat, mode = key

        def rhs(tt, yy, A=A, B=B):
            D = drive(np.array([tt]))
            return A @ yy + B @ np.array([D[0, 0], D[1, 0], 1.0])

        funcs, kinds = [], []

        def add(kind, func, direction):
            func.terminal, func.direction = True, direction
            funcs.append(func)
            kinds.append(kind)

        if contact:
            add("separation", lambda tt, yy: _link_force(model, drive, tt, yy), -1.0)
        else:
            add("re-contact", lambda tt, yy: float(drive(np.array([tt]))[0, 0]) - model.lash - yy[0], 1.0)
        if mode == 0:  # held by friction: released when the net force leaves [-R, R]
            coef, alpha, beta, const = model.net_force_row(contact, seat)

            def net(tt, yy, coef=coef, alpha=alpha, beta=beta, const=const):
                D = drive(np.array([tt]))
                return float(coef @ yy) + alpha * float(D[0, 0]) + beta * float(D[1, 0]) + const

            add("release:1", lambda tt, yy: net(tt, yy) - model.friction, 1.0)
            add("release:-1", lambda tt, yy: net(tt, yy) + model.friction, -1.0)
        elif seat:
            add("lift-off", lambda tt, yy: yy[0], 1.0)
        else:
            add("seat", lambda tt, yy: yy[0], -1.0)
        if mode != 0 and model.friction > 0.0:
            add("velocity-zero", lambda tt, yy: yy[n], -float(mode))
        # guards: solve_ivp sees a crossing only between its steps, and a hop of the valve off its
        # seat (or a touch of the linkage) shorter than a step goes unseen. A restart at the
        # extremum in between (the valve's apex, the gap's minimum) splits such a pair
        # (not right after a guard's restart: it is 0 there and would fire again at once, and on
        # the base circle, S' = 0, both are 0 at the valve's apex)
        if not seat and mode != 0 and last_guard is None:
            add("guard-apex", lambda tt, yy: yy[n], -1.0)
        if not contact and last_guard is None:
            add("guard-gap", lambda tt, yy: float(drive(np.array([tt]))[1, 0]) - yy[n], 1.0)
        last_guard = None
        if math.isfinite(model.clash_compression):
            for j in range(n):
                # an element that has clashed waits until it comes back below the clash
                # compression (a restart there), as the exact solver disarms its function
                add(f"guard-unclash:{j}" if j in clashed else f"coil-clash:{j}",
                    (lambda tt, yy, j=j: yy[j] - (yy[j + 1] if j + 1 < n else 0.0) - model.clash_compression),
                    -1.0 if j in clashed else 1.0)
        t_eval = t[i_next:]
        sol = solve_ivp(rhs, (t_now, float(t[-1])), y, method=scipy_method, t_eval=t_eval, events=funcs,
                        rtol=rtol, atol=atol, max_step=max_step_fraction * 2.0 * math.pi / rho)
        nfev += sol.nfev
        m = int(np.size(sol.t))  # (scipy returns lists when a segment ends before any t_eval)
        if m:
            out[:, i_next:i_next + m] = np.asarray(sol.y).reshape(2 * n, m)
        keys[i_next:i_next + m] = [key] * m
        i_next += m
        if sol.status != 1:
            break
        hit = min((float(te[0]), k) for k, te in enumerate(sol.t_events) if te.size)
        t_ev, k = hit
        y = sol.y_events[k][0].copy()
        kind = kinds[k]
        if kind.startswith("guard"):
            if kind.startswith("guard-unclash"):
                clashed.discard(int(kind.split(":")[1]))
            t_now, last_guard = t_ev, kind
            continue
        if kind == "velocity-zero":
            D = drive(np.array([t_ev]))
            kind, mode = stick_or_turn(model, y, float(D[0, 0]), float(D[1, 0]), contact, seat)
            y[n] = 0.0
        elif kind.startswith("release"):
            mode = int(kind.split(":")[1])
        item = {"kind": kind.split(":")[0], "time_s": t_ev}
        if kind == "seat":
            item["velocity_m_s"] = float(y[n])
        if kind.startswith("coil-clash"):
            item["element"] = int(kind.split(":")[1])
            clashed.add(item["element"])
        events.append(item)
        if len(events) > max_events:
            raise RuntimeError(f"more than {max_events} events in one run")
        key = ({"separation": False, "re-contact": True}.get(kind, contact),
               {"lift-off": False, "seat": True}.get(kind, seat), mode)
        t_now = t_ev
    stats = {"rhs_evaluations": int(nfev), "events": len(events)}
    codes = np.array([key_code(k) for k in keys])
    return chain_outputs(model, drive, t, out, codes, events, stats, lambda k: modes(k)[:2])


def _link_force(model, drive, tt, yy) -> float:
    D = drive(np.array([tt]))
    n = model.n
    return model.stiffness * (float(D[0, 0]) - model.lash - yy[0]) + model.damping * (float(D[1, 0]) - yy[n])
