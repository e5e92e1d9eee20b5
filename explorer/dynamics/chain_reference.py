"""The models of the piecewise-exact solver (chain_exact.py) with scipy's solve_ivp: its reference.

Any PhaseSystem (phase_system.py: the spring chain, the valve train) runs here with the same
phase types, event functions and transitions: in each phase y' = A y + B [S, S', 1] with the
analytic drive (not its step polynomials), integrated by solve_ivp (DOP853 by default) with the
phase's event functions; at an event the model's apply_event decides the next phase and the
integration restarts there. The step is bounded by a quarter of the fastest period of the phase
(its oscillating modes; a real eigenvalue's decay is left to the error control).

solve_ivp sees a crossing only between its steps. Two guards keep a short excursion from going
unseen: (1) a function the model marks `guard` (a seat, a contact's re-contact) gets a restart at
its turning point towards its crossing (g' = 0 crossing in the event's direction: the valve's
apex in flight, the gap's minimum while a contact is open), so a hop shorter than a step is split;
not right after a guard's own restart (it is 0 there and would fire again at once); (2) a function
that has just fired without changing the phase (a coil clash) waits for its return to the near side
(a restart there), as the exact solver disarms it; so does a function that starts a phase within
rounding of its zero (chain_kernels.NOISE of the size of its terms) and not moving to its near
side (the check valve on its threshold at rest): the exact solver's arming rule."""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp

from .chain import ChainModel
from .chain_exact import as_system
from .chain_kernels import NOISE


