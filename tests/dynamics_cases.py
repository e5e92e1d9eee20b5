"""Drives and scenes shared by the dynamics tests (exact, reference, schenker1902, stability,
bench, elastic effect). Hand-built so that the motion they cause is known in closed form; the
oracles themselves stay in the tests."""

import json
import math
from types import SimpleNamespace

import numpy as np

from explorer.dynamics.model import Drive, LinkageModel
from explorer.lift.curves import LawLift

# The converged reference: DOP853 at rtol 1e-12, accurate to ~1e-13 m on lifts of a few mm.
REF = dict(method="scipy", scipy_method="DOP853", rtol=1e-12, atol=1e-15)

KGF = 9.80665  # Schenker's kg (force) in N; his mass unit kgf s^2/m in kg


class ConstantLift:
    """S = height at every angle (the drive stands still)."""

    def __init__(self, height: float):
        self.height = height

    def derivatives(self, theta):
        theta = np.asarray(theta, dtype=float)
        out = np.zeros((4,) + theta.shape)
        out[0] = self.height
        return out

    def breakpoints(self):
        return np.zeros(0)


class RampStopLift:
    """L = base + slope*theta up to theta_stop, then constant: a drive that stops dead."""

    def __init__(self, base: float, slope: float, theta_stop: float):
        self.base, self.slope, self.theta_stop = base, slope, theta_stop

    def derivatives(self, theta):
        theta = np.asarray(theta, dtype=float)
        out = np.zeros((4,) + theta.shape)
        moving = theta < self.theta_stop
        out[0] = self.base + self.slope * np.where(moving, theta, self.theta_stop)
        out[1] = np.where(moving, self.slope, 0.0)
        return out

    def breakpoints(self):
        return np.array([self.theta_stop])


class BumpLift:
    """A smooth narrow Gaussian bump of the drive, no breakpoints (a trap for event detection)."""

    def __init__(self, height: float, centre: float, width: float, base: float = 0.0):
        self.height, self.centre, self.width, self.base = height, centre, width, base

    def derivatives(self, theta):
        theta = np.asarray(theta, dtype=float)
        z = (theta - self.centre) / self.width
        g = self.height * np.exp(-0.5 * z * z)
        w = self.width
        return np.stack([self.base + g, -z / w * g, (z * z - 1.0) / w**2 * g, (3.0 * z - z**3) / w**3 * g])

    def breakpoints(self):
        return np.zeros(0)


class OffsetLift:
    """base + lift(theta): a follower on a raised base circle (the valve starts pre-lifted)."""

    def __init__(self, base: float, lift):
        self.base, self.lift = base, lift

    def derivatives(self, theta):
        out = self.lift.derivatives(theta)
        out[0] = out[0] + self.base
        return out

    def breakpoints(self):
        return self.lift.breakpoints()


def revolution(drive, n):
    """n output times over one cam revolution."""
    return np.arange(n) * (2.0 * np.pi / drive.omega / n)


# Schenker's gear (1902, section 3): M = 2.9, M1 = 2.6 (technical units), k = 1 800 000 kg/m, W = 385 kg.
SCHENKER = LinkageModel(mass=2.9 * KGF, oscillating_mass=2.6 * KGF, stiffness=1.8e6 * KGF, preload=385.0 * KGF)


def cycloidal_groups(r: float, spring: float, lash: float, zeta: float = 0.0, mu: float = 0.0, e: float = 0.0,
                     m1: float = 1.0):
    """The property tests' case, set by nondimensional groups: a cycloidal rise and return (70 deg
    each) of h = 10 mm at 3000 rpm driving M = 0.1 kg. r: natural period over rise time; spring:
    preload over M times the law's peak deceleration; lash over h; zeta: damping ratio (of k and
    M); mu: friction over preload; e: restitution; m1: M1 over M. Returns (model, drive, h)."""
    rpm, rise, h, M = 3000.0, math.radians(70), 0.01, 0.1
    omega = rpm * math.pi / 30
    t_rise = rise / omega
    k = M * (2 * math.pi / (r * t_rise)) ** 2
    W0 = spring * M * 2 * math.pi * h / t_rise**2  # times the cycloidal peak acceleration
    model = LinkageModel(mass=M, oscillating_mass=m1 * M, stiffness=k, damping=2 * zeta * math.sqrt(k * M),
                         lash=lash * h, preload=W0, friction=mu * W0, restitution=e)
    lift = LawLift(height=h * (1 + lash), start=0.3, rise=rise, dwell=0.2, ret=rise, rise_law="cycloidal",
                   return_law="cycloidal")
    return model, Drive(lift, 1.0, omega), h


