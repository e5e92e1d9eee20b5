# ---
# jupyter:
#   jupytext:
#     text_representation:
#       extension: .py
#       format_name: percent
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # Valve-Gear Explorer from Python
#
# Load a built-in scene, compute one revolution, sweep it over the speed range and plot what a
# designer reads. Run it with `jupytext --to ipynb notebooks/tour.py` and Jupyter, or as a
# script (`python notebooks/tour.py`); `tests/test_docs.py` executes it.

# %%
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # the test runs it without a display; in Jupyter plots show inline anyway
import matplotlib.pyplot as plt
import numpy as np

import explorer

ROOT = Path(explorer.__file__).resolve().parents[1]
SCENE = ROOT / "assets" / "scenes" / "valve_float_demo.toml"

# %% [markdown]
# ## One revolution
# `simulate` computes exactly the effects the scene lists; columns are numpy arrays in SI units.

# %%
scene = explorer.load_scene(SCENE)
result = explorer.simulate(scene)
theta = result.columns["cam_angle_deg"]
print(f"{scene.name}: {scene.drive.rpm:g} rpm, float (jump) speed {result.summary['jump_speed_rpm']:.0f} rpm")

fig, (ax_s, ax_f) = plt.subplots(2, 1, sharex=True, figsize=(8, 6))
ax_s.plot(theta, 1e3 * result.columns["rigid_valve_lift_m"], label="rigid")
ax_s.plot(theta, 1e3 * result.columns["valve_lift_m"], "--", label="elastic linkage")
ax_s.set_ylabel("valve lift s [mm]")
ax_s.legend()
ax_f.plot(theta, result.columns["contact_force_N"], label="rigid contact force")
ax_f.axhline(0.0, color="k", lw=0.5)
ax_f.set_xlabel("cam angle θ [°]")
ax_f.set_ylabel("F [N]")
ax_f.legend()
fig.savefig("tour_revolution.png", dpi=80)

# %% [markdown]
# ## Over the speed range
# `sweep` runs the scene at many speeds (or over tolerances with `sample=`) and returns one row
# of figures per run.

# %%
table = explorer.sweep(SCENE, vary={"drive.rpm": "1000:6000:51"})
rpm = table.columns["drive_rpm"]
separated = table.columns["separations"] > 0
first = rpm[separated][0] if separated.any() else float("nan")
print(f"the elastic valve first leaves the cam at {first:g} rpm; rigid float speed {result.summary['jump_speed_rpm']:.0f} rpm")

fig, ax = plt.subplots(figsize=(8, 3.5))
ax.plot(rpm, table.columns["seating_velocity_m_s"], label="seating velocity [m/s]")
ax.axvline(result.summary["jump_speed_rpm"], color="r", ls="--", label="rigid float speed")
ax.set_xlabel("camshaft speed [rpm]")
ax.legend()
fig.savefig("tour_sweep.png", dpi=80)
assert np.isfinite(table.columns["peak_linkage_force_N"]).all()
