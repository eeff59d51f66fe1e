"""Per-cycle speed figures shared by simulated and logged speed: trend, δ and orders.

One definition, one code path, for :class:`rotor.SpeedResult` (a simulated run) and
:func:`rotor.analyze_log` (a logged one), so that their figures can be compared:

- **the cycle's linear trend**: the slope of each cycle's speed [rad/s per rad of crank
  angle] from the time-mean speeds of its neighbours (central differences, one-sided at
  the ends; none for a single cycle), applied as a ramp through zero at mid-cycle;
- **δ of a cycle**: (ω_max − ω_min)/ω_mean of the cycle's speed with that ramp removed, so
  that a run-up or a coast-down adds nothing; in a periodic steady state (one cycle, no
  trend) it is the classic (ω_max − ω_min)/ω_mean;
- **orders of a cycle**: the discrete Fourier transform of the detrended speed over the
  cycle, by engine order (cycles per revolution): a trend left in would leak into every
  order, the half orders of a four-stroke first.

Pure array code (jax.numpy for tracers, so that ``jax.grad`` and ``jax.jit`` flow through;
numpy for concrete arrays, JAX's included, where each operation would otherwise compile a
program of its own for every new shape); base layer: imports nothing from rotor but
:mod:`rotor.jaxconfig` (JAX with float64 on) where a tracer comes in.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .checks import is_tracer

__all__ = ["cycle_slopes", "cycle_ramp", "detrended_cycles", "cycle_spectrum", "cycle_delta", "extreme_index"]


def array_module(*arrays: Any) -> Any:
    """jax.numpy when any argument is a tracer (inside ``jit``, ``grad``, ``vmap``), else numpy.
    A process that has not imported JAX has no tracer (a log's figures import no JAX)."""
    if not any(is_tracer(a) for a in arrays):
        return np
    from .jaxconfig import jax

    return jax.numpy


def extreme_index(xp: Any, x: Any, largest: bool) -> Any:
    """Index along the last axis of the first largest (``largest``) or smallest value of
    ``x``, or of its first NaN where it has one: ``argmax``/``argmin``, as NumPy and JAX
    define them. Under JAX it is two plain reductions, the extreme and then the first index
    that holds it: XLA's arg-reduction, which carries the index along, took 1.2–1.6 times as
    long on the CPU for a cycle's nodes (``benchmarks/xla_reductions.py``). ``xp``: numpy or
    jax.numpy."""
    if xp is np:
        return np.argmax(x, axis=-1) if largest else np.argmin(x, axis=-1)
    extreme = (xp.max if largest else xp.min)(x, axis=-1, keepdims=True)  # NaN where x has one
    hit = (x == extreme) | xp.isnan(x)
    n = x.shape[-1]
    return xp.min(xp.where(hit, xp.arange(n), n), axis=-1)


def cycle_slopes(mean_omega: ArrayLike, cycle_rad: float) -> Any:
    """The linear trend of each cycle's speed [rad/s per rad], shape (cycles,).

    **Arguments:** ``mean_omega``: the time-mean speed of each consecutive cycle [rad/s];
    ``cycle_rad``: the cycle's length [rad]. Central differences of the neighbours' means
    (one-sided, second order, at the ends; the difference of the two for two cycles);
    zero for a single cycle.
    """
    xp = array_module(mean_omega)
    m = xp.asarray(mean_omega, dtype=xp.float64)
    C = m.shape[0]
    if C < 2:
        return xp.zeros_like(m)
    if C == 2:
        return xp.full(2, m[1] - m[0]) / cycle_rad
    # second order throughout: central inside, one-sided three-point at the ends (a run-up's
    # curvature would otherwise leak into the first and last cycles' half orders)
    first = (-3 * m[0] + 4 * m[1] - m[2]) / 2
    last = (3 * m[-1] - 4 * m[-2] + m[-3]) / 2
    inner = (m[2:] - m[:-2]) / 2
    return xp.concatenate([xp.reshape(first, (1,)), inner, xp.reshape(last, (1,))]) / cycle_rad


def cycle_ramp(slopes: ArrayLike, points: int, cycle_rad: float) -> Any:
    """The trend of each cycle on its uniform grid of ``points`` samples [rad/s], zero at
    mid-cycle: slope·(ψ − Θ/2), ψ = 0, Θ/points, …; shape (cycles, points)."""
    xp = array_module(slopes)
    psi = xp.arange(points) * (cycle_rad / points)
    return xp.asarray(slopes)[:, None] * (psi[None, :] - cycle_rad / 2)


def detrended_cycles(omega: ArrayLike, mean_omega: ArrayLike, cycle_rad: float) -> Any:
    """The speed of each cycle (rows of ``omega``, uniform in angle) [rad/s] with its
    linear trend (:func:`cycle_slopes`) removed; shape as ``omega`` (cycles, points)."""
    w = omega
    P = np.shape(w)[1]
    return w - cycle_ramp(cycle_slopes(mean_omega, cycle_rad), P, cycle_rad)


def cycle_spectrum(omega: ArrayLike, mean_omega: ArrayLike, cycle_rad: float) -> Any:
    """The complex harmonics of each detrended cycle, X_k = 2/P·Σ ω·e^(−2πi·k·n/P), so that
    ω(ψ) ≈ X_0/2 + Σ |X_k|·cos(k·2πψ/Θ + arg X_k); shape (cycles, points//2 + 1).
    Harmonic k of a cycle of r revolutions is engine order k/r."""
    xp = array_module(omega, mean_omega)
    w = detrended_cycles(omega, mean_omega, cycle_rad)
    P = np.shape(w)[1]
    return xp.fft.rfft(w, axis=1) * (2.0 / P)


def cycle_delta(detrended_max: ArrayLike, detrended_min: ArrayLike, mean_omega: ArrayLike) -> Any:
    """δ of each cycle, (ω_max − ω_min)/ω_mean [-], from the extremes of its detrended speed
    [rad/s] (:func:`detrended_cycles`, refined or rebuilt as the caller's sampling needs)
    and its time-mean speed [rad/s]."""
    xp = array_module(detrended_max, detrended_min, mean_omega)
    return (xp.asarray(detrended_max) - xp.asarray(detrended_min)) / xp.asarray(mean_omega)
