"""Closed-form node states of one linear phase kind over a whole grid (used by exact.py).

A moving phase obeys m s'' + c s' + K s = f_drive(t) - Fc with constant coefficients. From node to
node the state x = (s, v) follows x[n+1] = Phi(h_n) x[n] + g_n with Phi(h) = exp(A h). In modal
coordinates y = (s, (v + alpha s)/beta) (alpha = c/2m, beta = sqrt|K/m - alpha^2|) exp(A h) is a
multiplication by exp(mu h) for every step length h: one complex mode mu = -alpha - i beta
(underdamped) or two real ones mu = -alpha +- beta (overdamped). So the product of the steps from
node j to node n is U_n / U_j with U_n = prod_{m<n} exp(mu h_m) (step_powers: each U_n to a few
eps, no drift with n), and the recurrence is solved by
    z_n = z_p + U_n ((z_j - z_p) D_j + Q_n - Q_j),   D = 1/U,   Q_n = sum_{m<n} D_{m+1} w_m,
where z_p is the particular (static) state of the constant load -Fc and w_m the modal part of the
drive's forcing over step m (from exact.py's step tables). U and the sums Q depend only on the
phase kind, not on where a phase starts or on Fc: they are computed once per solve (U for the
whole grid; Q, when the forcing is given as a function of the steps, as far as the phases reach,
with the same values), and a phase is then a few vector operations on slices (no per-phase
cumulative sums, no Python loop over steps).

Rounding: Q_n - Q_j carries an absolute error of a few eps times the modal responses summed from
j to n, as a step-by-step recurrence does; the powers U are exact to a few eps relative (no
accumulation: a stiff linkage's v = beta Im z would otherwise lose eps beta^2 |z| t); the sums
are two-level prefix sums. On a stiff linkage (k = 1e11 N/m, 3000 steps of 0.46 rad) the node
velocities agree with a long-double recurrence to ~5e-13 relative, where the per-run recurrence
this replaced drifted to ~1e-9 (tests/test_dynamics_modal.py: all within 64 eps of the state's
size). With damping |U| decays and
|D| grows; the grid is cut into blocks over which |Re mu| (t_n - t_b) stays below BLOCK_RATE (no
overflow, and the sums stay dominated by recent terms, so nothing is lost in Q_n - Q_j). Critical
damping (a Jordan block, no modal form) uses a plain step-by-step loop. A phase with neither
stiffness nor damping (flight without spring rate) is the parabola s = s_j + v_j tau -
Fc tau^2 / 2m in closed form.
"""

from __future__ import annotations

import cmath
import math

import numpy as np

BLOCK_RATE = 200.0  # decay rate times a block's duration: exp(200) ~ 1e87, far from overflow
_SPLIT = 134217729.0  # 2^27 + 1 (Dekker's splitting)


def _split(a: float):
    c = _SPLIT * a
    hi = c - (c - a)
    return hi, a - hi


def _two_prod(a: float, b: float):
    """a b = p + e exactly (Dekker)."""
    p = a * b
    ah, al = _split(a)
    bh, bl = _split(b)
    return p, ((ah * bh - p) + ah * bl + al * bh) + al * bl


def _power(rh: float, rl: float, ih: float, il: float, scale: float, is_complex: bool):
    """exp(scale (r + i i')) for the double-doubles r = rh + rl, i' = ih + il and a power of two
    `scale`: exactly rounded but for the tiny low parts (a first-order correction)."""
    if is_complex:
        xl = complex(rl, il) * scale
        return cmath.exp(complex(rh * scale, ih * scale)) * (1.0 + xl * (1.0 + 0.5 * xl))
    xl = rl * scale
    return math.exp(rh * scale) * (1.0 + xl * (1.0 + 0.5 * xl))


def _doubling(first: float | complex, parts: list, n: int, dtype) -> np.ndarray:
    """[p^0, p^1, ..., p^(n-1)] by doubling, parts[k] = p^(2^k) (each exactly rounded)."""
    out = np.empty(n, dtype=dtype)
    out[0] = 1.0
    filled, k = 1, 0
    while filled < n:
        m = min(filled, n - filled)
        np.multiply(out[:m], parts[k], out=out[filled:filled + m])
        filled += m
        k += 1
    return out


