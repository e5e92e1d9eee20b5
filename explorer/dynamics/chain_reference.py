"""The spring-chain model (chain.py) with scipy's solve_ivp: the reference for chain_exact.py.

The same phases and rules: in each phase y' = A y + B [S, S', 1] with the analytic drive (not
its step polynomials), integrated by solve_ivp (DOP853 by default) with the phase's event
functions; at an event the phase switches and the integration restarts there. The step is
bounded by a quarter of the fastest period of the phase (solve_ivp sees crossings only between
its steps)."""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp

from .chain import ChainModel
from .chain_exact import chain_outputs, phase_modes, start_state


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
    while i_next < t.size:
        A, B, rho = modes(key)
        contact, seat = key

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
        if seat:
            add("lift-off", lambda tt, yy: yy[0], 1.0)
        else:
            add("seat", lambda tt, yy: yy[0], -1.0)
        if math.isfinite(model.clash_compression):
            for j in range(n):
                add(f"coil-clash:{j}", (lambda tt, yy, j=j: yy[j] - (yy[j + 1] if j + 1 < n else 0.0)
                                        - model.clash_compression), 1.0)
        t_eval = t[i_next:]
        sol = solve_ivp(rhs, (t_now, float(t[-1])), y, method=scipy_method, t_eval=t_eval, events=funcs,
                        rtol=rtol, atol=atol, max_step=max_step_fraction * 2.0 * math.pi / rho)
        nfev += sol.nfev
        m = sol.t.size
        out[:, i_next:i_next + m] = sol.y
        keys[i_next:i_next + m] = [key] * m
        i_next += m
        if sol.status != 1:
            break
        hit = min((float(te[0]), k) for k, te in enumerate(sol.t_events) if te.size)
        t_ev, k = hit
        y = sol.y_events[k][0].copy()
        kind = kinds[k]
        item = {"kind": kind.split(":")[0], "time_s": t_ev}
        if kind == "seat":
            item["velocity_m_s"] = float(y[n])
        events.append(item)
        if len(events) > max_events:
            raise RuntimeError(f"more than {max_events} events in one run")
        key = ({"separation": False, "re-contact": True}.get(kind, contact),
               {"lift-off": False, "seat": True}.get(kind, seat))
        t_now = t_ev
        # (a clash changes nothing: restart a hair later so the same crossing is not found again)
        if kind.startswith("coil-clash"):
            t_now = t_ev
    stats = {"rhs_evaluations": int(nfev), "events": len(events)}
    return chain_outputs(model, drive, t, out, keys, events, stats, lambda k: modes(k)[:2])


def _link_force(model, drive, tt, yy) -> float:
    D = drive(np.array([tt]))
    n = model.n
    return model.stiffness * (float(D[0, 0]) - model.lash - yy[0]) + model.damping * (float(D[1, 0]) - yy[n])