def solve(model, drive, t: np.ndarray, scipy_method: str = "DOP853", rtol: float = 1e-10,
          atol: float = 1e-13, max_step_fraction: float = 0.25, initial_state=None, max_events: int = 10_000):
    """The model (a ChainModel or a PhaseSystem) over the times t; initial_state as chain_exact.solve."""
    t = np.asarray(t, dtype=float)
    system = as_system(model)
    N = system.size
    if initial_state is None:
        y, key = system.start_state(drive, float(t[0]))
    elif isinstance(model, ChainModel):
        x0, v0, key = initial_state
        y = np.concatenate([np.asarray(x0, float), np.asarray(v0, float)])
    else:
        y, key = initial_state
        y = np.asarray(y, float).copy()
    cache: dict = {}

    def modes(k):
        if k not in cache:
            md = system.phase_modes(k)
            # the step bound: a quarter of the fastest period; a real eigenvalue (a leak's, a
            # refill's decay) has no period, and DOP853's error control follows its decay itself
            osc = np.abs(md.lam[np.abs(md.lam.imag) > 1e-6 * np.abs(md.lam)])
            cache[k] = (md.A, md.B, float(np.max(osc)) if osc.size else float(np.max(np.abs(md.lam))))
        return cache[k]

    out = np.empty((N, t.size))
    keys: list = [None] * t.size
    events: list[dict] = []
    t_now = float(t[0])
    out[:, 0] = y
    keys[0] = key
    i_next = 1
    nfev = 0
    last_guard = None
    # (kind, index) -> margin of the functions waiting for their return to the near side (a function
    # that fired without a phase change, or one that began its phase on its zero): the return is
    # where it is back by more than its rounding (margin), as the exact solver arms
    waiting: dict = {}
    fresh = True  # a phase begins (the run's start, or an event): its functions are armed by the rule below
    while i_next < t.size:
        A, B, rho = modes(key)
        functions = system.event_functions(key)

        def rhs(tt, yy, A=A, B=B):
            D = drive(np.array([tt]))
            return A @ yy + B @ np.array([D[0, 0], D[1, 0], 1.0])

        # a phase's function within rounding of its zero and not moving to its near side is not
        # armed (the exact solver's rule): it waits for its return, or it would fire on a rounding
        D0 = drive(np.array([t_now]))
        u0 = np.array([D0[0, 0], D0[1, 0], 1.0])
        yd0 = A @ y + B @ u0
        yd0_size = np.abs(A) @ np.abs(y) + np.abs(B) @ np.abs(u0)
        for e in functions:
            if not fresh and (e.kind, e.index) not in waiting:
                continue
            g0 = float(e.coef @ y) + e.alpha * float(D0[0, 0]) + e.beta * float(D0[1, 0]) + e.const
            g1 = float(e.coef @ yd0) + e.alpha * float(D0[1, 0]) + e.beta * float(D0[2, 0])
            size = (float(np.abs(e.coef) @ np.abs(y)) + abs(e.alpha * float(D0[0, 0])) + abs(e.beta * float(D0[1, 0]))
                    + abs(e.const))
            # (the slope's rounding: that of the terms making y', not y' itself, which is a rounding at rest)
            size1 = float(np.abs(e.coef) @ yd0_size) + abs(e.alpha * float(D0[1, 0])) + abs(e.beta * float(D0[2, 0]))
            if (e.kind, e.index) in waiting:
                waiting[(e.kind, e.index)] = NOISE * size
            elif abs(g0) <= NOISE * size and not e.sign * g1 < -NOISE * size1:
                # on its zero and not moving in by more than a rounding (parts at rest against
                # each other with no force between them)
                waiting[(e.kind, e.index)] = NOISE * size
        funcs, roles = [], []

        def add(role, func, direction):
            func.terminal, func.direction = True, direction
            funcs.append(func)
            roles.append(role)

        for e in functions:
            def g(tt, yy, e=e):
                D = drive(np.array([tt]))
                return float(e.coef @ yy) + e.alpha * float(D[0, 0]) + e.beta * float(D[1, 0]) + e.const

            if (e.kind, e.index) in waiting:
                margin = e.sign * waiting[(e.kind, e.index)]

                def back(tt, yy, g=g, margin=margin):
                    return g(tt, yy) + margin

                add(("return", e), back, -e.sign)
                continue
            add(("event", e), g, e.sign)
        # the guards after every event function: at a tie (the valve's apex is where its velocity
        # reaches 0) the event wins
        for e in functions:
            if e.guard and last_guard is None and (e.kind, e.index) not in waiting:
                def dg(tt, yy, e=e, A=A, B=B):
                    D = drive(np.array([tt]))
                    yd = A @ yy + B @ np.array([D[0, 0], D[1, 0], 1.0])
                    return float(e.coef @ yd) + e.alpha * float(D[1, 0]) + e.beta * float(D[2, 0])

                add(("guard", e), dg, e.sign)
        last_guard = None
        t_eval = t[i_next:]
        sol = solve_ivp(rhs, (t_now, float(t[-1])), y, method=scipy_method, t_eval=t_eval, events=funcs,
                        rtol=rtol, atol=atol, max_step=max_step_fraction * 2.0 * math.pi / rho)
        nfev += sol.nfev
        m = int(np.size(sol.t))  # (scipy returns lists when a segment ends before any t_eval)
        if m:
            out[:, i_next:i_next + m] = np.asarray(sol.y).reshape(N, m)
        keys[i_next:i_next + m] = [key] * m
        i_next += m
        if sol.status != 1:
            break
        t_ev, k = min((float(te[0]), k) for k, te in enumerate(sol.t_events) if te.size)
        y = sol.y_events[k][0].copy()
        role, e = roles[k]
        t_now = t_ev
        fresh = role == "event"
        if role == "guard":
            last_guard = e
            continue
        if role == "return":
            waiting.pop((e.kind, e.index), None)
            continue
        D = drive(np.array([t_ev]))
        tr = system.apply_event(key, e, y, float(D[0, 0]), float(D[1, 0]))
        if tr.record is not None:
            item = {"kind": tr.record["kind"], "time_s": t_ev}
            item.update((kk, v) for kk, v in tr.record.items() if kk != "kind")
            events.append(item)
            if len(events) > max_events:
                raise RuntimeError(f"more than {max_events} events in one run")
        if tr.key == key:
            waiting[(e.kind, e.index)] = 0.0  # (its margin is set at the segment's start)
        y = tr.y
        key = tr.key
    stats = {"rhs_evaluations": int(nfev), "events": len(events)}
    table: list = []
    index: dict = {}
    codes = np.empty(t.size, dtype=np.int16)
    for i, k in enumerate(keys):
        if k not in index:
            index[k] = len(table)
            table.append(k)
        codes[i] = index[k]
    D_out = np.asarray(drive(t), dtype=float)
    return system.outputs(t, out, table, codes, events, stats, lambda k: modes(k)[:2], D_out)
