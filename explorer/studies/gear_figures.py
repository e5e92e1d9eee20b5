"""Summary figures and tables for the seeds' other gears (matplotlib, Agg; nothing interactive).

    python -m explorer.studies.gear_figures OUTDIR [--scenes DIR]

writes
  rocking_cam_swings.png   seed 004: equal eccentric arcs -> unequal swings of the rocking cam,
                           with the valve's s, v, p mirrored about the eccentric's dead centre
  trip_buffers.png / .md   the trip gear's valve closed with no buffer, an air and an oil dashpot:
                           lift over time after the release, seating velocity and closing time
"""

from __future__ import annotations

import argparse
import io
import math
from dataclasses import replace
from pathlib import Path

import numpy as np

from ..core.outputs import write_output
from ..effects.lift import build_lift
from ..effects.pipeline import simulate
from ..gears.rocking import swing_increments
from ..scene.builtin import scenes_dir
from ..scene.scene import load_scene

TWO_PI = 2.0 * math.pi


def rocking_cam_figure(scene, path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    lift = build_lift(scene)
    gear = lift.gear
    closed = [c for c in gear.drive.dead_centres() if abs(np.angle(np.exp(1j * (c - gear.dead_centre)))) > 1e-9][0]
    start = gear.dead_centre - float(np.mod(gear.dead_centre - closed, TWO_PI))
    theta, inc = swing_increments(gear, start, gear.dead_centre, 12)
    chi = np.degrees(np.unwrap(gear.drive.angle(theta)))
    w = scene.drive.omega
    u = np.linspace(-math.pi, math.pi, 1441)
    d = lift.derivatives(np.mod(gear.dead_centre + u, TWO_PI))
    lash = scene.valve.lash if scene.valve else 0.0

    fig = plt.figure(figsize=(12, 5.2))
    grid = fig.add_gridspec(3, 2)
    ax = fig.add_subplot(grid[:, 0])
    mid = 0.5 * (theta[:-1] + theta[1:])
    ax.bar(np.degrees(mid - gear.dead_centre), np.degrees(np.abs(inc)), width=np.degrees(theta[1] - theta[0]) * 0.8,
           color="#4c72b0")
    ax.set_xlabel("eccentric angle from the open dead centre, deg (12 equal arcs)")
    ax.set_ylabel("swing of the rocking cam per arc, deg")
    ax.set_title("Equal eccentric arcs, unequal swings (seed 004)")
    twin = ax.twinx()
    twin.plot(np.degrees(theta - gear.dead_centre), chi - chi[0], "k.-", lw=1)
    twin.set_ylabel("rocking angle from the closed end, deg")
    x = np.degrees(u)
    rows = (("valve lift s, mm", 1e3 * np.maximum(d[0] - lash, 0.0)), ("v, m/s (odd)", w * d[1]),
            ("p, m/s^2 (even)", w**2 * d[2]))
    for k, (label, y) in enumerate(rows):
        ax = fig.add_subplot(grid[k, 1])
        ax.plot(x, y, color=("#4c72b0", "#dd8452", "#55a868")[k])
        ax.axvline(0.0, color="k", lw=0.8)
        ax.set_ylabel(label, fontsize=8)
        if k == 0:
            ax.set_title("One contour opens and closes: mirror images")
        if k == 2:
            ax.set_xlabel("shaft angle from the eccentric's open dead centre, deg")
        else:
            ax.set_xticklabels([])
    fig.tight_layout()
    path = Path(path)
    _save_png(fig, path)
    plt.close(fig)
    return path


def buffer_rows(scene) -> list[dict]:
    return list(simulate(scene).summary["gear"]["buffer_comparison"])


def buffer_table_markdown(rows) -> str:
    lines = ["| buffer | closing time, ms | seating velocity, m/s | largest buffer force, N | rebounds |",
             "|---|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r['buffer']} | {1e3 * r['closing_time_s']:.2f} | {r['seating_velocity_m_s']:.3f} | "
                     f"{r['max_buffer_force_N']:.0f} | {r['rebounds']} |")
    return "\n".join(lines) + "\n"


def trip_buffers_figure(scene, path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt


    from ..gears.trip_gear import make_buffer  # heavy (scipy): imported on use
    from ..gears.trip import simulate_closing  # heavy (scipy): imported on use

    lift = build_lift(scene)
    spec = scene.gear
    s0 = float(lift.latch.derivatives(np.array([lift.trip_angle]))[0, 0] - lift.overtravel)
    v0 = float(scene.omega * lift.latch.derivatives(np.array([lift.trip_angle]))[1, 0])
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for name in ("none", "air", "oil"):
        if name != "none" and f"{name}_dashpot" not in spec.parts:
            continue
        buffer = make_buffer(spec, name)
        density = None
        if name == "air":  # the pocket as the latched phase leaves it at the trip (as the gear effect)
            density = lift.density_at_trip(buffer)
        sol = simulate_closing(replace(lift.closing.model, buffer=buffer), s0, v0, 1.0, density=density)
        t = np.linspace(0.0, sol.seat_time, 800)
        ax.plot(1e3 * t, 1e3 * sol.state(t)["s"],
                label=f"{name}: {1e3 * sol.seat_time:.1f} ms, seats at {abs(sol.seat_velocity):.2f} m/s")
    ax.set_xlabel("time after the release, ms")
    ax.set_ylabel("valve lift, mm")
    ax.set_title("Trip gear: closing with no buffer, air and oil dashpot")
    ax.legend(fontsize=8)
    fig.tight_layout()
    path = Path(path)
    _save_png(fig, path)
    plt.close(fig)
    return path


def _save_png(fig, path: Path) -> None:
    """By explorer.core.outputs' rules (temporary and rename, mode kept), like every other output."""

    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110)
    write_output(path, buffer.getvalue())


def main(argv=None) -> int:

    parser = argparse.ArgumentParser(prog="python -m explorer.studies.gear_figures", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("outdir")
    parser.add_argument("--scenes", default=None, help="directory with rocking_cam.toml and trip_gear_dashpot.toml")
    args = parser.parse_args(argv)
    out = Path(args.outdir)
    out.mkdir(parents=True, exist_ok=True)
    where = Path(args.scenes) if args.scenes else scenes_dir()
    rocking = load_scene(where / "rocking_cam.toml")
    trip = load_scene(where / "trip_gear_dashpot.toml")
    print(rocking_cam_figure(rocking, out / "rocking_cam_swings.png"))
    print(trip_buffers_figure(trip, out / "trip_buffers.png"))
    table = buffer_table_markdown(buffer_rows(trip))
    write_output(out / "trip_buffers.md", table)
    print(table, end="")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
