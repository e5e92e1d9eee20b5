"""`polydyne` law: the cam that makes an elastic linkage give the wanted valve lift (Dudley 1948).

Schenker's "Rückwärtskonstruktion" (1902) laid the lift curve out for given accelerations and
drew the cam backwards from it; Dudley's polydyne cam does the same with the linkage's
elasticity. In contact the valve obeys (explorer.dynamics.model, no damping)

    M1 s'' = k (S - lash - s) - W(s),   W(s) = preload + rate s + closing loads

so a drive S(t) = lash + s + (M1 s'' + W(s)) / k makes the valve follow any wanted s(t) exactly.
With s'' = w_d^2 d2s/dtheta2 at the design speed w_d the cam lift (follower, before the ratio) is

    L(theta) = [lash + s + (M1 w_d^2 s_theta_theta + W(s)) / k] / ratio      while the valve is open,

and its derivatives are exact: L^(n) = [s^(n) (1 + rate/k) + (M1 w_d^2 / k) s^(n+2)] / ratio, which
needs the wanted lift to its fifth derivative for the cam's jerk (closed forms, explorer.lift.laws).

Before the valve lifts the linkage must take up the lash and be loaded to W(0): a take-up ramp
(cycloidal, angle `ramp`) raises S from 0 to S0 = lash + W(0)/k; at its end the valve lifts with
zero velocity and acceleration. After the event the same ramp, reversed, unloads the linkage.

Smoothness: S is continuous only if s'' is, and its slope only if s''' is: a wanted law whose
acceleration or jerk jumps (cycloidal and 3-4-5 at their ends) would need a cam with a step or a
corner, and is refused naming that derivative. The cam's acceleration holds the wanted snap s^(4),
so a wanted lift whose snap jumps (4-5-6-7 at its ends, into a dwell or a ramp) makes a cam whose
acceleration steps by (M1 w_d^2/k) w_d^2 times the jump (valve-referred, m/s^2): a valid cam, whose
jerk is unbounded there, so the run warns in one line (`acceleration_steps`: the same rule for a
closed form and a spline, read off the law's own derivatives at each joint) and advises the
5-6-7-8-9 polynomial, continuous to its snap. The linkage must push throughout
(M1 w_d^2 s_theta_theta + W(s) > 0), and the model has no term for Coulomb friction (it flips at the
valve's reversal and would step the cam by 2 R / k) or a damper (then S follows from a differential
equation): both are refused.

The wanted lift may also be a spline (`wanted_law = "spline"` with [[lift.stations]] as for the
spline law, explorer.lift.spline): then no closed form is smooth enough by itself, so the spline
must ask for it. `continuity` (default 4, at least 3) makes s to its fourth derivative (snap)
continuous at every interior station, so that the cam's acceleration
L_theta_theta = [s_theta_theta (1 + rate/k) + (M1 w_d^2/k) s^(4)] / ratio has no step; and
s, v, a, j, snap = 0 at the first and last station join the event to the take-up ramps as
smoothly (at the ramps' ends the cam's slope and acceleration are 0). A shortfall up to the jerk
is refused naming the derivative, as for a rough law; one in the snap (continuity = 3, or an end
snap not 0) warns, as for a closed form. The spline's polynomials are exact to any order, so
the cam's jerk (from s^(5)) comes from them too.

Off the design speed the valve deviates: with e = s - s_wanted, in contact
M1 e'' + (k + rate) e = M1 (w_d^2 - w^2) s_theta_theta(w t), a linear oscillator whose residual
vibration after a rise has the closed form in `residual_amplitude`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..core.errors import InputError, echo
from ..core.ranges import RANGES
from .laws import HIGH_ORDER_LAWS, LAWS, POLYNOMIAL_56789, law_derivatives
from .validity import computed_error, lift_fault
from .spline import MAX_CONTINUITY, SplineLift, SplineOptions, check_spline_shape, parse_stations, solve_spline

TWO_PI = 2.0 * math.pi
SPLINE = "spline"  # wanted_law: the wanted lift through [[lift.stations]]
SPLINE_KEYS = ("stations", "continuity", "reference_rpm")  # [lift] keys of the wanted spline only
SHAPE_KEYS = ("height", "rise", "dwell", "return", "return_law")  # [lift] keys of a closed-form wanted law only
MIN_SPLINE_CONTINUITY = 3  # the jerk continuous: the cam's slope has no corner (a snap jump only warns)
DEFAULT_SPLINE_CONTINUITY = 4  # s^(4) continuous: the cam's acceleration has no step
REFUSED_ORDERS = 4  # a jump in s to its jerk is refused (a step or a corner in the cam); in the snap it warns
SNAP = 4
DERIVATIVE_NAMES = ("lift", "velocity", "acceleration", "jerk", "snap (fourth derivative)")
DERIVATIVE_UNITS = ("m", "m/s", "m/s**2", "m/s**3", "m/s**4")
CONSEQUENCES = ("a step in the cam", "a step in the cam", "a step in the cam",
                "a corner in the cam (its slope would jump)", "a step in the cam's acceleration")
JUMP_TOLERANCE = 1e-9  # relative to h / beta^k: rounding of the closed forms is ~1e-15
MIN_RAMP = math.radians(0.1)
RAMP_LAW = "cycloidal"  # zero slope and curvature at both ends of the take-up ramp


@dataclass(frozen=True)
class PolydyneOptions:
    wanted_law: str
    return_law: str
    design_rpm: float  # rev/min
    ramp: float  # rad
    spline: SplineOptions | None = None  # the wanted spline's stations (wanted_law = "spline")


@dataclass(frozen=True)
class Train:
    """What the polydyne formula takes from the scene (SI)."""

    mass: float  # M1, the mass the contact phase moves
    stiffness: float
    preload: float  # W(0) = preload + closing loads
    rate: float
    lash: float
    ratio: float

    @staticmethod
    def from_fields(valve, spring, loads, linkage, follower) -> "Train":
        mass = valve.oscillating_mass if valve.oscillating_mass is not None else valve.mass
        return Train(mass, linkage.stiffness, spring.preload + loads.closing_total, spring.rate, valve.lash, follower.ratio)


@dataclass(frozen=True)
class Joint:
    """Where the wanted lift's pieces meet: its derivatives per radian on both sides."""

    where: str  # for the messages
    before: np.ndarray  # s, s', ... per rad^k
    after: np.ndarray
    law: str  # the law whose end this is
    beta: float  # rad, its angle (scale of the jump tolerance)
    key: str  # the scene key that chose it
    angle: float  # rad since the event starts


