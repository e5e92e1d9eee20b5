"""Part of the `exact` solver (exact.py): the grid of steps and the drive over it.

The nodes are the output times plus the drive's breakpoints (where S'' may jump: a step must end
there), with steps longer than MAX_RHO_H / rho split (stiff linkages). Over each step the drive is
the quintic Hermite polynomial through S, S', S'' at both ends (one-sided values at breakpoints),
carried as scaled coefficients in u = tau/h. Steps of (nearly) equal length are grouped, so that
the per-length tables of exact_steps.py are built once per group. See exact.py for the method.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .exact_events import BOUND_WEIGHTS
from .series import hermite5, taylor_shift, taylor_shift1

EPS = float(np.finfo(float).eps)
MAX_RHO_H = 0.5  # longest step times the fastest rate: short, well-conditioned series; cheap chunk bounds
_MAX = np.maximum.reduce  # the ufunc itself: ndarray.max adds a Python layer per call


@dataclass(frozen=True)
class Grid:
    nodes: np.ndarray  # step ends: the output times, the drive's breakpoints, split points
    is_out: np.ndarray  # (bool per node) an output time
    h: np.ndarray  # step lengths
    P: np.ndarray  # (6, steps) the drive's quintic per step, scaled coefficients in u = tau/h
    PT: np.ndarray  # P.T: rows are one step's polynomial
    Dn: np.ndarray  # (3, nodes) S, S', S'' at the nodes as the following step's polynomial sees them
    Sb: np.ndarray  # (3, steps) bounds of |S'|, |S''|, |S'''| over each step
    h_max: float
    uniform: bool  # every step in one length group
    window_h_is_max: bool  # the most common steps are the longest: a window's longest step is h_max
    h_unique: np.ndarray  # the length of each group
    hidx: np.ndarray  # the group of each step
    base_col: int  # the most common group
    odd: np.ndarray  # the steps outside the most common group


def build_grid(drive, t: np.ndarray, rho: float, hmin: float) -> Grid:
    """The grid over the output times t (strictly increasing) for a fastest rate rho; hmin: the
    shortest output step (a breakpoint within 1e-9 of it from a node is that node)."""
    t0, t1 = float(t[0]), float(t[-1])
    tol = 1e-9 * hmin
    n = t.size
    # drive breakpoints: a node within tol of one becomes a breakpoint node, the others are
    # inserted as nodes (a few per revolution: plain Python, then one insertion)
    brk_set, new = set(), []
    bps = [b for b in np.asarray(drive.breakpoints(t0, t1), dtype=float).ravel().tolist() if t0 <= b <= t1]
    if bps:
        for b, i in zip(bps, t.searchsorted(bps).tolist()):
            i = min(max(i, 1), n - 1)
            if b - float(t[i - 1]) <= tol:
                brk_set.add(i - 1)
            elif float(t[i]) - b <= tol:
                brk_set.add(i)
            else:
                new.append(b)
    inserted: list[int] = []  # final indices of the inserted nodes
    if new:
        new = sorted(set(new))
        new = [b for k, b in enumerate(new) if k == 0 or b - new[k - 1] > tol]
        pos = t.searchsorted(new).tolist()  # insertion points (no node within tol)
        inserted = [p + k for k, p in enumerate(pos)]
        nodes = np.empty(n + len(new))
        prev = 0
        for k, (p, b) in enumerate(zip(pos, new)):
            nodes[prev + k:p + k] = t[prev:p]
            nodes[p + k] = b
            prev = p
        nodes[prev + len(new):] = t[prev:]
        brk = sorted({i + sum(1 for p in pos if p <= i) for i in brk_set} | set(inserted))
    else:
        nodes = t.copy()
        brk = sorted(brk_set)
    is_out = np.empty(nodes.size, bool)
    is_out[:] = True
    is_out[inserted] = False
    h = nodes[1:] - nodes[:-1]
    h_max = float(_MAX(h))
    # split steps longer than MAX_RHO_H / rho (stiff linkages)
    if rho * h_max / MAX_RHO_H > 1.0:
        brk_mask = np.zeros(nodes.size, bool)
        brk_mask[brk] = True
        parts = np.maximum(1, np.ceil(rho * h / MAX_RHO_H)).astype(np.int64)
        starts = np.repeat(nodes[:-1], parts)
        frac = np.arange(parts.sum()) - np.repeat(np.cumsum(parts) - parts, parts)
        inner = starts + np.repeat(h / parts, parts) * frac
        keep = frac > 0
        nodes = np.concatenate([nodes, inner[keep]])
        is_out = np.concatenate([is_out, np.zeros(int(keep.sum()), bool)])
        brk_mask = np.concatenate([brk_mask, np.zeros(int(keep.sum()), bool)])
        order = np.argsort(nodes, kind="stable")
        nodes, is_out, brk_mask = nodes[order], is_out[order], brk_mask[order]
        brk = brk_mask.nonzero()[0].tolist()
        h = nodes[1:] - nodes[:-1]
        h_max = float(_MAX(h))
    nn = nodes.size
    # one-sided drive data at breakpoint nodes: evaluated a hair inside and moved back by Taylor
    nb = len(brk)
    if nb:
        hl = [float(h[i - 1]) if i > 0 else math.inf for i in brk]
        hr = [float(h[i]) if i < nn - 1 else math.inf for i in brk]
        d = [1e-7 * min(a, b) for a, b in zip(hl, hr)]
        tb = nodes[brk]
        dd = np.array(d)
        D = np.asarray(drive(np.concatenate([nodes, tb + dd, tb - dd])), dtype=float)
        right = D[:3, :nn]
        left = right.copy()
        if nb <= 32:  # a few breakpoints: plain Python (numpy's overhead on tiny arrays)
            Dr, Dl = D[:, nn:nn + nb].T.tolist(), D[:, nn + nb:].T.tolist()
            right[:, brk] = np.array([taylor_shift1(r, -di)[:3] for di, r in zip(d, Dr)]).T
            left[:, brk] = np.array([taylor_shift1(l, di)[:3] for di, l in zip(d, Dl)]).T
        else:
            right[:, brk] = taylor_shift(D[:, nn:nn + nb], -dd)[:3]
            left[:, brk] = taylor_shift(D[:, nn + nb:], dd)[:3]
    else:
        right = left = np.asarray(drive(nodes), dtype=float)
    P = hermite5(h, right[:, :-1], left[:, 1:])  # (6, steps)
    # drive at the nodes as the following step sees it (the last node: the end of its step):
    # S, S', S'' of the step polynomials, so node values match the step expansions
    inv = 1.0 / h
    inv2 = inv * inv
    Dn = np.empty((3, nn))
    Dn[0, :-1] = P[0]
    np.multiply(P[1], inv, out=Dn[1, :-1])
    np.multiply(P[2], 2.0 * inv2, out=Dn[2, :-1])
    last = P[:, -1].tolist()
    Dn[0, -1] = math.fsum(last)
    Dn[1, -1] = sum(k * c for k, c in enumerate(last)) * float(inv[-1])
    Dn[2, -1] = sum(k * (k - 1) * c for k, c in enumerate(last)) * float(inv2[-1])
    # per step: bounds of |S1|, |S2|, |S3| (derivatives) over the step (from the polynomial)
    Sb = BOUND_WEIGHTS @ np.abs(P)
    Sb[0] *= inv
    Sb[1] *= inv2
    inv2 *= inv
    Sb[2] *= inv2
    return Grid(nodes=nodes, is_out=is_out, h=h, P=P, PT=P.T, Dn=Dn, Sb=Sb, h_max=h_max,
                **_group_steps(nodes, h, h_max))


def _group_steps(nodes: np.ndarray, h: np.ndarray, h_max: float) -> dict:
    """Steps of (nearly) equal length share their tables: equal up to 1e-11 relative or up to
    the rounding of the node times (a few ulp of t: a uniform grid of 10^5 steps differs by
    ~1e-10 relative from step to step). The sorted lengths are chained while consecutive
    ones differ by at most tol; the tables take a group's mean length (summed in sorted
    order): a time warp of the drive by at most those roundings (~1e-18 s), no error of
    the state. Returns Grid's fields uniform (one group), window_h_is_max, h_unique (group
    lengths), hidx (group of each step), base_col (the most common group) and odd (the steps
    of the other groups)."""
    tol = max(1e-11 * h_max, 8.0 * EPS * max(abs(float(nodes[0])), abs(float(nodes[-1]))))
    uniform = float(np.minimum.reduce(h)) >= h_max - tol
    if uniform:
        # the scan bounds a window's longest step by the grid's when the most common steps are
        # the longest (a uniform grid with drive breakpoints inserted): the same bound then
        return dict(uniform=True, window_h_is_max=True,
                    h_unique=np.array([np.add.reduce(h) / h.size]),  # (h.mean())
                    hidx=np.zeros(h.size, dtype=np.int64), base_col=0, odd=np.zeros(0, dtype=np.int64))
    hs = h.copy()
    hs.sort()  # (equal lengths are equal floats: no need of a stable argsort)
    starts = (hs[1:] - hs[:-1] > tol).nonzero()[0] + 1
    bounds = [0] + starts.tolist() + [h.size]
    means = []
    for a, b in zip(bounds[:-1], bounds[1:]):
        if b - a > 32:
            total = float(hs[a:b].cumsum()[-1])  # sequential, as a running sum
        else:
            total = 0.0
            for x in hs[a:b].tolist():
                total += x
        means.append(total / (b - a))
    counts = [b - a for a, b in zip(bounds[:-1], bounds[1:])]
    base = max(range(len(counts)), key=counts.__getitem__)  # the most common length
    # the steps outside the base group's range, and their groups (searched among the few)
    lo, hi = float(hs[bounds[base]]), float(hs[bounds[base + 1] - 1])
    odd = ((h < lo) | (h > hi)).nonzero()[0]
    hidx = np.empty(h.size, dtype=np.intp)
    hidx[:] = base
    hidx[odd] = hs[starts].searchsorted(h[odd], side="right")  # group starts at or below
    return dict(uniform=False, window_h_is_max=base == len(counts) - 1, h_unique=np.array(means), hidx=hidx,
                base_col=base, odd=odd)
