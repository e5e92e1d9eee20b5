"""Statics of a one-degree-of-freedom valve train between the cam and the valve, with Coulomb
friction at the sliding contacts; the same for the tappet, the finger, the rocker and the pushrod
train.

The follower (tappet; finger; rocker with lifter and pushrod) moves with one coordinate q (a lift
or an arm angle). Its joints (pivot, bore, ball ends) are frictionless, so only two external
forces do work on it: the cam's, at the cam contact X_c,
    F_c = N (n + mu_c sigma_c t_c),      sigma_c = sign(sliding at the cam),
and the valve's, at the tip contact X_t (the valve pushes back along its axis u with the valve
force F of the forces effect, and drags the pad along the tip with mu_t F),
    F_t = -F u + mu_t F sigma_t t_t,    sigma_t = sign(sliding at the tip).
With V_c, V_t the follower's material velocities at the contacts per unit dq (the mechanism's
Jacobians), virtual work gives the cam's normal force in one line:
    N (n + mu_c sigma_c t_c) . V_c = F (u - mu_t sigma_t t_t) . V_t,
and the camshaft torque is the moment of F_c about the camshaft, T = X_c x F_c. Nothing here
uses the kinematic ratio ds/dtheta, so the tests can check the power balance
    T omega = F v + mu_c N |v_slide,c| + mu_t F |v_slide,t|
exactly (friction turns the difference into heat), and T omega = F v without friction.

Friction drags each surface the way the other surface slides relative to it (sigma is the sign of
the sliding velocity of the first body, the cam or the valve, relative to the second). A sample
with (n + mu_c sigma_c t_c) . V_c <= 0 while F > 0 cannot be driven (self-locking): N = inf there,
and the friction and the torque are their limits (+-inf; a roller's friction 0), never NaN.
A valve force F <= 0 (the valve would have to be pulled) is passed through without friction.
Rollers roll: no sliding friction at their contact (mu_c = 0; the bearing's drag is not modelled).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class ContactForces:
    """Per sample. Forces of the cam (resp. the valve) on the follower; torque the camshaft supplies."""

    normal: np.ndarray  # N, cam on follower along the contact normal (inf: self-locked)
    friction: np.ndarray  # N, cam on follower along the cam contact's tangent (CamSurface.tangent)
    torque: np.ndarray  # N m, camshaft torque (> 0: the shaft drives the cam)
    tip_normal: np.ndarray  # N, valve on follower along -u (the valve force itself)
    tip_friction: np.ndarray  # N, valve on follower along the tip's tangent


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("ij,ij->i", a, b)


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]


def cam_forces(valve_force, *, contact: np.ndarray, normal: np.ndarray, tangent: np.ndarray,
               cam_jacobian: np.ndarray, cam_sliding: np.ndarray, cam_friction: float,
               valve_axis: np.ndarray, valve_jacobian: np.ndarray, tip_tangent: np.ndarray | None = None,
               tip_sliding: np.ndarray | None = None, tip_friction: float = 0.0) -> ContactForces:
    """The module's statics. Arrays are (N, 2) for vectors, (N,) for scalars: contact point,
    normal (cam -> follower), tangent at the cam contact; V_c = cam_jacobian; the valve axis u
    (opening direction) and V_t = valve_jacobian (u . V_t = ds/dq); the tip's tangent and
    sliding, if the valve is pushed through a sliding pad."""
    f = np.broadcast_to(np.asarray(valve_force, dtype=float), (len(contact),))
    # the coordinate's direction that opens the valve: both sides of the balance turned to it
    way = np.where(_dot(valve_axis, valve_jacobian) < 0.0, -1.0, 1.0)[:, None]
    cam_jacobian = way * cam_jacobian
    valve_jacobian = way * valve_jacobian
    # sgn(0) = 0: at exactly zero sliding (a scrub's reversal) Coulomb's friction is set-valued,
    # |F_t| <= mu N; the statics take the frictionless balance, between the two sides' (finite:
    # nothing divides by the sliding velocity; tests/test_train_statics.py)
    sigma_c = np.sign(cam_sliding)
    drive = _dot(normal, cam_jacobian) + cam_friction * sigma_c * _dot(tangent, cam_jacobian)
    free_drive = _dot(normal, cam_jacobian)
    opening = _dot(valve_axis, valve_jacobian)
    resist = opening.copy()
    sigma_t = np.zeros_like(opening)
    if tip_tangent is not None and tip_friction:
        sigma_t = np.sign(tip_sliding)
        resist = resist - tip_friction * sigma_t * _dot(tip_tangent, valve_jacobian)
    loaded = f > 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        n_loaded = np.where(drive > 0.0, f * resist / drive, np.inf)
        n_free = f * opening / free_drive
    n = np.where(loaded, n_loaded, np.where(f < 0.0, n_free, 0.0))
    coefficient = np.where(loaded, cam_friction, 0.0) * sigma_c  # friction per newton of normal force
    finite = np.isfinite(n)
    # a self-locked sample (N infinite): the friction and the torque are the limits N -> inf, never the
    # NaN of 0 x inf (a roller's zero friction) or of inf - inf between the force's components
    with np.errstate(invalid="ignore"):
        friction = np.where(coefficient == 0.0, 0.0, coefficient * n)
        force = np.where(finite[:, None], n[:, None] * normal + friction[:, None] * tangent, 0.0)
        arm = _cross(contact, normal) + coefficient * _cross(contact, tangent)  # torque per newton of N
        torque = np.where(finite, _cross(contact, force), np.where(arm == 0.0, n, n * arm))
    tip_fr = np.where(loaded, tip_friction, 0.0) * sigma_t * f
    return ContactForces(normal=n, friction=friction, torque=torque, tip_normal=f.copy(), tip_friction=tip_fr)


def point_velocity_about(pivot, points: np.ndarray) -> np.ndarray:
    """Velocity of body points turning about `pivot` at unit angular speed: J (X - pivot)."""
    return np.column_stack([-(points[:, 1] - pivot[1]), points[:, 0] - pivot[0]])