@dataclass(frozen=True)
class WantedLift:
    """The valve lift wanted, in event coordinates x (rad since the rise starts): rise of `height`
    over `rise` with `rise_law`, dwell, return with `return_law`; 0 outside [0, end)."""

    height: float
    rise: float
    dwell: float
    ret: float
    rise_law: str
    return_law: str
    advice = "use a law continuous to the jerk, such as polynomial-4567"
    snap_advice = "use a law continuous to the snap, such as polynomial-56789"

    @property
    def end(self) -> float:
        return self.rise + self.dwell + self.ret

    @property
    def closed_form_laws(self) -> set[str]:
        return {self.rise_law, self.return_law}

    def marks(self) -> list[float]:
        """Event angles where a derivative may jump."""
        return [0.0, self.rise, self.rise + self.dwell, self.end]

    def dwell_start(self) -> float | None:
        """Event angle where the dwell after the rise starts (None without a dwell)."""
        return self.rise if self.dwell > 0.0 else None

    def derivatives(self, x, order: int = 5) -> np.ndarray:
        """(order + 1, N): s and its derivatives per radian at event angles x."""
        x = np.asarray(x, dtype=float).reshape(-1)
        out = np.zeros((order + 1, x.size))
        h = self.height
        rising = (x >= 0.0) & (x < self.rise)
        if np.any(rising):
            f = law_derivatives(self.rise_law, x[rising] / self.rise, order)
            out[:, rising] = h * f / np.array([self.rise**k for k in range(order + 1)])[:, None]
        top = (x >= self.rise) & (x - self.rise < self.dwell)
        out[0, top] = h
        x_ret = x - self.rise - self.dwell
        falling = (x_ret >= 0.0) & (x_ret < self.ret) & ~top & ~rising
        if np.any(falling):
            g = law_derivatives(self.return_law, x_ret[falling] / self.ret, order)
            scale = np.array([self.ret**k for k in range(order + 1)])[:, None]
            out[:, falling] = -h * g / scale
            out[0, falling] += h
        return out

    def joints(self, order: int = 3) -> list[Joint]:
        """The lift and its first `order` derivatives per radian on both sides of each joint of the
        event (order 4, the snap: the laws' closed-form higher derivatives)."""
        h = self.height
        powers = np.arange(order + 1)

        def side(law: str, u: float, beta: float) -> np.ndarray:
            return h * law_derivatives(law, np.full(1, u), order)[:, 0] / beta**powers

        rise0, rise1 = side(self.rise_law, 0.0, self.rise), side(self.rise_law, 1.0, self.rise)
        ret0, ret1 = -side(self.return_law, 0.0, self.ret), -side(self.return_law, 1.0, self.ret)
        ret0[0] += h
        ret1[0] += h
        rest, top = np.zeros(order + 1), np.zeros(order + 1)
        top[0] = h
        rise = (self.rise_law, self.rise, "lift.wanted_law")
        ret = (self.return_law, self.ret, "lift.return_law")
        out = [Joint("the start of the rise", rest, rise0, *rise, 0.0)]
        if self.dwell > 0.0:
            out += [Joint("the end of the rise", rise1, top, *rise, self.rise),
                    Joint("the start of the return", top, ret0, *ret, self.rise + self.dwell)]
        else:
            out += [Joint("the top, where the rise meets the return", rise1, ret0, *rise, self.rise)]
        out.append(Joint("the end of the return", ret1, rest, *ret, self.end))
        return out