def schenker_drive(rpm: float) -> Drive:
    """Schenker's 20.6 mm of roller lift on a harmonic cam, 80 deg up and 80 deg down."""
    lift = LawLift(height=0.0206, start=0.2, rise=1.4, dwell=0.0, ret=1.4, rise_law="harmonic", return_law="harmonic")
    return Drive(lift, 1.0, 2 * math.pi * rpm / 60)


def flight_case():
    """A valve thrown up from s0 = 1 mm at v0 = 2 m/s over a drive at rest at 0: it flies the
    parabola s0 + v0 t - g t^2/2 (g = W/M = 1500 m/s^2) and lands at its root t_land.
    Returns (model, drive, (s0, v0), g, t_land)."""
    M, W = 0.2, 300.0
    model = LinkageModel(mass=M, oscillating_mass=M, stiffness=1e6, preload=W)
    drive = Drive(ConstantLift(0.0), 1.0, 10.0)
    s0, v0, g = 1.0e-3, 2.0, W / M
    t_land = (v0 + math.sqrt(v0 * v0 + 2 * g * s0)) / g
    return model, drive, (s0, v0), g, t_land


def stopping_drive():
    """A drive that stops dead, and the valve's motion after it in closed form.

    At constant drive speed V the valve follows with the steady compression W/k. When the drive
    stops (at t1), the valve oscillates about H - W/k with amplitude A = V/omega (omega with M1),
    separates when k x = 0, i.e. omega tau = asin(W/(k A)), flies under W/M (a parabola) and
    touches the linkage again when s = H (at t_re). Returns a namespace: model, drive, start (the
    initial state), t (output times to past the re-contact), t1, t_sep, t_re, and the lift
    oscillation(t) for t1 < t < t_sep and flight(t) for t_sep < t < t_re."""
    k, M, m1, W = 1.0e6, 0.3, 0.25, 200.0
    omega_cam, slope, theta_stop = 100.0, 1.0e-2, 0.5  # V = 1 m/s, stops at t1 = 5 ms
    model = LinkageModel(mass=M, oscillating_mass=m1, stiffness=k, preload=W)
    drive = Drive(RampStopLift(1e-3, slope, theta_stop), 1.0, omega_cam)
    V, t1 = slope * omega_cam, theta_stop / omega_cam
    H = 1e-3 + slope * theta_stop
    w = math.sqrt(k / m1)
    A = V / w
    tau_sep = math.asin(W / (k * A)) / w
    t_sep = t1 + tau_sep
    s_sep, v_sep = H - W / k + A * math.sin(w * tau_sep), V * math.cos(w * tau_sep)
    g = W / M
    # flight: s = s_sep + v_sep tau - g tau^2 / 2 meets H (x = 0) again
    tau_fly = (v_sep + math.sqrt(v_sep**2 - 2 * g * (H - s_sep))) / g
    t_re = t_sep + tau_fly
    return SimpleNamespace(
        model=model, drive=drive, start=(1e-3 - W / k, V), t=np.linspace(0.0, t_re + 0.2 * (t_re - t1), 4001),
        t1=t1, t_sep=t_sep, t_re=t_re,
        oscillation=lambda t: H - W / k + A * np.sin(w * (t - t1)),
        flight=lambda t: s_sep + v_sep * (t - t_sep) - 0.5 * g * (t - t_sep) ** 2,
    )


