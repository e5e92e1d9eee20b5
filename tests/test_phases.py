"""The phase-transition rules written once (explorer/dynamics/phases.py): the event tables against
the physical quantities they name, the exact solver's rows against the same, and the seat rules
against kinematics (energy, the rise of a rebound)."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from explorer.dynamics import phases
from explorer.dynamics.exact_events import event_of
from explorer.dynamics.phases import CONTACT, FLIGHT

finite = st.floats(-1e-2, 1e-2, allow_nan=False)


def _quantity(name: str, S, S1, s, v, k, c, lash, s_star):
    """The quantities of phases.EventRule, from their definitions."""
    if name == "gap":
        return S - lash - (s_star if s_star is not None else s)
    if name == "force":
        return k * (S - lash - s) + c * (S1 - v)
    if name == "push":
        return k * (S - lash - s_star) + c * S1
    return {"lift": s, "velocity": v}[name]


def _rule_value(rule, *state):
    comps = [sign * (_quantity(q, *state) - thr) for q, sign, thr in rule.comps]
    return {"one": comps[0] if len(comps) == 1 else None, "min": min(comps), "max": max(comps)}[rule.comb]


def _row_value(row, S, S1, s, v):
    aP, bP, const, l0, l1 = row
    return aP * S + bP * S1 + const + l0 * s + l1 * v


@settings(max_examples=300, deadline=None)
@given(S=finite, S1=st.floats(-5, 5), s=finite, v=st.floats(-5, 5), k=st.floats(1e4, 1e8), c=st.sampled_from([0.0, 50.0]),
       lash=st.floats(0, 1e-3), phase=st.sampled_from([CONTACT, FLIGHT]), sigma=st.sampled_from([1.0, -1.0]))
def test_moving_rows_have_the_sign_of_the_rule(S, S1, s, v, k, c, lash, phase, sigma):
    """Each exact row (force units: a gap is k gap) is > 0 exactly where the rule's component is,
    away from the rounding of its terms; a force row equals the force."""
    for rule in phases.moving_events(phase, c > 0.0, True, sigma):
        event = event_of(rule, k, c, lash)
        assert event.kind == rule.kind and event.comb == rule.comb
        for (q, sign, thr), row in zip(rule.comps, event.comps):
            want = sign * (_quantity(q, S, S1, s, v, k, c, lash, None) - thr)
            got = _row_value(row, S, S1, s, v)
            scale = k * (abs(S) + lash + abs(s)) + c * (abs(S1) + abs(v)) + abs(s) + abs(v)
            if abs(got) > 1e-12 * scale:
                assert (got > 0.0) == (want > 0.0)
            if q == "force":
                assert got == pytest.approx(want, abs=1e-12 * scale)


@settings(max_examples=300, deadline=None)
@given(S=finite, S1=st.floats(-5, 5), s_star=st.sampled_from([0.0, 2e-3]), k=st.floats(1e4, 1e8),
       c=st.sampled_from([0.0, 50.0]), lash=st.floats(0, 1e-3), W0=st.floats(0, 500), rate=st.floats(0, 5e4),
       R=st.floats(0, 300))
def test_rest_rows_fire_where_the_push_leaves_the_friction_band(S, S1, s_star, k, c, lash, W0, rate, R):
    """"up": the push beats W0 + rate s* + R with the gap closed; "down": it falls below
    W0 + rate s* - R (or the gap opens); the exact rows agree with the rule away from rounding."""
    rules = {r.kind: r for r in phases.rest_events(s_star, W0, rate, R, gap_check=True)}
    push = k * (S - lash - s_star) + c * S1
    gap = S - lash - s_star
    assert (_rule_value(rules["up"], S, S1, s_star, 0.0, k, c, lash, s_star) > 0.0) == (
        push - (W0 + rate * s_star + R) > 0.0 and gap > 0.0)
    assert ("down" in rules) == (s_star > 0.0 and W0 + rate * s_star - R > 0.0)
    for rule in phases.rest_events(s_star, W0, rate, R, gap_check=c > 0.0):
        event = event_of(rule, k, c, lash, s_star)
        for (q, sign, thr), row in zip(rule.comps, event.comps):
            want = sign * (_quantity(q, S, S1, s_star, 0.0, k, c, lash, s_star) - thr)
            got = _row_value(row, S, S1, 0.0, 0.0)
            scale = k * (abs(S) + lash + s_star) + c * abs(S1) + W0 + rate * s_star + R
            if abs(got) > 1e-12 * scale:
                assert (got > 0.0) == (want > 0.0)


def test_event_tables():
    """Contact ends by separation, flight by re-contact (with damping: where the linkage would
    push, min(gap, force)); both at the seat; with friction at velocity zero against sigma."""
    contact = phases.moving_events(CONTACT, False, False, 1.0)
    assert [r.kind for r in contact] == ["separation", "seat"]
    assert contact[0].comps == (("force", -1.0, 0.0),) and contact[1].comps == (("lift", -1.0, 0.0),)
    damped = phases.moving_events(FLIGHT, True, True, -1.0)
    assert [r.kind for r in damped] == ["re-contact", "seat", "velocity-zero"]
    assert damped[0].comb == "min" and {q for q, _, _ in damped[0].comps} == {"gap", "force"}
    assert damped[2].comps == (("velocity", 1.0, 0.0),)  # moving down (sigma -1): fires where v > 0
    assert [r.kind for r in phases.rest_events(0.0, 100.0, 1e3, 10.0, gap_check=False)] == ["up"]


@given(v0=st.floats(-10.0, -0.01), acc=st.floats(-1e4, 1e4), tau=st.floats(1e-9, 1e-5))
def test_seat_speed_is_the_speed_at_the_seat_by_kinematics(v0, acc, tau):
    """Landing at s = 0 with v0 under a constant acceleration, found tau later at s < 0: the
    speed it gives back is v0 (the parabola s = v0 tau + acc tau^2 / 2)."""
    s = v0 * tau + 0.5 * acc * tau * tau
    v = v0 + acc * tau
    if s >= 0.0:
        return
    assert phases.seat_speed(v, s, acc) == pytest.approx(v0, rel=1e-9, abs=1e-12)


def test_rebound_rest_speed_rises_rest_height():
    """A rebound at exactly that speed rises rest_height against (W0 + R) / M; none without load."""
    W0, R, M, h = 300.0, 20.0, 0.2, 1e-9
    v = phases.rebound_rest_speed(W0, R, M, h)
    assert v * v / (2.0 * (W0 + R) / M) == pytest.approx(h, rel=1e-12)
    assert phases.rebound_rest_speed(0.0, 0.0, M, h) == 0.0


def test_touching_needs_the_gap_closed_and_the_linkage_pushing():
    k, c, lash = 1e6, 100.0, 1e-4
    assert phases.touching(2e-4, 0.0, k, c, lash, 0.0)
    assert not phases.touching(0.5e-4, 0.0, k, c, lash, 0.0)  # gap open
    # gap closed by 1 um (k x = 1 N) but the dashpot pulls at 0.1 m/s (10 N): not pushing
    assert not phases.touching(lash + 1e-6, 0.0, k, c, lash, 0.0, v=0.1)
    assert phases.touching(lash + 1e-6, 0.0, k, c, lash, 0.0, v=-0.1)
    assert math.isclose(k * 1e-6, 1.0)