@dataclass(frozen=True)
class SplineWanted:
    """The wanted valve lift as a spline (explorer.lift.spline) in event coordinates; 0 outside."""

    spline: SplineLift  # start 0: knots are event angles
    height: float  # largest lift (scale of the jump tolerance)
    rise_law = SPLINE
    return_law = SPLINE
    advice = ("give s, v, a and j = 0 at the first and last station and continuity = "
              f"{DEFAULT_SPLINE_CONTINUITY} or more")
    snap_advice = (f"give snap = 0 at the first and last station and continuity = {DEFAULT_SPLINE_CONTINUITY} or more, "
                   "or a closed-form wanted_law continuous to the snap, such as polynomial-56789")
    closed_form_laws = frozenset()  # the polynomials give every derivative exactly

    @property
    def end(self) -> float:
        return float(self.spline.knots[-1])

    def derivatives(self, x, order: int = 5) -> np.ndarray:
        return self.spline.local_derivatives(x, order)

    def marks(self) -> list[float]:
        return [float(k) for k in self.spline.knots]

    def dwell_start(self) -> None:
        return None  # a spline names no dwell

    def joints(self, order: int = 3) -> list[Joint]:
        """Every station: the derivatives to `order` from the polynomial on each side (0 off the
        event), evaluated at the segment's own end rather than near it."""
        knots, n = self.spline.knots, len(self.spline.coefficients)
        out = []
        for i in range(n + 1):
            before = self.spline.segment_derivatives(i - 1, 1.0, order) if i > 0 else np.zeros(order + 1)
            after = self.spline.segment_derivatives(i, 0.0, order) if i < n else np.zeros(order + 1)
            beta = float(min(knots[j + 1] - knots[j] for j in (i - 1, i) if 0 <= j < n))
            where = f"station {i} ({math.degrees(knots[i]):.6g} deg after the start)"
            out.append(Joint(where, before, after, SPLINE, beta, f"lift.stations[{i}]", float(knots[i])))
        return out