def _lattice(mu, h: float, n: int, mu_lo=0.0) -> np.ndarray:
    """exp(mu h)^i for i = 0..n-1, from exp(mu h 2^k), each from the exact double-double
    product mu h (so the powers agree with exp(mu h i) to ~log2(i) eps, however large mu h i:
    no drift of the argument's rounding with i). mu_lo: the low part of mu when mu is known
    more precisely than a double (a frequency sqrt(K/m) rounds by half an ulp, which would turn
    the phase by eps omega t). The low and the high bits of i separately (two short doublings),
    combined by one outer product."""
    is_complex = isinstance(mu, complex)
    mr, mi = (mu.real, mu.imag) if is_complex else (float(mu), 0.0)
    rh, rl = _two_prod(mr, h)
    ih, il = _two_prod(mi, h)
    if mu_lo:
        lo = complex(mu_lo)
        rl += lo.real * h
        il += lo.imag * h
    dtype = complex if is_complex else float
    bits = max(1, (n - 1).bit_length())
    low_bits = (bits + 1) // 2
    parts = [_power(rh, rl, ih, il, float(1 << k), is_complex) for k in range(bits)]
    low = _doubling(1.0, parts[:low_bits], 1 << low_bits, dtype)
    high = _doubling(1.0, parts[low_bits:], -(-n >> low_bits), dtype)
    return np.multiply.outer(high, low).ravel()[:n]


LATTICE_MIN = 64  # a step length this frequent gets lattice powers (others: a cumulative product)


def step_powers(mu, hidx: np.ndarray, h_unique: np.ndarray, mu_lo=0.0, base: int | None = None) -> np.ndarray:
    """U_n = prod_{m<n} exp(mu h_m) at the nodes n = 0..len(hidx) of a run of steps, h_m =
    h_unique[hidx[m]] (the step lengths of exact.py's step tables, so that U agrees with the
    tables' forcing: mixing in the nodes' own differences, which differ from the tables' by
    ~1e-13 relative, costs ~1e-11 relative in v for a stiff linkage).

    Each U_n is accurate to a few eps relative, whatever n: the propagation of a phase from
    node j to n is U_n / U_j, and both errors enter. Every frequent step length contributes
    lattice powers (the count of its steps before n is exact); the rare ones (steps ending at
    inserted drive breakpoints) a cumulative product, whose error grows with their number.
    base: the most common column of hidx, when known (the usual grid: that length and fewer
    than LATTICE_MIN others, whose product is then applied run by run between them)."""
    n = hidx.size
    if base is not None:
        odd = (hidx != base).nonzero()[0]
        if odd.size == 0:
            return _lattice(mu, float(h_unique[base]), n + 1, mu_lo)
        if odd.size < LATTICE_MIN <= n - odd.size:
            # the same products as below: U_n = lattice[n - k] * C[k], k the rare steps before n
            lattice = _lattice(mu, float(h_unique[base]), n - odd.size + 1, mu_lo)
            C = np.empty(odd.size + 1, dtype=lattice.dtype)
            C[0] = 1.0
            np.exp(mu * h_unique[hidx[odd]]).cumprod(out=C[1:])
            U = np.empty(n + 1, dtype=lattice.dtype)
            a = 0
            for k, (m, ck) in enumerate(zip(odd.tolist(), C.tolist())):
                np.multiply(lattice[a - k:m + 1 - k], ck, out=U[a:m + 1])  # nodes a..m: k rare steps before
                a = m + 1
            np.multiply(lattice[a - odd.size:], C[-1], out=U[a:])
            return U
    counts = np.bincount(hidx, minlength=h_unique.size)
    U = None
    rest = np.ones(n, dtype=bool)
    if counts.size == 1 or counts.max() == n:  # one step length: the lattice itself
        return _lattice(mu, float(h_unique[hidx[0]] if n else h_unique[0]), n + 1, mu_lo)
    for col in np.nonzero(counts >= LATTICE_MIN)[0].tolist():
        member = hidx == col
        c = np.zeros(n + 1, dtype=np.int64)
        np.cumsum(member, out=c[1:])
        powers = _lattice(mu, float(h_unique[col]), int(c[-1]) + 1, mu_lo)[c]
        U = powers if U is None else U * powers
        rest &= ~member
    if U is None:
        U = np.ones(n + 1, dtype=np.result_type(mu, 1.0))
    odd = np.nonzero(rest)[0]
    if odd.size:
        C = np.empty(odd.size + 1, dtype=U.dtype)
        C[0] = 1.0
        np.cumprod(np.exp(mu * h_unique[hidx[odd]]), out=C[1:])
        c = np.zeros(n + 1, dtype=np.int64)
        np.cumsum(rest, out=c[1:])
        U *= C[c]  # the product over the rare steps before each node
    return U


