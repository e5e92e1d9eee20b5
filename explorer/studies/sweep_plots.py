"""Pictures of a sweep table (PNG through matplotlib's off-screen backend, as `explorer bench`
draws its charts) and a rerun recording with the swept key as a timeline.

- one grid key: every figure against it, one panel each; the rigid float speed marked when the
  key is the speed;
- two grid keys: heat maps over them (seating velocity, peak linkage force, largest deviation,
  the rigid contact margin: those the table has) with the boundary of first separation drawn;
- random samples (a tolerance study): histograms of the sampled inputs and of the figures (a
  count one bar per integer; a figure that is NaN in some runs says in how many it is shown) and
  the share of runs that separate.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..core.outputs import as_output, output_path
from .charts import figure, png
from .sweep_spec import SIGN_LABELS, SWEEP_KEYS

# what a designer looks at first, in this order (those the table has are drawn)
FIGURES = ("seating_velocity_m_s", "peak_linkage_force_N", "max_deviation_m", "separations", "flight_time_s",
           "first_separation_deg", "peak_camshaft_back_pressure_N", "largest_bounce_m", "lift_off_delay_s",
           "seat_impacts", "min_contact_force_N", "max_camshaft_torque_Nm", "residual_deviation_m",
           "residual_amplitude_m")
COUNTS = ("separations", "seat_impacts")  # integer columns: steps in a line, one bar per value in a histogram
HEATMAPS = ("seating_velocity_m_s", "peak_linkage_force_N", "max_deviation_m", "min_contact_force_N")






def _figures(table) -> list[str]:
    return [f for f in FIGURES if f in table.columns and np.isfinite(np.asarray(table.columns[f], float)).any()]


def sweep_png(table) -> bytes:
    """The picture that suits the table (see the module docstring)."""
    meta = table.metadata
    axes = meta.get("axes", [])
    if meta.get("samples"):
        return histograms_png(table)
    if len(axes) == 2:
        return heatmaps_png(table)
    return lines_png(table)


def _key_column(key: str) -> str:
    return SWEEP_KEYS[key].column


def lines_png(table) -> bytes:
    meta = table.metadata
    key = meta["axes"][0]["key"] if meta.get("axes") else meta["keys"][0]
    x = np.asarray(table.columns[_key_column(key)], float)
    figs = _figures(table)
    n = max(1, len(figs))
    cols = 2 if n > 1 else 1
    rows = math.ceil(n / cols)
    floats = np.asarray(table.columns.get("float_speed_rpm", []), float)
    float_rpm = float(floats[np.isfinite(floats)][0]) if key == "drive.rpm" and np.isfinite(floats).any() else None
    with figure(rows, cols, figsize=(5.2 * cols, 2.6 * rows + 0.6), dpi=100, squeeze=False) as (fig, grid):
        for i, name in enumerate(figs):
            ax = grid[i // cols][i % cols]
            # a count changes in whole steps: drawn as steps, not as slopes between the speeds
            style = {"drawstyle": "steps-mid", "marker": ".", "markersize": 3} if name in COUNTS else {}
            ax.plot(x, np.asarray(table.columns[name], float), linewidth=1.0, color="C0", **style)
            if float_rpm is not None:
                ax.axvline(float_rpm, color="C3", linestyle="--", linewidth=0.9, label=f"rigid float speed {float_rpm:.0f} rpm")
                if i == 0:
                    ax.legend(fontsize=7)
            ax.set_title(_label(name), fontsize=9)
            ax.set_xlabel(_key_column(key), fontsize=8)
            if meta.get("axes") and meta["axes"][0].get("log"):
                ax.set_xscale("log")
            ax.grid(alpha=0.3)
        for j in range(len(figs), rows * cols):
            grid[j // cols][j % cols].axis("off")
        fig.suptitle(_title(table), fontsize=10)
        return png(fig)


def heatmaps_png(table) -> bytes:
    meta = table.metadata
    (ka, na), (kb, nb) = [(a["key"], a["points"]) for a in meta["axes"][:2]]
    full = len(table) == na * nb
    names = [h for h in HEATMAPS if h in table.columns] or _figures(table)[:1]
    with figure(1, max(1, len(names)), figsize=(4.6 * max(1, len(names)), 4.2), dpi=100, squeeze=False) as (fig, grid):
        if not full or not names:
            grid[0][0].text(0.5, 0.5, "incomplete sweep: no map", ha="center")
            return png(fig)
        xa = np.asarray(table.columns[_key_column(ka)], float).reshape(na, nb)[:, 0]
        xb = np.asarray(table.columns[_key_column(kb)], float).reshape(na, nb)[0, :]
        for ax, name in zip(grid[0], names):
            z = np.asarray(table.columns[name], float).reshape(na, nb)
            mesh = ax.pcolormesh(xb, xa, z, shading="nearest", cmap="viridis")
            fig.colorbar(mesh, ax=ax, shrink=0.85).set_label(_label(name), fontsize=8)
            if "separations" in table.columns:
                sep = np.asarray(table.columns["separations"], float).reshape(na, nb)
                if (sep > 0).any() and (sep == 0).any():
                    ax.contour(xb, xa, (sep > 0).astype(float), levels=[0.5], colors="w", linewidths=1.2)
            ax.set_xlabel(_key_column(kb), fontsize=8)
            ax.set_ylabel(_key_column(ka), fontsize=8)
            for a, setter in ((meta["axes"][1], ax.set_xscale), (meta["axes"][0], ax.set_yscale)):
                if a.get("log"):
                    setter("log")
            ax.set_title(_label(name) + ("\n(white: boundary of first separation)" if "separations" in table.columns else ""),
                         fontsize=8)
        fig.suptitle(_title(table), fontsize=10)
        return png(fig)


@dataclass(frozen=True)
class Histogram:
    name: str  # the column
    data: np.ndarray  # its finite values
    bins: Any  # a count or the edges
    title: str


def histograms(table) -> list[Histogram]:
    """The panels of a tolerance study: first the sampled inputs (the distribution actually drawn),
    then the figures. A count column gets one bar per integer (edges at k +- 1/2: automatic bins
    put bars between integers); a column with NaN (a figure that does not exist in some runs, such
    as first_separation_deg of a run that never separates, or a failed run) says how many of the
    runs it shows, as a histogram of the rest alone would pass for all of them."""
    inputs = [_key_column(s["key"]) for s in table.metadata.get("samples", [])]
    panels = []
    for name in [c for c in inputs if c in table.columns] + [f for f in _figures(table) if f not in inputs]:
        raw = np.asarray(table.columns[name], float)
        data = raw[np.isfinite(raw)]
        if name in COUNTS and data.size:
            bins = np.arange(np.min(data) - 0.5, np.max(data) + 1.0, 1.0)
        else:
            bins = min(60, max(5, int(math.sqrt(max(data.size, 1)))))
        title = _label(name) + (" (sampled input)" if name in inputs else "")
        if data.size < raw.size:
            title += f"\n{data.size} of {raw.size} runs (NaN in {raw.size - data.size}: none there, or failed)"
        panels.append(Histogram(name, data, bins, title))
    return panels


def histograms_png(table) -> bytes:
    panels = histograms(table)
    n = max(1, len(panels))
    cols = min(3, n)
    rows = math.ceil(n / cols)
    with figure(rows, cols, figsize=(4.2 * cols, 2.8 * rows + 0.8), dpi=100, squeeze=False) as (fig, grid):
        for i, panel in enumerate(panels):
            ax = grid[i // cols][i % cols]
            ax.hist(panel.data, bins=panel.bins, color="C1" if "sampled" in panel.title else "C0")
            ax.set_title(panel.title, fontsize=9)
            ax.set_ylabel("runs", fontsize=8)
            ax.grid(alpha=0.3)
        for j in range(len(panels), rows * cols):
            grid[j // cols][j % cols].axis("off")
        title = _title(table)
        share = separating_share(table)
        if share is not None:
            title += f"\n{share_text(table, share)}"
        fig.suptitle(title, fontsize=10)
        return png(fig)


def separating_share(table) -> float | None:
    """The share of the runs that finished (a failed run's figures are NaN: it neither separates
    nor stays seated) whose valve separates; None without the column or a finished run."""
    if "separations" not in table.columns or len(table) == 0:
        return None
    sep = np.asarray(table.columns["separations"], float)
    finished = np.isfinite(sep)
    if not finished.any():
        return None
    return float(np.mean(sep[finished] > 0))


def failed_runs(table) -> int:
    return int(np.sum(np.asarray(table.columns["run_failed"]))) if "run_failed" in table.columns else 0


def share_text(table, share: float) -> str:
    failed = failed_runs(table)
    text = f"{100.0 * share:.2f} % of the runs separate"
    return text + (f" (of {len(table) - failed} finished; {failed} failed)" if failed else "")


def _label(name: str) -> str:
    """A figure's name, with its sign convention where it has one (SIGN_LABELS)."""
    return f"{name} ({SIGN_LABELS[name]})" if name in SIGN_LABELS else name