@dataclass(frozen=True)
class PolydyneLift:
    """The polydyne cam's follower lift (LiftCurve): ramp, event, ramp; base circle elsewhere."""

    wanted: WantedLift | SplineWanted
    train: Train
    start: float  # rad, cam angle where the valve starts to lift
    ramp: float  # rad
    design_omega: float  # rad/s

    @property
    def ramp_height(self) -> float:
        """S0 = lash + W(0)/k, valve-referred: the drive at which the seated valve lifts."""
        return self.train.lash + self.train.preload / self.train.stiffness

    def wanted_valve_lift(self, theta, order: int = 3) -> np.ndarray:
        """(order + 1, N): the wanted valve lift and its derivatives per radian at cam angles theta."""
        return self.wanted.derivatives(_wrap(np.asarray(theta, dtype=float) - self.start), order)

    def linkage_force(self, theta) -> np.ndarray:
        """Linkage force at the design speed, M1 w_d^2 s'' + W(s), while the valve is open (N)."""
        s = self.wanted_valve_lift(theta, 2)
        t = self.train
        return t.mass * self.design_omega**2 * s[2] + t.preload + t.rate * s[0]

    def derivatives(self, theta) -> np.ndarray:
        theta = np.asarray(theta, dtype=float)
        x = _wrap(theta.reshape(-1) - self.start + self.ramp)  # 0 where the opening ramp starts
        out = np.zeros((4, x.size))
        t, w = self.train, self.wanted
        s0 = self.ramp_height
        powers = np.array([self.ramp**k for k in range(4)])[:, None]
        up = x < self.ramp
        if np.any(up):
            out[:, up] = s0 * LAWS[RAMP_LAW](x[up] / self.ramp) / powers
        x_event = x - self.ramp
        event = (x_event >= 0.0) & (x_event < w.end)
        if np.any(event):
            s = w.derivatives(x_event[event], 5)
            c = t.mass * self.design_omega**2 / t.stiffness
            gain = 1.0 + t.rate / t.stiffness
            out[:, event] = gain * s[:4] + c * s[2:6]
            out[0, event] += t.lash + t.preload / t.stiffness
        x_down = x_event - w.end
        down = (x_down >= 0.0) & (x_down < self.ramp) & ~event & ~up
        if np.any(down):
            g = LAWS[RAMP_LAW](x_down[down] / self.ramp)
            out[:, down] = -s0 * g / powers
            out[0, down] += s0
        out /= t.ratio
        return out.reshape((4,) + theta.shape)

    def breakpoints(self) -> np.ndarray:
        w = self.wanted
        marks = [-self.ramp, *w.marks(), w.end + self.ramp]
        return np.array(sorted({(m + self.start) % TWO_PI for m in marks}))

    @property
    def warnings(self) -> tuple[str, ...]:
        """Steps in the cam's acceleration (a wanted lift whose snap jumps), for the run's warnings."""
        return acceleration_step_warnings(self)

    @property
    def report(self) -> dict:
        theta = self.start + np.linspace(0.0, self.wanted.end, 4001)
        force = self.linkage_force(theta)
        return {
            "polydyne_design_rpm": self.design_omega * 60.0 / TWO_PI,
            "polydyne_ramp_height_m": self.ramp_height / self.train.ratio,
            "polydyne_min_linkage_force_at_design_N": float(force.min()),
        }


def _wrap(x: np.ndarray) -> np.ndarray:
    return np.mod(x, TWO_PI)


