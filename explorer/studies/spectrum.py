"""Harmonic content of the valve drive's acceleration against cam order, with the linkage's
natural frequency marked: how designers judge what a law will excite.

The acceleration the linkage is shaken with is the drive's, S'' = ratio w^2 L''(theta) (the
valve's own rigid motion adds the impacts of the lash, which no law changes). It is periodic in
the cam angle, so its Fourier series runs over cam orders n (n times per revolution):

    S''(theta) = sum_n C_n exp(i n theta),   amplitude of order n: 2 |C_n| (n >= 1)

The C_n come from the FFT of the analytic curve sampled at N equally spaced angles; the sampled
coefficients differ from the true ones by the aliased orders n +- N, ... which for a law with a
continuous acceleration fall as 1/N^2 (tests: the cycloidal rise and return against its closed
form). A linkage of stiffness k + rate and mass M1 rings at wn = sqrt((k + rate)/M1), i.e. at cam
order wn / w: the orders near it are the ones that excite it. A spring with mass ([spring] mass or
wire geometry) surges at its own frequencies, ends held: those of its chain of `elements` masses
when the scene cuts it into masses, else the continuous spring's f_j = (j/2) sqrt(k/m_s); they
are marked as cam orders too.
"""

from __future__ import annotations

import io
import math
from dataclasses import dataclass

import numpy as np

from ..core.errors import InputError
from ..core.units import resolved
from ..dynamics.chain import chain_frequencies, continuous_frequencies
from .charts import figure, png

TWO_PI = 2.0 * math.pi
MAX_ORDERS = 5000


@dataclass(frozen=True)
class Spectrum:
    orders: np.ndarray  # 1, 2, ...
    amplitude: np.ndarray  # m/s^2, 2 |C_n|
    phase: np.ndarray  # rad, of C_n, to the digits its aliasing error leaves (core.units.resolved)
    mean: float  # C_0, m/s^2 (0 for a closed event)
    rpm: float
    natural_order: float | None  # wn / w of the linkage in contact (None without [linkage])
    samples: int
    spring_orders: tuple[float, ...] = ()  # the spring's surge frequencies / w, within the orders shown


def acceleration_spectrum(scene, lift, orders: int = 100, samples: int | None = None) -> Spectrum:
    if not 1 <= orders <= MAX_ORDERS:
        raise InputError("<command line>", "--orders", f"must be between 1 and {MAX_ORDERS}, got {orders}")
    n = samples or max(1 << 16, 64 * orders)
    theta = np.arange(n) * (TWO_PI / n)
    w = scene.omega
    accel = scene.follower.ratio * w**2 * lift.derivatives(theta)[2]
    c = np.fft.rfft(accel) / n
    # the aliasing error of each coefficient, estimated from the FFT of every second sample (its
    # own error is at least as large as the full one's; conservative): a phase is known only to
    # error / |C_n| and is printed to that (core.units.resolved), so a phase that is 0 reads 0
    half = np.fft.rfft(accel[::2]) / (n // 2)
    natural = None
    if scene.linkage is not None and scene.valve is not None:
        mass = scene.valve.oscillating_mass if scene.valve.oscillating_mass is not None else scene.valve.mass
        rate = scene.spring.rate if scene.spring is not None else 0.0
        natural = math.sqrt((scene.linkage.stiffness + rate) / mass) / w
    k = np.arange(1, orders + 1)
    error = np.abs(c[k] - half[k]) if 2 * orders < n // 2 else np.zeros(orders)
    with np.errstate(divide="ignore", invalid="ignore"):
        phase_error = np.where(np.abs(c[k]) > error, error / np.abs(c[k]), math.pi)
    # the mean too is known only to its aliasing error (a closed event's is 0 exactly: L' returns
    # to its start; the FFT gave 3.2e-06 m/s^2 on the cycloidal demo)
    mean = resolved(float(c[0].real), abs(float(c[0].real - half[0].real)))
    return Spectrum(k, 2.0 * np.abs(c[k]), resolved(np.angle(c[k]), phase_error), mean, scene.drive.rpm,
                    natural, n, spring_surge_orders(scene.spring, w, orders))


def spring_surge_orders(spring, omega: float, orders: int) -> tuple[float, ...]:
    """The spring's own frequencies (ends held) as cam orders up to `orders`; () for a massless spring."""
    if spring is None or spring.mass <= 0.0 or spring.rate <= 0.0:
        return ()
    if spring.elements > 0:
        w_j = chain_frequencies(spring.elements, spring.rate, spring.mass)
    else:
        first = 2.0 * math.pi * continuous_frequencies(1, spring.rate, spring.mass)[0]
        w_j = 2.0 * math.pi * continuous_frequencies(int(orders * omega / first) + 1, spring.rate, spring.mass)
    return tuple(float(x) for x in w_j / omega if x <= orders)


def table_text(scene, spectrum: Spectrum) -> str:
    out = io.StringIO()
    marked = "" if spectrum.natural_order is None else f"; the linkage rings at cam order {spectrum.natural_order:.6g}"
    if spectrum.spring_orders:
        marked += "; the spring surges at cam orders " + ", ".join(f"{o:.6g}" for o in spectrum.spring_orders)
    out.write(f"# {scene.name}: harmonics of the drive acceleration ratio w^2 L'' at {spectrum.rpm:g} rpm "
              f"(FFT of {spectrum.samples} samples){marked}\n")
    # without the convention a phase cannot be used: peak or RMS, cos or sin, from which zero
    out.write(f"# S''(theta) = {spectrum.mean:.10g} m/s^2 + sum over the orders n of amplitude cos(n theta + phase), "
              "theta the cam angle from the scene's zero; amplitude is the peak (2 |C_n|), not RMS; "
              "frequency = n rpm / 60\n")
    out.write("order,frequency_Hz,amplitude_m_s2,phase_rad\n")
    f = spectrum.orders * spectrum.rpm / 60.0
    np.savetxt(out, np.column_stack([spectrum.orders, f, spectrum.amplitude, spectrum.phase]), delimiter=",",
               fmt=["%d", "%.10g", "%.10e", "%.10g"])
    return out.getvalue()


def chart_png(scene, spectrum: Spectrum) -> bytes:
    with figure(figsize=(8.0, 4.6), dpi=110) as (fig, ax):
        floor = max(float(spectrum.amplitude.max()) * 1e-8, 1e-12)
        ax.semilogy(spectrum.orders, np.maximum(spectrum.amplitude, floor), "o-", ms=3, lw=0.8,
                    label="amplitude of the order")
        if spectrum.natural_order is not None:
            ax.axvline(spectrum.natural_order, color="crimson", lw=1.2,
                       label=f"linkage natural frequency (order {spectrum.natural_order:.1f})")
        for i, order in enumerate(spectrum.spring_orders):
            ax.axvline(order, color="teal", lw=0.9, ls="--",
                       label="spring surge frequencies (ends held)" if i == 0 else None)
        ax.set_xlabel("cam order (per revolution)")
        ax.set_ylabel("drive acceleration amplitude [m/s²]")
        ax.set_title(f"{scene.name}: spectrum at {spectrum.rpm:g} rpm")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
        return png(fig)
