"""Part of the `exact` solver (exact.py): the output. The solver records s, v, the phase and the
friction sign at every node; acceleration, jerk and linkage force follow here from the phase
ODEs at all nodes at once (exact: the closed form's derivatives), and the output times are
picked from the nodes (output_nodes: the nodes of the output times; the compiled exact solver,
exact_kernel.py, shares both)."""

from __future__ import annotations

import numpy as np

from .model import DynamicsSolution
from .phases import CONTACT, FLIGHT


def output_nodes(t) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, float]:
    """(the output times as a flat float array, the grid's output nodes: the distinct times, the
    node of each output time (None: the nodes are the output times), the shortest step between
    nodes). ValueError (one line) for times that are empty, unsorted or not finite. One instant
    alone gets a second node 1e-9 s later (the state itself is the answer)."""
    t_req = np.asarray(t, dtype=float).ravel()
    steps = t_req[1:] - t_req[:-1]
    hmin = float(np.minimum.reduce(steps)) if steps.size else 0.0
    if t_req.size == 0 or hmin < 0.0 or not np.isfinite(t_req).all():
        raise ValueError("output times must be a non-empty, sorted array of finite numbers")
    if t_req.size > 1 and hmin > 0.0:  # strictly increasing: the nodes themselves
        return t_req, t_req, None, hmin
    t_nodes, inverse = np.unique(t_req, return_inverse=True)
    inverse = inverse.ravel()
    if t_nodes.size == 1:  # one instant: the state itself
        t_nodes = np.array([t_nodes[0], t_nodes[0] + 1e-9])
        inverse = np.zeros(t_req.size, dtype=np.int64)
    return t_req, t_nodes, inverse, float(np.minimum.reduce(t_nodes[1:] - t_nodes[:-1]))


def solution(t_req: np.ndarray, inverse, s: np.ndarray, v: np.ndarray, sigma: np.ndarray, phase: np.ndarray, Dn,
             is_out: np.ndarray, lins: dict, k_link: float, c_link: float, lash: float, W0: float, R: float,
             events: list, stats: dict) -> DynamicsSolution:
    """The results at the output times t_req from the node records s, v, friction sign sigma and
    phase (codes); Dn: S, S', S'' at the nodes; is_out: the nodes that are output times;
    inverse: node of each output time (None: one each, in order); lins: the LinearPhase of each
    moving phase code; k_link, c_link, lash, W0, R: the model's (stats gets the event count)."""
    D0, D1, D2 = Dn
    # acceleration and jerk from the phase ODEs (exact: the closed form's derivatives), with
    # each node's coefficients looked up by its phase code (at rest: a = jerk = 0); computed
    # in place in the looked-up rows (the formulas' order of operations kept)
    table = np.zeros((8, 4))
    table[1] = 1.0  # m
    table[7] = 1.0  # linkage force kept (0 in flight)
    for code, lin in lins.items():
        table[:7, code] = (1.0, lin.m, lin.c, lin.K, lin.kc, lin.cc, lin.kc * lash + W0)
    table[7, FLIGHT] = 0.0
    moving, m, c, K, kc, cc, Fc, keep = table.take(phase, axis=1)
    if R:
        Fc += R * sigma
    acc = kc * D0  # (kc D0 + cc D1 - Fc - c v - K s) / m * moving
    if c_link:
        acc += cc * D1
        acc -= Fc
        acc -= np.multiply(c, v, out=Fc)
    else:
        acc -= Fc
    acc -= np.multiply(K, s, out=Fc)
    acc /= m
    acc *= moving
    jerk = np.multiply(kc, D1, out=kc)  # (kc D1 + cc D2 - c a - K v) / m * moving
    if c_link:
        jerk += np.multiply(cc, D2, out=cc)
        jerk -= np.multiply(c, acc, out=c)
    jerk -= np.multiply(K, v, out=K)
    jerk /= m
    jerk *= moving
    # linkage force: in contact the stretched linkage; at rest the static force; in flight 0
    x = D0 - lash
    x -= s
    if c_link:
        kx = k_link * x
        contact_force = np.maximum(0.0, kx + c_link * (D1 - v))
        rest_force = np.where(x >= 0.0, np.maximum(0.0, kx + c_link * D1), 0.0)
        force = np.where(phase == CONTACT, contact_force, np.where(moving > 0.0, 0.0, rest_force))
    else:  # undamped: contact and rest alike max(0, k x) (k x < 0 exactly where x < 0)
        x *= k_link
        force = np.maximum(x, 0.0, out=x)
        force *= keep
    stats["events"] = len(events)
    if inverse is None and is_out.all():  # the output times are the nodes
        pick = slice(None)
    else:
        out = is_out.nonzero()[0]
        pick = out if inverse is None else out[inverse]
    force = force[pick]
    return DynamicsSolution(
        t=t_req, s=s[pick], v=v[pick], a=acc[pick], linkage_force=force,
        contact=force > 0.0, events=tuple(events), stats=stats,
        jerk=jerk[pick], phase=phase[pick].astype(np.int64),
    )