def parse_polydyne_options(table, fields: dict[str, Any]) -> PolydyneOptions:
    """[lift] keys of the polydyne law, checked at load: the wanted law is smooth enough, the
    linkage pushes throughout at the design speed, and the train has what the formula needs."""
    file = table.file
    for section in ("valve", "spring", "linkage"):
        if fields.get(section) is None:
            raise InputError(file, section, f"missing section: lift.law = 'polydyne' designs the cam for the train's "
                             f"mass, spring and stiffness and needs [{section}]")
    if fields["loads"].friction != 0.0:
        raise InputError(file, "loads.friction", "a polydyne cam cannot compensate Coulomb friction: it flips where the "
                         "valve turns and would step the cam by 2 friction / stiffness; set it to 0 for the design")
    if fields["linkage"].damping != 0.0:
        raise InputError(file, "linkage.damping", "the polydyne formula has no damper term (the cam would follow from a "
                         "differential equation, not from the wanted lift); set it to 0 for the design")
    wanted_law = table.string("wanted_law", choices=(*LAWS, SPLINE))
    if table.has("design_rpm"):
        omega = table.quantity("design_rpm", "speed", positive=True)
    else:
        omega = fields["drive"].cam_omega
    spline = None
    if wanted_law == SPLINE:
        spline = _parse_wanted_spline(table, omega)
        return_law = SPLINE
    else:
        for name in SPLINE_KEYS:
            if table.has(name):
                raise table.error(name, "only with wanted_law = \"spline\" (the wanted lift through [[lift.stations]])")
        return_law = table.string("return_law", wanted_law, choices=tuple(LAWS)) if table.has("return_law") else wanted_law
    if not table.has("ramp"):
        raise table.error("ramp", "the polydyne cam needs a take-up ramp angle (lash plus the linkage's preload "
                          "deflection are taken up over it), such as \"15 deg\"")
    ramp = table.quantity("ramp", "angle", positive=True)
    if ramp < MIN_RAMP:
        raise table.error("ramp", f"must be at least {math.degrees(MIN_RAMP):g} deg")
    spec = fields["lift"]
    event = spline.stations[-1].angle if spline is not None else spec.rise + spec.dwell + spec.ret
    total = event + 2.0 * ramp
    if total > TWO_PI * (1.0 + 1e-12):
        what = "the stations' event" if spline is not None else "rise + dwell + return"
        raise table.error("ramp", f"two ramps + {what} = {math.degrees(total):.6g} deg exceed 360 deg")
    options = PolydyneOptions(wanted_law, return_law, omega * 60.0 / TWO_PI, ramp, spline)
    lift = polydyne_lift(spec, options, fields["valve"], fields["spring"], fields["loads"], fields["linkage"], fields["follower"])
    check_polydyne(lift, file, fields["follower"])
    return options


def _parse_wanted_spline(table, design_omega: float) -> SplineOptions:
    """[[lift.stations]] of the wanted valve lift; values in time units at reference_rpm (default
    the design speed). The continuity asked for must reach the snap (module doc)."""
    for name in SHAPE_KEYS:
        if table.has(name):
            raise table.error(name, "not used with wanted_law = \"spline\" (the stations give the wanted lift); remove it")
    continuity = int(table.number("continuity", DEFAULT_SPLINE_CONTINUITY, integer=True, minimum=0, maximum=MAX_CONTINUITY))
    if continuity < MIN_SPLINE_CONTINUITY:
        raise table.error("continuity", f"'spline' with continuity = {continuity} is too rough for a polydyne cam: the "
                          f"cam lift S = s + (M w^2 s'' + W)/k needs the wanted valve {DERIVATIVE_NAMES[continuity + 1]} "
                          f"continuous at every station, which continuity = {continuity} does not ask for, and a jump "
                          f"makes {CONSEQUENCES[continuity + 1]}; set continuity = {DEFAULT_SPLINE_CONTINUITY} or more")
    omega = table.quantity("reference_rpm", "speed", positive=True) if table.has("reference_rpm") else design_omega
    options, lift = parse_stations(table, continuity, omega)
    for i, st in enumerate(options.stations):
        if any(st.free):
            name = ("s", "v", "a", "j")[st.free.index(True)]
            raise InputError(table.file, f"{table.key('stations')}[{i}].{name}", "a polydyne's wanted spline has no "
                             "\"free\" values: explorer design optimises a law = \"spline\" lift; design the wanted lift "
                             "there (continuity = 4) and give its stations here")
    check_spline_shape(table, lift)
    return options


def _jumps(jump: float, height: float, beta: float, k: int) -> bool:
    """Whether a derivative k of the wanted lift jumps beyond rounding (relative to h / beta^k)."""
    return abs(jump) > JUMP_TOLERANCE * height / beta**k


@dataclass(frozen=True)
class AccelerationStep:
    """Where the wanted lift's snap jumps, the step it makes in the polydyne cam's acceleration."""

    joint: Joint
    cam_angle: float  # rad, in [0, 2 pi)
    jump: float  # m/s^2: the cam's acceleration, valve-referred, at the design speed (after - before)