PREFIX_BLOCK = 64


def _prefix_size(n: int) -> int:
    """Length of the buffer _prefix_sum_into works in for n terms (whole blocks)."""
    return n if n <= 4 * PREFIX_BLOCK else -(-n // PREFIX_BLOCK) * PREFIX_BLOCK


def _prefix_sum_into(buf: np.ndarray, n: int) -> np.ndarray:
    """[0, x_0, x_0 + x_1, ...] in place: buf = [0, x_0, ..., x_(n-1), (unused up to 1 +
    _prefix_size(n))]; returns buf[:n + 1] (the sums of _prefix_sum, with the leading 0)."""
    B = PREFIX_BLOCK
    buf[0] = 0.0
    if n <= 4 * B:
        buf[1:n + 1].cumsum(out=buf[1:n + 1])
        return buf[:n + 1]
    pad = buf[1:]
    pad[n:] = 0.0
    M = pad.reshape(-1, B)
    M.cumsum(axis=1, out=M)
    M[1:] += M[:-1, -1].cumsum()[:, None]
    return buf[:n + 1]


LAZY_CHUNK = 16 * PREFIX_BLOCK  # nodes of the first part of a lazily summed Q


class _LazyPrefix:
    """Q = [0, cumsum(D[1:] w)] of one complex mode over one block, summed as far as the phases
    reach: the first LAZY_CHUNK nodes (or up to the first phase's window), then, if a phase
    goes further, the rest (a phase kind often covers a part of the grid only). The chunks are
    whole blocks of _prefix_sum_into and the block offsets are carried from chunk to chunk in
    the same order of additions: the values are those of the sum over the whole block."""

    def __init__(self, U: np.ndarray, unit: bool, weights, b0: int, k: int):
        self.U, self.unit, self.weights, self.b0, self.k = U, unit, weights, b0, k
        self.buf = np.empty(_prefix_size(k) + 1, dtype=U.dtype)
        self.buf[0] = 0.0
        self.ready = 0  # terms summed (Q valid at the nodes 0..ready)
        self.carry = 0.0  # offset of the next block (the block totals so far, summed in order)

    def upto(self, n: int) -> np.ndarray:
        """The buffer, with Q valid at the nodes 0..n (at least)."""
        if n > self.ready:
            self._extend(n)
        return self.buf

    def _extend(self, n: int) -> None:
        B, k, r, buf = PREFIX_BLOCK, self.k, self.ready, self.buf
        two_level = k > 4 * B
        # the first chunk, then all the rest (a kind that comes back usually covers much of the grid)
        r2 = k if not two_level or r else min(k, -(-max(n, LAZY_CHUNK) // B) * B)
        terms = buf[1 + r:1 + r2]
        if self.unit:
            np.conjugate(self.U[1 + r:1 + r2], out=terms)
        else:
            np.divide(1.0, self.U[1 + r:1 + r2], out=terms)
        terms *= self.weights(self.b0 + r, self.b0 + r2)
        if not two_level:
            terms.cumsum(out=terms)
        else:
            end = r2 if r2 < k else buf.size - 1
            buf[1 + r2:1 + end] = 0.0
            M = buf[1 + r:1 + end].reshape(-1, B)
            M.cumsum(axis=1, out=M)
            # offsets: o_(b+1) = o_b + T_b, the running sum of the block totals T (in order)
            offsets = np.empty(M.shape[0], dtype=buf.dtype)
            offsets[0] = self.carry
            offsets[1:] = M[:-1, -1]
            last = M[-1, -1]
            offsets.cumsum(out=offsets)
            self.carry = offsets[-1] + last
            if r == 0:
                M[1:] += offsets[1:, None]
            else:
                M += offsets[:, None]
        self.ready = r2


class Propagator:
    """Node states of one phase kind (m, c, K) on the grid `nodes` with the drive's per-step
    forcing G (2, steps) in (s, v) (the response over each step from zero state) and the step
    transition matrices Phi (2, 2, steps) (used only by the critical-damping loop). G may also
    be a function G(a, b) -> (2, b - a) of the steps a..b-1: then an underdamped kind sums the
    drive's forcing only as far as its phases reach (the same values, chunk by chunk).

    states(j, L, s, v, Fc) -> (2, L + 1) array of s and v at the nodes j..j+L (s, v given at j):
    a few vector operations, however long the run (the critical-damping loop excepted)."""

    def __init__(self, m: float, c: float, K: float, nodes: np.ndarray, G, Phi_of_step,
                 hidx: np.ndarray, h_unique: np.ndarray, base: int | None = None):
        self.m, self.c, self.K = m, c, K
        self.nodes = nodes
        alpha = 0.5 * c / m
        self.alpha = alpha
        disc = K / m - alpha * alpha
        scale = max(K / m, alpha * alpha)
        if K == 0.0 and c == 0.0 and G is None:
            self.mode = "parabola"
            return
        lazy = callable(G)
        if lazy and not disc > 0.0:  # (sums over the whole grid at once, as from an array)
            G, lazy = G(0, hidx.size), False
        if scale == 0.0 or abs(disc) <= 1e-8 * scale:
            # (nearly) critical damping: a Jordan block, no modal form -- or no dynamics at all
            self.mode = "loop"
            self.Phi_of_step = Phi_of_step
            self.G = G
            return
        beta = math.sqrt(abs(disc))
        self.beta = beta
        # beta and the modes' exponents as double-doubles (beta^2 = |K/m - alpha^2| exactly, for
        # the doubles K/m and alpha): the powers' phase then does not drift by eps beta t
        Km = K / m
        a2, a2e = _two_prod(alpha, alpha)
        d_hi = Km - a2
        bb = d_hi - Km
        d_lo = ((Km - (d_hi - bb)) + (-a2 - bb)) - a2e  # Km - alpha^2 = d_hi + d_lo (two-sum)
        if disc < 0.0:
            d_hi, d_lo = -d_hi, -d_lo
        b2, b2e = _two_prod(beta, beta)
        beta_lo = ((d_hi - b2) - b2e + d_lo) / (2.0 * beta)
        if disc > 0.0:
            self.mode = "complex"
            mus = [complex(-alpha, -beta)]
            mus_lo = [complex(0.0, -beta_lo)]
        else:
            self.mode = "real"
            mus = [beta - alpha, -alpha - beta]
            mus_lo = [beta_lo, -beta_lo]
        # the fastest decay: how fast |D| = 1/|U| grows
        rate = max(-mu.real if isinstance(mu, complex) else abs(mu) for mu in mus)
        # modal forcing of the drive: w = g0 + i (alpha g0 + g1) / beta (complex) or
        # g0 +- (alpha g0 + g1) / beta (real)
        if lazy:
            ws = [lambda a, b: self._weights(G(a, b))]
        elif G is not None:
            if self.mode == "complex":
                ws = [self._weights(G)]
            else:
                g0, g1 = G
                w2 = (alpha * g0 + g1) / beta if alpha else g1 / beta
                ws = [g0 + w2, g0 - w2]
        else:
            ws = [None] * len(mus)
        # blocks of nodes [b_k, b_{k+1}] over which |Re mu| tau stays below BLOCK_RATE
        n = nodes.size
        if rate * (nodes[-1] - nodes[0]) <= BLOCK_RATE:
            cuts = [0, n - 1]
        else:
            tau = nodes - nodes[0]
            marks = np.floor(tau * (rate / BLOCK_RATE)).astype(np.int64)
            starts = np.nonzero(np.diff(marks))[0] + 1
            cuts = [0] + starts.tolist() + [n - 1]
            cuts = [b for i, b in enumerate(cuts) if i == 0 or b > cuts[i - 1]]
            if cuts[-1] != n - 1:
                cuts.append(n - 1)
        self.cuts = cuts
        self.block_of_node = None
        if len(cuts) > 2:
            self.block_of_node = np.searchsorted(np.asarray(cuts[1:-1]), np.arange(n), side="right")
        # per mode, per block: U over the block's nodes, Q of the drive over them (None: no
        # drive); D = 1/U is only needed at a phase's first node (unit: |U| = 1, D = conj(U))
        self.modes = []
        for mu, mu_lo, w in zip(mus, mus_lo, ws):
            blocks = []
            unit = alpha == 0.0 and isinstance(mu, complex)
            for b0, b1 in zip(cuts[:-1], cuts[1:]):
                U = step_powers(mu, hidx[b0:b1], h_unique, mu_lo, base)
                if lazy:
                    Q = _LazyPrefix(U, unit, w, b0, b1 - b0)
                elif w is not None:  # Q = [0, cumsum(D[1:] w)], computed in its own buffer
                    k = b1 - b0
                    buf = np.empty(_prefix_size(k) + 1, dtype=U.dtype)
                    terms = buf[1:k + 1]
                    if unit:
                        np.conjugate(U[1:], out=terms)
                    else:
                        np.divide(1.0, U[1:], out=terms)
                    terms *= w[b0:b1]
                    Q = _prefix_sum_into(buf, k)
                else:
                    Q = None
                blocks.append((U, Q, unit))
            self.modes.append(blocks)

    def _weights(self, G: np.ndarray) -> np.ndarray:
        """The modal forcing w = g0 + i (alpha g0 + g1) / beta of the complex mode."""
        g0, g1 = G
        w = np.empty(g0.size, dtype=complex)  # without temporaries
        w.real = g0
        if self.alpha:
            w.imag = (self.alpha * g0 + g1) / self.beta
        else:
            np.divide(g1, self.beta, out=w.imag)
        return w

    def states(self, j: int, L: int, s: float, v: float, Fc: float) -> np.ndarray:
        """(2, L + 1): s and v at the nodes j..j+L of a phase at (s, v) at node j under the
        constant load -Fc and the drive."""
        mode = self.mode
        if mode == "loop":
            return self._loop(j, L, s, v, Fc)
        SV = np.empty((2, L + 1))
        S, V = SV
        if mode == "parabola":
            tau = self.nodes[j:j + L + 1] - self.nodes[j]
            acc = -Fc / self.m
            np.multiply(tau, acc, out=V)
            V += v
            np.multiply(tau, 0.5 * acc, out=S)
            S += v
            S *= tau
            S += s
        else:
            alpha, beta = self.alpha, self.beta
            y2 = (v + alpha * s) / beta
            sp = -Fc / self.K
            yp = alpha * sp / beta
            if mode == "complex":
                # relative to the static state
                Z = self._mode_run(self.modes[0], j, L, complex(s - sp, y2 - yp))
                np.add(Z.real, sp, out=S)
                np.multiply(Z.imag, beta, out=V)
                if alpha:
                    V += beta * yp
                    V -= alpha * S
            else:
                zp = self._mode_run(self.modes[0], j, L, (s - sp) + (y2 - yp))
                zm = self._mode_run(self.modes[1], j, L, (s - sp) - (y2 - yp))
                S[:] = 0.5 * (zp + zm) + sp
                V[:] = beta * (0.5 * (zp - zm) + yp) - alpha * S
        S[0], V[0] = s, v
        return SV

    def _mode_run(self, blocks, j: int, L: int, z):
        """z_n - z_p at nodes j..j+L of one mode, from z_j - z_p = z."""
        cuts = self.cuts
        if len(cuts) == 2:
            U, Q, unit = blocks[0]
            e = j + L + 1
            # (the product in plain Python: the same arithmetic, less overhead; a quotient
            # differs between numpy and Python)
            zD = z * U[j].item().conjugate() if unit else z / U[j]
            if Q is None:
                return U[j:e] * zD
            if not isinstance(Q, np.ndarray):
                Q = Q.upto(e - 1)
            return U[j:e] * ((zD - Q[j].item()) + Q[j:e])
        out = np.empty(L + 1, dtype=blocks[0][0].dtype)
        k = int(self.block_of_node[j])
        n, end = j, j + L
        while True:
            b0, b1 = cuts[k], cuts[k + 1]
            U, Q, unit = blocks[k]
            lj, le = n - b0, min(end, b1) - b0
            zD = z * U[lj].conjugate() if unit else z / U[lj]
            if Q is None:
                seg = U[lj:le + 1] * zD
            else:
                if not isinstance(Q, np.ndarray):
                    Q = Q.upto(le)
                seg = U[lj:le + 1] * ((zD - Q[lj]) + Q[lj:le + 1])
            out[n - j:n - j + le - lj + 1] = seg
            n = b0 + le
            if n >= end:
                return out
            z = seg[-1]
            k += 1

    def _loop(self, j: int, L: int, s: float, v: float, Fc: float):
        Phi, g1 = self.Phi_of_step(j, L)
        (p11, p12), (p21, p22) = Phi
        if self.G is not None:
            G0, G1 = (x.tolist() for x in self.G[:, j:j + L])
        else:
            G0 = G1 = [0.0] * L
        c0, c1 = g1
        S, V = [s] * (L + 1), [v] * (L + 1)
        for i in range(L):
            s, v = (p11[i] * s + p12[i] * v + G0[i] - Fc * c0[i],
                    p21[i] * s + p22[i] * v + G1[i] - Fc * c1[i])
            S[i + 1], V[i + 1] = s, v
        return np.array([S, V])