def _title(table) -> str:
    meta = table.metadata
    parts = [f"{meta.get('scene', '')}: {len(table)} runs"]
    if meta.get("samples"):
        parts.append(", ".join(f"{s['key']} ~ {s['distribution']}" for s in meta["samples"]))
    if not meta.get("complete", True):
        parts.append(f"INCOMPLETE ({meta.get('runs_finished')} of {meta.get('runs_planned')})")
    return "; ".join(parts)


def timeline_scale(values: np.ndarray) -> tuple[int, np.ndarray]:
    """A key's values as integers for a rerun sequence timeline: (exponent k, round(v * 10^k))
    with about seven significant digits of the largest value."""
    values = np.asarray(values, float)
    top = float(np.max(np.abs(values))) if values.size else 1.0
    k = 6 - int(math.floor(math.log10(top))) if top > 0.0 else 0
    return k, np.round(values * 10.0 ** k).astype(np.int64)


def record(table, path) -> None:
    """The table as a rerun recording: every figure a time series on the swept keys' timelines
    (one per key, named after its column and scaled to integers: `drive_rpm_e3` holds rpm x 1e3)
    and a `run` timeline, the rows ordered by the first key."""
    import rerun as rr


    out = as_output(path, "--record")
    meta = table.metadata
    keys = meta["keys"]
    first = np.asarray(table.columns[_key_column(keys[0])], float)
    order = np.argsort(first, kind="stable")
    indexes = [rr.TimeColumn("run", sequence=np.asarray(table.columns["run"], np.int64)[order])]
    for key in keys:
        col = _key_column(key)
        k, ints = timeline_scale(np.asarray(table.columns[col], float)[order])
        indexes.append(rr.TimeColumn(f"{col}_e{k}", sequence=ints))
    rec = rr.RecordingStream("valve-gear-explorer-sweep", recording_id=f"sweep-{meta.get('scene', '')}")
    with output_path(out) as tmp:
        rec.set_sinks(rr.FileSink(str(tmp)))
        for name in table.columns:
            if name == "run" or name in [_key_column(k) for k in keys]:
                continue
            values = np.asarray(table.columns[name], float)[order]
            rec.log(f"/sweep/{name}", rr.SeriesLines(names=name), static=True)
            rec.send_columns(f"/sweep/{name}", indexes=indexes, columns=rr.Scalars.columns(scalars=values))
        rec.log("/sweep/about", rr.TextDocument(_title(table)), static=True)
        rec.flush()
        rec.disconnect()