def acceleration_steps(lift: PolydyneLift) -> list[AccelerationStep]:
    """The joints where the wanted lift's snap jumps (its derivatives to the jerk are continuous:
    check_polydyne refuses the rest). The cam's acceleration is
    L_theta_theta = [s_theta_theta (1 + rate/k) + (M1 w_d^2/k) s^(4)] / ratio, so a snap jump ds4 (per
    rad^4) steps the valve-referred cam acceleration by (M1 w_d^2/k) ds4 w_d^2 m/s^2 at the design
    speed. The same rule for every wanted lift: its own derivatives on both sides of each joint
    (a closed form's, a spline's polynomials)."""
    t, w, omega = lift.train, lift.wanted, lift.design_omega
    out = []
    for joint in w.joints(SNAP):
        jump = joint.after[SNAP] - joint.before[SNAP]
        if _jumps(jump, w.height, joint.beta, SNAP):
            step = t.mass * omega**2 / t.stiffness * jump * omega**2
            out.append(AccelerationStep(joint, float((lift.start + joint.angle) % TWO_PI), float(step)))
    return out


def acceleration_step_warnings(lift: PolydyneLift) -> tuple[str, ...]:
    """One line naming every step in the polydyne cam's acceleration (acceleration_steps): where,
    by how much and of which law; none for a wanted lift continuous to its snap."""
    steps = acceleration_steps(lift)
    if not steps:
        return ()
    rpm = lift.design_omega * 60.0 / TWO_PI
    where = ", ".join(f"{s.jump:+.4g} m/s**2 at cam angle {math.degrees(s.cam_angle):.4g} deg ({s.joint.where}, "
                      f"{s.joint.law})" for s in steps)
    return (f"polydyne: the wanted lift's snap (fourth derivative) jumps, so the cam's acceleration steps "
            f"(valve-referred, at the design speed {rpm:g} rpm) and its jerk is unbounded there: by {where}; "
            f"{lift.wanted.snap_advice}",)


def check_polydyne(lift: PolydyneLift, file: str, follower=None) -> None:
    """InputError when the wanted lift is too rough for a cam, the linkage would have to pull, or
    the cam fails the validity checks every cam passes (explorer.lift.validity; for `follower`)."""
    w = lift.wanted
    omega = lift.design_omega
    for joint in w.joints(REFUSED_ORDERS - 1):
        for k in range(REFUSED_ORDERS):
            jump = joint.after[k] - joint.before[k]
            if _jumps(jump, w.height, joint.beta, k):
                raise InputError(file, joint.key, f"{echo(joint.law)} is too rough for a polydyne cam: the cam lift "
                                 f"S = s + (M w^2 s'' + W)/k needs the wanted valve {DERIVATIVE_NAMES[k]} continuous, and it "
                                 f"jumps by {jump * omega**k:.4g} {DERIVATIVE_UNITS[k]} at {joint.where} (at "
                                 f"{omega * 60 / TWO_PI:g} rpm), which makes {CONSEQUENCES[k]}; {w.advice}")
    for name in sorted(w.closed_form_laws):
        if name not in HIGH_ORDER_LAWS:
            raise InputError(file, "lift.wanted_law", f"{echo(name)} has no closed-form fourth and fifth derivative, which "
                             "the polydyne cam's acceleration and jerk need")
    theta = lift.start + np.linspace(0.0, w.end, 20001)[1:-1]
    force = lift.linkage_force(theta)
    i = int(np.argmin(force))
    if not force[i] > 0.0:
        raise InputError(file, "lift.design_rpm", f"at {omega * 60 / TWO_PI:g} rpm the linkage would have to pull: the "
                         f"force M w^2 s'' + W(s) falls to {force[i]:.4g} N at cam angle "
                         f"{math.degrees(theta[i]) % 360:.3f} deg; more spring preload or rate, or a lower design speed")
    fault = lift_fault(lift, follower)  # the checks every cam passes, entered or computed
    if fault is not None:
        raise impossible_cam(lift, follower, fault, file)


