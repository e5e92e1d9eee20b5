"""The elastic seat's figures of the scenes with a Kelvin-Voigt seat (docs/theory/spring-chain.md,
train-dynamics.md: where the seat lets go).

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/seat_release.py [SCENE ...]

Per scene (default spring_surge, pushrod_train): the least force of the engaged seat (valve_phase
0) with its cam angle and the valve's lift and velocity there, the first lift-off's angle and the
lift-off delay, the seat impacts (count, the first three speeds), the largest bounce and the least
valve acceleration.
Public API only (simulate, its columns and events, the sweep row's elastic figures), so the same
command gives the figures of any commit.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from explorer import load_scene, simulate  # noqa: E402
from explorer.effects.elastic_events import elastic_row  # noqa: E402


def figures(name: str) -> list[str]:
    result = simulate(load_scene(ROOT / "assets" / "scenes" / f"{name}.toml"))
    c = result.columns
    f = np.where(np.asarray(c["valve_phase"]) == 0, np.asarray(c["seat_force_N"]), np.inf)  # engaged
    i = int(np.argmin(f))
    elastic = [e for e in result.events if e.effect == "elastic"]
    seats = [e for e in elastic if e.kind == "seat"]
    offs = [e for e in elastic if e.kind == "lift-off"]
    row = elastic_row(result)
    speeds = ", ".join(f"{e.values['velocity_m_s']:.4f}" for e in seats[:3])
    return [
        f"{name}",
        f"  least engaged seat force {f[i]:6.1f} N at {c['cam_angle_deg'][i]:.1f} deg "
        f"(s = {c['valve_lift_m'][i] * 1e6:.3f} um, v = {c['valve_velocity_m_s'][i]:+.4f} m/s)",
        f"  first lift-off        {offs[0].cam_angle_deg:9.3f} deg, delay after the take-up "
        f"{row['lift_off_delay_s'] * 1e6:.1f} us" if offs else "  no lift-off",
        f"  seat impacts          {len(seats):5d}, first three at {speeds} m/s",
        f"  largest bounce        {row['largest_bounce_m'] * 1e6:9.2f} um",
        f"  least valve accel     {float(np.min(c['valve_accel_m_s2'])):9.0f} m/s^2",
    ]


if __name__ == "__main__":
    for scene in sys.argv[1:] or ["spring_surge", "pushrod_train"]:
        print("\n".join(figures(scene)))