def friction_apex(preload: float):
    """A valve thrown up from the seat at v0 = 1 m/s against the preload W and Coulomb friction
    mu = 50 N, the drive at rest at 0. Up: deceleration (W + mu)/M to the apex (t_top, top).
    There the net force is -W: with W <= mu the valve sticks for good, otherwise it falls with
    deceleration (W - mu)/M. Returns a namespace: model, drive, start, t_top, top, sticks and
    fall(t), the lift for t > t_top when it does not stick."""
    M, mu, v0 = 0.1, 50.0, 1.0
    model = LinkageModel(mass=M, oscillating_mass=M, stiffness=1e6, preload=preload, friction=mu)
    drive = Drive(ConstantLift(0.0), 1.0, 10.0)
    g_up = (preload + mu) / M
    t_top, top = v0 / g_up, v0 * v0 / (2 * g_up)
    g_down = (preload - mu) / M
    return SimpleNamespace(model=model, drive=drive, start=(0.0, v0), t_top=t_top, top=top, sticks=preload <= mu,
                           fall=lambda t: np.maximum(top - 0.5 * g_down * (t - t_top) ** 2, 0.0))


def rise_in_contact(rise_law: str, r: float):
    """A rise of h = 2 mm over 0.5 rad of cam angle lasting r natural periods Tn, then a dwell,
    with the valve kept in contact (W = k base holds it on the raised base circle exactly;
    undamped, M1 = M). y = s - L obeys M1 y'' + k y = -M1 L'': after the rise y vibrates freely.
    Returns a namespace: model, drive, h, Tn, t_start (the rise begins), t_dwell (the dwell
    begins), amplitude(sol, t) (of the free vibration, from s and v in the dwell) and
    cycloidal_amplitude = h |sin pi r| / (pi r |1 - r^2|), its closed form after a cycloidal rise
    (h/2 at r = 1, zero at integer r >= 2)."""
    k, m1, h, base = 4.0e6, 1.0, 2.0e-3, 5.0e-3
    w = math.sqrt(k / m1)
    Tn = 2 * math.pi / w
    omega_cam = 0.5 / (r * Tn)  # the rise spans 0.5 rad of cam angle
    lift = LawLift(height=h, start=0.1, rise=0.5, dwell=4.0, ret=0.5, rise_law=rise_law, return_law=rise_law)
    model = LinkageModel(mass=m1, oscillating_mass=m1, stiffness=k, preload=k * base)
    t_dwell = 0.6 / omega_cam

    def amplitude(sol, t):
        dwell = t > t_dwell
        y, yd = sol.s[dwell] - h, sol.v[dwell]
        return np.sqrt(y * y + (yd / w) ** 2)

    return SimpleNamespace(
        model=model, drive=Drive(OffsetLift(base, lift), 1.0, omega_cam), h=h, Tn=Tn, t_start=0.1 / omega_cam,
        t_dwell=t_dwell, amplitude=amplitude,
        cycloidal_amplitude=h * (0.5 if r == 1.0 else abs(math.sin(math.pi * r)) / (math.pi * r * abs(1 - r * r))),
    )


FLOAT_VALVE_TABLES = """[drive]
rpm = 4000
[lift]
law = "polynomial-345"
height = "9.25 mm"
start = "30 deg"
rise = "75 deg"
dwell = "10 deg"
return = "75 deg"
[valve]
mass = "0.10 kg"
lash = "0.25 mm"
[spring]
preload = "220 N"
rate = "30 N/mm"
[loads]
friction = "10 N"
"""


def float_valve_scene(name: str, effects: list[str], more_tables: str = "") -> str:
    """Scene text of a small valve with a soft spring at high speed (lift-off, separations,
    re-contacts and seat), with `more_tables` (TOML) appended."""
    return f"\nname = {json.dumps(name)}\neffects = {json.dumps(effects)}\n" + FLOAT_VALVE_TABLES + more_tables