# the stiffness and design speed that make a polydyne cam valid are found to this ratio (bisection)
ADVICE_RATIO = 1.01
ADVICE_ITERATIONS = 80  # bound: log2(ln(1e15) / ln(1.01)) ~ 12 halvings are needed


def impossible_cam(lift: PolydyneLift, follower, fault, file: str) -> InputError:
    """The one line for a polydyne cam that fails the validity checks: the cam adds the linkage's
    deflection (M1 w_d^2 s'' + W(s))/k to the wanted lift, so what made it impossible is the
    linkage stiffness at this design speed -- unless even a rigid linkage fails (then the wanted
    lift itself is no cam for this follower). Says at which stiffness, and up to which design speed
    (when the cam at rest is valid), the cam passes, found by bisection on the same check."""
    from dataclasses import replace

    t = lift.train
    rpm = lift.design_omega * 60.0 / TWO_PI

    def fault_with(stiffness: float = t.stiffness, omega: float = lift.design_omega):
        return lift_fault(replace(lift, train=replace(t, stiffness=stiffness), design_omega=omega), follower)

    def valid(**changes) -> bool:
        return fault_with(**changes) is None

    k_max = RANGES["stiffness"][1]
    rigid = fault_with(stiffness=k_max)
    if rigid is not None:
        return computed_error(rigid, file, "lift", f"the polydyne cam even with a rigid linkage ({k_max:g} N/m: the "
                              "wanted lift plus the lash)", f"change the wanted lift or the follower: {rigid.advice.strip('()')}")
    lo, hi = t.stiffness, k_max  # fails, passes
    for _ in range(ADVICE_ITERATIONS):
        if hi / lo <= ADVICE_RATIO:
            break
        mid = math.sqrt(lo * hi)
        lo, hi = (lo, mid) if valid(stiffness=mid) else (mid, hi)
    theta = lift.start + np.linspace(0.0, lift.wanted.end, 4001)
    deflection = float(np.max(lift.linkage_force(theta))) / t.stiffness
    remedy = (f"the linkage deflection (M w^2 s'' + W)/k it adds to the wanted {_length(lift.wanted.height)} "
              f"lift reaches {_length(deflection)}: stiffen the linkage (at {_round(hi, math.ceil):.3g} N/m the cam passes)")
    if valid(omega=0.0):
        slow, fast = 0.0, lift.design_omega  # passes, fails
        for _ in range(ADVICE_ITERATIONS):
            if fast - slow <= (ADVICE_RATIO - 1.0) * fast:
                break
            mid = 0.5 * (slow + fast)
            slow, fast = (mid, fast) if valid(omega=mid) else (slow, mid)
        remedy += f" or lower lift.design_rpm (at {_round(slow * 60.0 / TWO_PI, math.floor, 4):.4g} rpm it passes)"
    else:
        remedy += (f"; no lower design speed helps: the cam fails at rest too, where its take-up ramp rises "
                   f"lash + W(0)/k = {_length(lift.ramp_height / t.ratio)} over lift.ramp = {math.degrees(lift.ramp):.4g} deg")
    return computed_error(fault, file, "linkage.stiffness", f"the polydyne cam for linkage.stiffness {t.stiffness:.4g} N/m "
                          f"at the design speed {rpm:g} rpm", remedy)


def _length(x: float) -> str:
    return f"{x * 1e3:.4g} mm" if abs(x) < 1.0 else f"{x:.4g} m"


def _round(x: float, direction, digits: int = 3) -> float:
    """x rounded to `digits` significant digits in `direction` (math.ceil for a stiffness to quote
    that still passes, math.floor for a speed)."""
    step = 10.0 ** (math.floor(math.log10(x)) - digits + 1)
    return direction(x / step) * step


def polydyne_lift(spec, options: PolydyneOptions, valve, spring, loads, linkage, follower) -> PolydyneLift:
    if options.spline is not None:
        o = options.spline
        spline = solve_spline(o.stations, o.continuity, 0.0)
        height = float(spline.local_derivatives(np.linspace(0.0, spline.knots[-1], 2001), 0)[0].max())
        wanted = SplineWanted(spline, height)
    else:
        wanted = WantedLift(spec.height, spec.rise, spec.dwell, spec.ret, options.wanted_law, options.return_law)
    train = Train.from_fields(valve, spring, loads, linkage, follower)
    return PolydyneLift(wanted, train, spec.start, options.ramp, options.design_rpm * TWO_PI / 60.0)


def build_polydyne_lift(scene) -> PolydyneLift:
    """The scene's polydyne cam, from its current train (a changed stiffness or spring redesigns it)."""
    lift = polydyne_lift(scene.lift, scene.lift.options, scene.valve, scene.spring, scene.loads, scene.linkage, scene.follower)
    check_polydyne(lift, scene.source, scene.follower)
    return lift


# ---------------------------------------------------------------------------------------------
# Off the design speed


SERIES_LAM = 4.0  # below it _polynomial_fourier sums the Taylor series (its terms stay below e^4 ~ 55)
SERIES_TERMS = 80  # bound: 4^n / n! < 1e-18 from n ~ 40


def _polynomial_fourier(coefficients, lam: float) -> complex:
    """Integral over [0, 1] of p(u) exp(i lam u) for the polynomial p (ascending coefficients), in
    closed form: sum_k (-1)^k [p^(k)(u) e^(i lam u)]_0^1 / (i lam)^(k+1).

    That sum cancels for small lam (its terms grow as p^(k)/lam^(k+1): 5-6-7-8-9's acceleration at
    lam = 0.7 loses 8 digits), so there the Taylor series of the exponential is summed instead,
    sum_n (i lam)^n / n! integral_0^1 p(u) u^n du, whose terms stay below e^|lam| times the integral's
    size (at lam <= SERIES_LAM: ~2 digits)."""
    if abs(lam) <= SERIES_LAM:
        moments = lambda n: sum(c / (m + n + 1) for m, c in enumerate(coefficients))  # noqa: E731
        total, term = 0.0 + 0.0j, 1.0 + 0.0j  # term = (i lam)^n / n!
        for n in range(SERIES_TERMS):
            total += term * moments(n)
            term *= 1j * lam / (n + 1)
            if abs(term) < 1e-18:  # moments are at most max|p|: the rest is below rounding
                break
        return complex(total)
    p = np.polynomial.Polynomial(coefficients)
    total = 0.0 + 0.0j
    k = 0
    while True:
        term = (p(1.0) * np.exp(1j * lam) - p(0.0)) / (1j * lam) ** (k + 1)
        total += (-1) ** k * term
        if p.degree() == 0:
            break
        p = p.deriv()
        k += 1
    return complex(total)


RISE_POLYNOMIALS = {"polynomial-345": (0, 0, 0, 10, -15, 6), "polynomial-4567": (0, 0, 0, 0, 35, -84, 70, -20),
                    "polynomial-56789": POLYNOMIAL_56789}


def residual_amplitude(lift: PolydyneLift, rpm: float) -> float:
    """Closed form (linear case: the valve stays in contact, no damping) of the valve's vibration
    amplitude about the wanted lift during the dwell after a polynomial rise, at `rpm`:

        A = |w_d^2 - w^2| h / (beta w wn) |integral_0^1 f''(u) exp(i lam u) du|,  lam = wn beta / w

    from Duhamel's integral of e'' + wn^2 e = (w_d^2 - w^2) s_theta_theta(w t), e(0) = e'(0) = 0."""
    w = lift.wanted
    if w.rise_law not in RISE_POLYNOMIALS:
        raise ValueError("closed form only for polynomial rises")
    t = lift.train
    omega = rpm * TWO_PI / 60.0
    wn = math.sqrt((t.stiffness + t.rate) / t.mass)
    lam = wn * w.rise / omega
    accel = np.polynomial.Polynomial(RISE_POLYNOMIALS[w.rise_law]).deriv(2).coef
    integral = _polynomial_fourier(accel, lam)
    return abs(lift.design_omega**2 - omega**2) * w.height / (w.rise * omega * wn) * abs(integral)
