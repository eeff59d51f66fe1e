"""Inverse dynamics: the indicated (gas) torque from the crankshaft speed ω(θ).

The equation of motion (:mod:`rotor.dynamics.equation`) in energy form,

    d/dθ [½·I(θ)·ω²] = I(θ)·ω·dω/dθ + ½·I′(θ)·ω²
                     = M_gas(θ) + k(θ)·ω² − M_friction(ω) − M_load(ω, t),

read backwards gives the indicated torque from the measured or simulated speed:

    M_ind(θ) = I(θ)·ω·dω/dθ + ½·I′(θ)·ω² − k(θ)·ω² + M_friction(ω) + M_load(ω, t)

(k ≠ 0 only at the ``"constant"`` fidelity, where I is constant and the reciprocating
inertia torque k·ω² is explicit). Two ways are offered:

- :func:`indicated_torque` — the exact inverse on the sample grid. dω/dθ is taken
  spectrally over the **whole record** (concatenated cycles of one continuous recording
  are continuous; differentiating each cycle as if it were periodic would put a jump at
  every cycle boundary of a run whose speed drifts). The record itself is not periodic:
  its end-to-start jumps in ω and its first derivatives are estimated by polynomial fits
  at both ends and removed with Bernoulli polynomials (Lanczos–Eckhoff), so that the
  rest is smooth and periodic over the record and its FFT derivative converges fast.
  Regularisation (``regularisation=``): ``"orders"`` keeps the engine orders up to
  ``max_order`` (an ideal low-pass on the whole record: cycle-to-cycle variation, which
  lies between the cycle harmonics, is kept), ``"tikhonov"`` minimises
  ‖ω_r − ω‖² + λ·‖ω_r″‖² (gain 1/(1 + λ·ν⁴) at engine order ν; λ [rad⁴] defaults to
  ``max_order``⁻⁴, gain ½ there), ``None`` none. With a known load and friction the
  identity is exact: what remains is the error of the derivative.
- :func:`harmonic_torque` — the harmonic method: the low orders of speed mapped to the
  low orders of the gas torque by the crank train's response linearised around the
  cycle's mean speed (see its docstring for the derivation and the neglected terms).

**Unknown load.** With ``load=None`` the load is taken as zero and the result is
M_gas − M_load. Over a steady cycle the mean of the net torque d(½Iω²)/dθ is zero, so the
mean of the result is then the mean friction only, and the mean gas torque (= mean load +
mean friction) is not observable from the speed: take it from elsewhere (IMEP, a torque
meter) or pass the load. The orders ≥ ½ are unaffected as long as the load torque does
not vary within the cycle (a load that follows ω varies by about δ·dM_load/dω·ω̄).

Angles: θ is the engine crank angle of the cycle grid, 0 = TDC of cylinder 1 before
intake (360° its firing TDC, four-stroke), as in :class:`rotor.SpeedResult` and
:class:`rotor.LogAnalysis`. Orders are per revolution (0.5, 1, 1.5, … four-stroke); a
harmonic X of order ν means X·e^{iνθ}, reported like :class:`rotor.Orders` as amplitude
and phase of A·cos(νθ + φ) with θ from the start of the cycle.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import ArrayLike

from ..checks import arrays_only
from ..dynamics.crank_train import COL_I, COL_K, crank_train
from ..dynamics.equation import friction_coefficients
from ..dynamics.loads import ConstantLoad, Load
from ..errors import EngineError
from ..results import Result, json_safe

if TYPE_CHECKING:
    from ..dynamics.result import SpeedResult
    from ..engine.friction import Friction
    from ..engine.model import Engine
    from ..logs.analysis import LogAnalysis

__all__ = [
    "IndicatedTorque",
    "HarmonicTorque",
    "TorqueOrders",
    "indicated_torque",
    "harmonic_torque",
    "harmonic_response",
    "REGULARISATIONS",
]

REGULARISATIONS = (None, "orders", "tikhonov")
MIN_POINTS = 16
# end-jump removal: jumps in ω and its first JUMPS derivatives; the one-sided polynomial
# fits that estimate them (degree, samples) without and with regularisation
JUMPS = 4
EXACT_FIT = (8, 9)
SMOOTH_FIT_DEGREE = 4


# ----------------------------------------------------------------------------- results
class TorqueOrders(eqx.Module):
    """Harmonics of the torque by engine order, one row per cycle.

    x(θ) = mean + Σ amplitude·cos(order·θ + phase), θ from the start of the cycle.

    **Fields:** ``order`` (K,) [-]; ``mean_Nm`` (cycles,) [N·m]; ``amplitude_Nm``,
    ``phase_rad`` (cycles, K) [N·m], [rad]; ``complex_Nm`` (cycles, K): amplitude·e^{i·phase}.
    """

    order: np.ndarray
    mean_Nm: np.ndarray
    complex_Nm: np.ndarray

    @property
    def amplitude_Nm(self) -> np.ndarray:
        """Amplitude of each order in each cycle [N·m], (cycles, K)."""
        return np.abs(self.complex_Nm)

    @property
    def phase_rad(self) -> np.ndarray:
        """Phase of each order in each cycle [rad], (cycles, K)."""
        return np.angle(self.complex_Nm)


class IndicatedTorque(eqx.Module, Result):
    """The indicated torque of every cycle from :func:`indicated_torque`.

    **Per cycle** (cycles, P) on the cycle-angle grid ``theta`` (P,) [rad]:
    ``omega`` (the speed used: regularised if asked) [rad/s]; ``domega_dtheta`` [rad/s per
    rad]; ``t`` [s]; ``torque`` M_ind, the indicated (gas) torque of the engine [N·m];
    ``net_torque`` d(½Iω²)/dθ, the torque accelerating the crank train [N·m];
    ``inertia_torque`` −k·ω² (explicit reciprocating inertia torque, nonzero only at the
    ``"constant"`` fidelity) [N·m]; ``friction_torque``, ``load_torque`` [N·m].
    M_ind = net − inertia + friction + load.

    **Attributes:** ``cycle_rad``, ``strokes``, ``fidelity``, ``regularisation``,
    ``max_order`` (the order cut-off or Tikhonov half-gain order, or None),
    ``tikhonov_weight`` λ [rad⁴] (or None), ``end_jumps`` (the end-to-start jumps of ω and
    its derivatives removed before the FFT, [rad/s·rad⁻ᵐ], m = 0…).
    """

    theta: np.ndarray
    omega: np.ndarray
    domega_dtheta: np.ndarray
    t: np.ndarray
    torque: np.ndarray
    net_torque: np.ndarray
    inertia_torque: np.ndarray
    friction_torque: np.ndarray
    load_torque: np.ndarray
    end_jumps: np.ndarray
    cycle_rad: float = eqx.field(static=True)
    strokes: int = eqx.field(static=True)
    fidelity: str = eqx.field(static=True)
    regularisation: str | None = eqx.field(static=True)
    max_order: float | None = eqx.field(static=True)
    tikhonov_weight: float | None = eqx.field(static=True)

    @property
    def cycles(self) -> int:
        return int(self.torque.shape[0])

    @property
    def mean_torque_Nm(self):
        """Angle mean of M_ind per cycle [N·m], shape (cycles,)."""
        return np.mean(self.torque, axis=1)

    def orders(self, max_order: float = 12.0, of: str = "torque") -> TorqueOrders:
        """Harmonics of ``of`` (``"torque"``, ``"net_torque"``, ``"load_torque"``, …) per
        cycle, orders up to ``max_order`` [per revolution] (FFT of each cycle)."""
        return cycle_orders(getattr(self, of), self.strokes, max_order)

    def summary(self) -> str:
        """A few lines: cycles, fidelity and regularisation, the mean and peak torque."""
        reg = "none" if self.regularisation is None else self.regularisation
        if self.max_order is not None:
            reg += f" (order {self.max_order:g})"
        m = self.mean_torque_Nm
        lines = [
            f"indicated torque of {self.cycles} cycle(s) of {math.degrees(self.cycle_rad):g}° "
            f"({self.torque.shape[1]} points each), {self.fidelity} fidelity, regularisation {reg}",
            f"  mean torque {np.mean(m):.2f} N·m (cycles {np.min(m):.2f} … {np.max(m):.2f}); "
            f"peak {np.max(self.torque):.1f} N·m, least {np.min(self.torque):.1f} N·m",
            f"  friction {np.mean(self.friction_torque):.2f} N·m, load {np.mean(self.load_torque):.2f} N·m (means)",
        ]
        return "\n".join(lines) + "\n"

    def __repr__(self) -> str:
        return Result.__repr__(self)

    def to_pandas(self) -> Any:
        """Tidy: one row per cycle and grid point: ``cycle``, ``theta_deg``, ``t_s``,
        ``omega_rad_s``, ``domega_dtheta_rad_s_per_rad``, ``torque_Nm``, ``net_torque_Nm``,
        ``inertia_torque_Nm``, ``friction_torque_Nm``, ``load_torque_Nm``."""
        import pandas as pd

        C, P = self.torque.shape
        return pd.DataFrame(
            {
                "cycle": np.repeat(np.arange(1, C + 1), P),  # counted from 1
                "theta_deg": np.tile(np.rad2deg(np.asarray(self.theta)), C),
                "t_s": np.asarray(self.t).reshape(-1),
                "omega_rad_s": np.asarray(self.omega).reshape(-1),
                "domega_dtheta_rad_s_per_rad": np.asarray(self.domega_dtheta).reshape(-1),
                "torque_Nm": np.asarray(self.torque).reshape(-1),
                "net_torque_Nm": np.asarray(self.net_torque).reshape(-1),
                "inertia_torque_Nm": np.broadcast_to(self.inertia_torque, (C, P)).reshape(-1),
                "friction_torque_Nm": np.broadcast_to(self.friction_torque, (C, P)).reshape(-1),
                "load_torque_Nm": np.broadcast_to(self.load_torque, (C, P)).reshape(-1),
            }
        )

    def to_json_dict(self) -> dict:
        """Plain JSON: the settings, the grid [deg], and per cycle the mean torque and the
        indicated torque on the grid [N·m]; ``None``, never NaN."""
        return json_safe(
            {
                "cycles": self.cycles,
                "strokes": self.strokes,
                "fidelity": self.fidelity,
                "regularisation": self.regularisation,
                "max_order": self.max_order,
                "tikhonov_weight": self.tikhonov_weight,
                "theta_deg": np.rad2deg(np.asarray(self.theta)),
                "mean_torque_Nm": self.mean_torque_Nm,
                "torque_Nm": self.torque,
            }
        )

    def plot(self, ax: Any = None) -> Any:
        """The indicated and the net torque over the record, on ``ax`` (one Axes or None);
        :func:`rotor.plotting.diagnostics.plot_indicated_torque`. Returns the Axes."""
        from ..plotting.diagnostics import plot_indicated_torque

        reg = "" if self.regularisation is None else f", {self.regularisation}"
        return plot_indicated_torque(
            theta=self.theta,
            torque=self.torque,
            net_torque=self.net_torque,
            title=f"indicated torque by inverse dynamics ({self.fidelity}{reg})",
            ax=ax,
        )


class HarmonicTorque(eqx.Module, Result):
    """Gas-torque harmonics from speed harmonics, :func:`harmonic_torque`.

    **Fields:** ``torque`` (:class:`TorqueOrders`, the gas torque: mean and orders up to
    ``max_order``); ``speed_orders`` (K_s,) and ``speed_complex`` (cycles, K_s): the speed
    harmonics used [rad/s] (amplitude·e^{i·phase}, after removing each cycle's linear trend);
    ``mean_omega`` (cycles,) angle-mean speed [rad/s]; ``trend`` (cycles,) dω̄/dθ [rad/s per
    rad]; ``relative_speed_amplitude`` (cycles,): max|w|/ω̄ of the fluctuation w rebuilt from
    the harmonics used, the size of the relative error the linearisation leaves (≈ half of it
    in the dynamic torque, see :func:`harmonic_torque`).
    """

    torque: TorqueOrders
    speed_orders: np.ndarray
    speed_complex: np.ndarray
    mean_omega: np.ndarray
    trend: np.ndarray
    relative_speed_amplitude: np.ndarray

    @property
    def cycles(self) -> int:
        """Cycles analysed."""
        return int(np.asarray(self.mean_omega).size)

    def summary(self) -> str:
        """A few lines: the mean torque, and each order's amplitude (mean over the cycles)."""
        t = self.torque
        amp = np.atleast_2d(t.amplitude_Nm)
        lines = [
            f"gas-torque harmonics of {self.cycles} cycle(s) from {np.asarray(self.speed_orders).size} speed "
            f"orders (largest relative speed fluctuation {np.max(self.relative_speed_amplitude):.4f})",
            f"  mean torque {np.mean(t.mean_Nm):.2f} N·m",
            "  order  amplitude [N·m] (mean over the cycles)",
        ]
        for o, a in list(zip(np.asarray(t.order), amp.mean(axis=0)))[:40]:
            lines.append(f"  {o:5.1f}  {a:12.2f}")
        return "\n".join(lines) + "\n"

    def __repr__(self) -> str:
        return Result.__repr__(self)

    def to_pandas(self) -> Any:
        """Tidy: one row per cycle and order: ``cycle``, ``order``, ``amplitude_Nm``,
        ``phase_rad``, ``mean_Nm`` (the cycle's mean torque), ``mean_omega_rad_s``."""
        import pandas as pd

        amp = np.atleast_2d(self.torque.amplitude_Nm)
        C, K = amp.shape
        cyc = np.repeat(np.arange(C), K)
        return pd.DataFrame(
            {
                "cycle": cyc + 1,  # counted from 1
                "order": np.tile(np.asarray(self.torque.order, dtype=np.float64), C),
                "amplitude_Nm": amp.reshape(-1),
                "phase_rad": np.atleast_2d(self.torque.phase_rad).reshape(-1),
                "mean_Nm": np.asarray(self.torque.mean_Nm)[cyc],
                "mean_omega_rad_s": np.asarray(self.mean_omega)[cyc],
            }
        )

    def to_json_dict(self) -> dict:
        """Plain JSON: the orders, per cycle the mean torque [N·m], each order's amplitude
        [N·m] and phase [rad], the mean speed [rad/s]; ``None``, never NaN."""
        return json_safe(
            {
                "order": self.torque.order,
                "mean_torque_Nm": self.torque.mean_Nm,
                "amplitude_Nm": self.torque.amplitude_Nm,
                "phase_rad": self.torque.phase_rad,
                "mean_omega_rad_s": self.mean_omega,
                "relative_speed_amplitude": self.relative_speed_amplitude,
            }
        )

    def plot(self, ax: Any = None) -> Any:
        """The gas-torque amplitude by order (mean and cycle-to-cycle spread), on ``ax`` (one
        Axes or None); :func:`rotor.plotting.diagnostics.plot_torque_orders`. Returns the Axes."""
        from ..plotting.diagnostics import plot_torque_orders

        return plot_torque_orders(
            order=self.torque.order,
            amplitude_Nm=self.torque.amplitude_Nm,
            title="gas-torque harmonics from the speed (harmonic method)",
            ax=ax,
        )


def cycle_orders(x: ArrayLike, strokes: int, max_order: float) -> TorqueOrders:
    """Mean and harmonics (orders up to ``max_order``) of each row of ``x`` (cycles, P)."""
    x = np.atleast_2d(np.asarray(x, dtype=np.float64))
    P = x.shape[1]
    revs = strokes / 2
    kmax = min(int(np.floor(max_order * revs + 1e-9)), (P - 1) // 2)
    X = np.fft.rfft(x, axis=1) * (2.0 / P)
    k = np.arange(1, kmax + 1)
    return TorqueOrders(k / revs, X[:, 0].real / 2.0, X[:, 1 : kmax + 1])


# ----------------------------------------------------------------------------- input
def _engine_cycle(engine):
    return float(engine.cycle_rad)


def _check_cycle(engine, cycle_rad, what):
    cyc = _engine_cycle(engine)
    if cycle_rad is not None and not math.isclose(float(cycle_rad), cyc, rel_tol=1e-9):
        raise EngineError(
            f"{what}: a cycle of {math.degrees(float(cycle_rad)):g}° does not fit the {engine.strokes}-stroke engine "
            f"{engine.name!r}, whose cycle is {math.degrees(cyc):g}°"
        )


def _speed_input(engine, speed, cycle_rad, t_start_s, periodic):
    """(ω (C, P), end sample or None, t (C, P) or None, t0, periodic) from any accepted input."""
    from ..dynamics.result import SpeedResult
    from ..logs.analysis import LogAnalysis

    end = None
    t = None
    if isinstance(speed, SpeedResult):
        _check_cycle(engine, speed.cycle_rad, "speed (a SpeedResult)")
        if speed.uniform_cycles < 1:
            raise EngineError("speed (a SpeedResult) holds no complete cycle sampled in the angle domain")
        P, C = speed.points_per_cycle, speed.uniform_cycles
        w_all, t_all = np.asarray(speed.omega), np.asarray(speed.t)
        omega = w_all[: C * P].reshape(C, P)
        t = t_all[: C * P].reshape(C, P)
        if speed.kind == "steady":
            periodic = True if periodic is None else periodic
        elif w_all.shape[0] > C * P:
            end = float(w_all[C * P])  # the sample that closes the last cycle
        t0 = float(t_all[0])
    elif isinstance(speed, LogAnalysis):
        _check_cycle(engine, speed.cycle_rad, "speed (a LogAnalysis)")
        omega = np.asarray(speed.omega, dtype=np.float64)
        starts = np.asarray(speed.cycle_start_rad)
        if starts.size > 1 and not np.allclose(np.diff(starts), speed.cycle_rad, rtol=0, atol=1e-9):
            raise EngineError("speed (a LogAnalysis): its cycles are not consecutive; pass them one at a time")
        t0 = float(speed.t_start_s[0])
    else:
        if isinstance(speed, jax.core.Tracer):
            raise EngineError("speed: indicated_torque works on concrete arrays (it is not traceable)")
        _check_cycle(engine, cycle_rad, "cycle_rad")
        omega = np.asarray(speed, dtype=np.float64)
        if omega.ndim == 1:
            omega = omega[None, :]
        if omega.ndim != 2:
            raise EngineError(
                f"speed has shape {np.shape(speed)}: needs (points,) for one cycle or (cycles, points) on the uniform "
                "cycle-angle grid"
            )
        t0 = 0.0 if t_start_s is None else float(t_start_s)
    if omega.shape[0] < 1:
        raise EngineError(f"speed has shape {omega.shape}: no cycle; needs at least one")
    if omega.shape[1] < MIN_POINTS:
        raise EngineError(f"speed has {omega.shape[1]} points per cycle: needs {MIN_POINTS} or more")
    if not np.all(np.isfinite(omega)):
        bad = np.argwhere(~np.isfinite(omega))[0]
        raise EngineError(f"speed is not finite (NaN or inf) at cycle {bad[0]}, point {bad[1]}")
    if np.any(omega <= 0):
        raise EngineError(
            f"speed must be positive everywhere (the crankshaft turning forwards); its minimum is {omega.min():g} rad/s"
        )
    return omega, end, t, t0, bool(periodic) if periodic is not None else False


def _check_regularisation(regularisation, max_order, tikhonov_weight, P, strokes):
    if regularisation not in REGULARISATIONS:
        raise EngineError(f"regularisation = {regularisation!r}: must be None, 'orders' or 'tikhonov'")
    nyquist = P / 2 / (strokes / 2)
    if regularisation is None:
        return None, None
    if regularisation == "tikhonov" and tikhonov_weight is not None:
        lam = float(tikhonov_weight)
        if not (np.isfinite(lam) and lam > 0):
            raise EngineError(f"tikhonov_weight = {tikhonov_weight!r}: must be a positive number [rad⁴]")
        return (None if max_order is None else float(max_order)), lam
    if max_order is None:
        raise EngineError(f"regularisation = {regularisation!r} needs max_order (the engine order to keep up to)")
    K = float(max_order)
    if not (np.isfinite(K) and 0 < K < nyquist):
        raise EngineError(f"max_order = {max_order!r}: must be positive and below the grid's Nyquist order {nyquist:g}")
    return K, (K**-4 if regularisation == "tikhonov" else None)


def _load_module(load):
    if load is None:
        return None
    if isinstance(load, Load):
        return arrays_only(load)
    try:
        return ConstantLoad(float(load))
    except (TypeError, ValueError):
        raise EngineError(
            f"load = {load!r}: must be a rotor load (rotor.PropellerLoad, …), a torque in N·m or None"
        ) from None


# ----------------------------------------------------------------------------- derivative
# Bernoulli polynomials B_0…B_5: B_n′ = n·B_{n−1} and B_n(1) − B_n(0) = [n = 1], so
# q_m(θ) = L^m/(m+1)!·B_{m+1}(θ/L) jumps by 1 over [0, L) in its m-th derivative only
_B = [
    lambda x: np.ones_like(x),
    lambda x: x - 0.5,
    lambda x: x * x - x + 1.0 / 6.0,
    lambda x: x**3 - 1.5 * x**2 + 0.5 * x,
    lambda x: x**4 - 2 * x**3 + x**2 - 1.0 / 30.0,
    lambda x: x**5 - 2.5 * x**4 + 5.0 / 3.0 * x**3 - x / 6.0,
]


def _end_derivatives(y, h, degree, at):
    """Derivatives 0…JUMPS at sample position ``at`` (in samples from y[0]) of the
    least-squares polynomial of ``degree`` through the samples y (index 0…len−1)."""
    u = np.arange(y.size, dtype=np.float64)
    c0, s = 0.5 * (y.size - 1), max(0.5 * (y.size - 1), 1.0)
    poly = np.polynomial.Polynomial.fit(u, y, degree, domain=[c0 - s, c0 + s], window=[-1, 1])
    out = []
    for m in range(JUMPS + 1):
        out.append(poly.deriv(m)(at) / h**m if m <= degree else 0.0)
    return np.array(out)


def _record_derivative(x, h, end, periodic, gain_of_order, fit):
    """ω and dω/dθ of the record x (N,) sampled every h [rad] from θ = 0, filtered in the order
    domain by ``gain_of_order`` (None: no filter). ``end``: the sample at θ = N·h if known.

    Returns (ω_r, dω_r/dθ, jumps)."""
    N = x.size
    L = N * h
    theta = np.arange(N) * h
    jumps = np.zeros(JUMPS + 1)
    if not periodic:
        degree, window = fit
        window = min(window, N // 2)
        degree = min(degree, window - 1)
        start = _end_derivatives(x[:window], h, degree, 0.0)
        tail = x[N - window :] if end is None else np.append(x[N - window + 1 :], end)
        at = window if end is None else window - 1
        stop = _end_derivatives(tail, h, degree, at)
        # a derivative as high as the fit's degree is one noisy number: its jump is left out
        jumps = np.where(np.arange(JUMPS + 1) < degree, stop - start, 0.0)
    s = theta / L
    trend = np.zeros(N)
    dtrend = np.zeros(N)
    for m in range(JUMPS + 1):
        if jumps[m] == 0.0:
            continue
        trend += jumps[m] * L**m / math.factorial(m + 1) * _B[m + 1](s)
        dtrend += jumps[m] * L ** (m - 1) / math.factorial(m) * _B[m](s)
    g = x - trend
    G = np.fft.rfft(g)
    n = np.arange(G.size)
    kappa = 2 * np.pi * n / L  # wavenumber [1/rad] = engine order
    if gain_of_order is not None:
        G = G * gain_of_order(kappa)
    dG = 1j * kappa * G
    if N % 2 == 0:
        dG[-1] = 0.0  # the Nyquist bin has no derivative
    return np.fft.irfft(G, n=N) + trend, np.fft.irfft(dG, n=N) + dtrend, jumps


def _cumulative_time(omega, h, t0):
    """t(θ) = t0 + ∫ dθ/ω on the samples (trapezoid; the first sample at t0)."""
    r = 1.0 / omega
    return t0 + np.concatenate([[0.0], np.cumsum(0.5 * h * (r[1:] + r[:-1]))])


# ----------------------------------------------------------------------------- exact inverse
def indicated_torque(
    engine: Engine,
    speed: LogAnalysis | SpeedResult | ArrayLike,
    *,
    load: Load | float | None = None,
    friction: Friction | bool | None = None,
    regularisation: str | None = None,
    max_order: float | None = None,
    tikhonov_weight: float | None = None,
    fidelity: str = "variable",
    grid_deg: float = 0.25,
    cycle_rad: float | None = None,
    t_start_s: float | None = None,
    periodic: bool | None = None,
) -> IndicatedTorque:
    """The engine's indicated torque from its crankshaft speed, by inverse dynamics.

    M_ind = I(θ)·ω·dω/dθ + ½·I′(θ)·ω² − k(θ)·ω² + M_friction(ω) + M_load(ω, t)   [N·m]

    **Arguments:**
    - ``engine``: a :class:`rotor.Engine`.
    - ``speed``: ω [rad/s] on the uniform cycle-angle grid (0 = TDC of cylinder 1 before
      intake): an array (P,) for one cycle or (cycles, P) for consecutive cycles of one
      continuous recording, a :class:`rotor.SpeedResult` or a :class:`rotor.LogAnalysis`.
    - ``load``: the load torque acting, a :mod:`rotor.dynamics.loads` load, a constant torque
      [N·m], or None (taken as zero: see the module doc for what the result means then).
    - ``friction``: a :class:`rotor.Friction`, None (the engine file's) or False (none).
    - ``regularisation``: None (default), ``"orders"`` (engine orders up to ``max_order``
      kept) or ``"tikhonov"`` (gain 1/(1 + λ·ν⁴) at order ν, λ = ``tikhonov_weight``
      [rad⁴], default ``max_order``⁻⁴).
    - ``fidelity``: of the crank train's I(θ) (see :func:`rotor.dynamics.crank_train`); the same
      as the simulation's for a round trip.
    - ``grid_deg``: node spacing of the crank-train tables [deg].
    - ``cycle_rad``: the cycle of an array ``speed`` [rad], checked against the engine's.
    - ``t_start_s``: the time of the first sample [s] of an array ``speed`` (default 0),
      for time-dependent loads; the times are ∫dθ/ω from there.
    - ``periodic``: the record is one period of a periodic motion (a steady state): no
      end jumps are removed. Default: True for a steady :class:`rotor.SpeedResult`, else
      False.

    **Returns:** an :class:`IndicatedTorque`.

    **Accuracy:** with the simulation's own load and friction the torque is exact but for
    the derivative's error: on a 6-cycle 4chn15 run-up sampled every 1°, within 0.28 N·m
    (6e-5 of the 4.7 kN·m peak), the first and last cycles included; 0.075 N·m at 0.5°
    (``tests/diagnostics/test_inverse.py``). Noise in ω is amplified by the order ν in dω/dθ: 1e-4
    white noise at 1° gives 1.8 kN·m rms unregularised, 45 N·m keeping orders ≤ 12.
    """
    omega, end, t, t0, periodic = _speed_input(engine, speed, cycle_rad, t_start_s, periodic)
    C, P = omega.shape
    K, lam = _check_regularisation(regularisation, max_order, tikhonov_weight, P, engine.strokes)
    load_m = _load_module(load)
    cyc = _engine_cycle(engine)
    h = cyc / P
    if regularisation == "orders":
        gain = lambda nu: (nu <= K * (1 + 1e-12)).astype(np.float64)  # noqa: E731
    elif regularisation == "tikhonov":
        gain = lambda nu: 1.0 / (1.0 + lam * nu**4)  # noqa: E731
    else:
        gain = None
    if regularisation is None:
        fit = EXACT_FIT
    else:  # a least-squares fit over half a period of the highest order kept
        top = K if K is not None else lam**-0.25
        window = max(SMOOTH_FIT_DEGREE + 3, int(round(np.pi / (top * h))))
        fit = (SMOOTH_FIT_DEGREE, window)
    w, dw, jumps = _record_derivative(omega.reshape(-1), h, end, periodic, gain, fit)
    w, dw = w.reshape(C, P), dw.reshape(C, P)
    if t is None or regularisation is not None:
        t = _cumulative_time(w.reshape(-1), h, t0).reshape(C, P)
    theta = np.arange(P) * h
    train = crank_train(engine, fidelity, grid_deg)
    val, der = train.at(jnp.asarray(theta))
    inertia, dinertia, k = (np.asarray(a) for a in (val[:, COL_I], der[:, COL_I], val[:, COL_K]))
    net = inertia * w * dw + 0.5 * dinertia * w**2
    explicit = k * w**2
    fa, fb, fc = (np.asarray(v, dtype=np.float64) for v in friction_coefficients(engine, friction))
    m_f = fa + fb * w + fc * w**2
    m_l = np.zeros_like(w) if load_m is None else np.asarray(load_m.torque(jnp.asarray(w), jnp.asarray(t)))
    torque = net - explicit + m_f + m_l
    return IndicatedTorque(
        theta=theta,
        omega=w,
        domega_dtheta=dw,
        t=t,
        torque=torque,
        net_torque=net,
        inertia_torque=explicit,
        friction_torque=m_f,
        load_torque=m_l,
        end_jumps=jumps,
        cycle_rad=cyc,
        strokes=int(engine.strokes),
        fidelity=fidelity,
        regularisation=regularisation,
        max_order=K,
        tikhonov_weight=lam,
    )


# ----------------------------------------------------------------------------- harmonic method
def harmonic_response(
    inertia_coefficients: ArrayLike,
    mean_omega: float,
    revs: float,
    out_orders: int,
    explicit_coefficients: ArrayLike | None = None,
    loss_slope: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """The linearised response of the crank train: gas-torque harmonics from speed harmonics.

    **Arguments** (two-sided complex Fourier coefficients over one cycle, index n for
    order n/revs, length 2N+1 centred on n = 0):
    - ``inertia_coefficients``: of I(θ) [kg·m²], N ≥ 2·``out_orders``.
    - ``mean_omega``: ω̄ [rad/s].
    - ``revs``: revolutions per cycle (2 four-stroke).
    - ``out_orders``: how many harmonics n = 1…n_out to return.
    - ``explicit_coefficients``: of k(θ) [kg·m²] (``"constant"`` fidelity), or None.
    - ``loss_slope``: dM_loss/dω at ω̄ [N·m·s] (friction plus load).

    **Returns:** (offset (n_out,), matrix (n_out, 2N+1)): the two-sided gas-torque
    coefficients m_n = offset_n + Σ_j matrix[n, j]·w_j for n = 1…n_out, with w the
    two-sided speed-fluctuation coefficients on the same index range (w_0 = 0).
    """
    c_i = np.asarray(inertia_coefficients)
    N = (c_i.size - 1) // 2
    c_k = np.zeros_like(c_i) if explicit_coefficients is None else np.asarray(explicit_coefficients)
    n = np.arange(1, out_orders + 1)
    j = np.arange(-N, N + 1)
    diff = n[:, None] - j[None, :]
    inside = np.abs(diff) <= N
    conv_i = np.where(inside, c_i[np.clip(diff + N, 0, 2 * N)], 0.0)
    conv_k = np.where(inside, c_k[np.clip(diff + N, 0, 2 * N)], 0.0)
    nu = n / revs
    wbar = mean_omega
    matrix = 1j * nu[:, None] * wbar * conv_i - 2 * wbar * conv_k + loss_slope * (diff == 0)
    offset = 1j * nu * 0.5 * wbar**2 * c_i[N + n] - wbar**2 * c_k[N + n]
    return offset, matrix


def _cycle_trends(omega, end, cycle, periodic):
    """Each cycle's linear trend dω̄/dθ [rad/s per rad] of a continuous record: the change
    of ω from its first sample to the next cycle's (the periodic part cancels there); the last
    cycle's from the record's end sample, else extrapolated from the two before it."""
    C = omega.shape[0]
    if periodic or (C == 1 and end is None):
        return np.zeros(C)
    starts = omega[:, 0] if end is None else np.append(omega[:, 0], end)
    s = np.diff(starts) / cycle
    if end is None:
        s = np.append(s, s[-1] if C < 3 else 2 * s[-1] - s[-2])
    return s


def harmonic_torque(
    engine: Engine,
    speed: LogAnalysis | SpeedResult | ArrayLike,
    *,
    max_order: float = 6.0,
    speed_max_order: float | None = None,
    load: Load | float | None = None,
    friction: Friction | bool | None = None,
    fidelity: str = "variable",
    grid_deg: float = 0.25,
    cycle_rad: float | None = None,
) -> HarmonicTorque:
    """Gas-torque harmonics from the low orders of speed (the harmonic method).

    **Derivation.** With E = ½·I(θ)·ω², the equation of motion is exactly
    dE/dθ = M_gas + k·ω² − M_loss(ω). Write ω = ω̄ + ω̄′·(θ − Θ/2) + w(θ) per cycle (angle
    mean ω̄, linear trend ω̄′ from ω at the cycle's start and at the next one's, fluctuation
    w of zero mean) and expand to first order in w and ω̄′ (the trend taken with Ī):

        E ≈ ½·I·ω̄² + ω̄·I·w + ω̄·Ī·ω̄′·(θ − Θ/2)

    neglecting ½·I·w², of relative size |w|/(2ω̄) against ω̄·I·w.

    With two-sided harmonics x_n of order ν_n = n/revs (x(θ) = Σ x_n·e^{iν_nθ}) and the
    convolution (I∗w)_n = Σ_j I_{n−j}·w_j (I(θ)'s own orders couple the speed orders):

        M_gas,n = iν_n·[½·ω̄²·I_n + ω̄·(I∗w)_n] − ω̄²·k_n − 2ω̄·(k∗w)_n + M_loss′(ω̄)·w_n,  n ≥ 1
        M_gas,0 = Ī·ω̄·ω̄′ − ω̄²·k_0 + M_loss(ω̄)

    (:func:`harmonic_response`). For constant inertia (I = J, k = 0, no losses) this is
    M_n = iν_n·J·ω̄·w_n: the classic response, exact for E and wrong only by the ½·J·w²
    term, which puts iν·½·J·(w∗w)_n at the sums and differences of the speed orders —
    for a pure sinusoidal speed ω̄ + W·cos νθ the order ν is exact and order 2ν carries
    ½·ν·J·W², W/(2ω̄) of the order ν's amplitude (the tests check both). For a real
    engine the neglected term is about δ/4 of the dynamic torque at each order (δ the speed irregularity, at most twice
    max|w|/ω̄; ``relative_speed_amplitude`` reports max|w|/ω̄ per cycle). The mean
    needs the load: with ``load=None`` it is the friction plus the acceleration torque.

    **Arguments:**
    - ``engine``, ``speed``, ``load``, ``friction``, ``fidelity``, ``grid_deg``,
      ``cycle_rad``: as :func:`indicated_torque` (a steady or continuous record; each
      cycle's linear trend is the change of ω from its start to the next cycle's start).
    - ``max_order``: the highest gas-torque order returned.
    - ``speed_max_order``: the highest speed order used (default ``max_order`` plus twice
      the firing order, so that I(θ)'s orders couple the ones returned); below the grid's
      Nyquist.

    **Returns:** a :class:`HarmonicTorque`.
    """
    omega, end, t, _, periodic = _speed_input(engine, speed, cycle_rad, None, None)
    C, P = omega.shape
    revs = engine.strokes / 2
    nyq = (P - 1) // 2
    n_out = int(np.floor(float(max_order) * revs + 1e-9))
    if not (np.isfinite(max_order) and 1 <= n_out <= nyq):
        raise EngineError(
            f"max_order = {max_order!r}: must be at least {1 / revs:g} and below the grid's Nyquist "
            f"order {nyq / revs:g}"
        )
    if speed_max_order is None:
        n_s = min(n_out + 2 * engine.cylinders, nyq)  # the firing order is `cylinders` cycle harmonics
    else:
        n_s = int(np.floor(float(speed_max_order) * revs + 1e-9))
        if not (n_out <= n_s <= nyq):
            raise EngineError(
                f"speed_max_order = {speed_max_order!r}: must lie between max_order and the grid's "
                f"Nyquist order {nyq / revs:g}"
            )
    load_m = _load_module(load)
    cyc = _engine_cycle(engine)
    h = cyc / P
    theta = np.arange(P) * h
    wbar = np.mean(omega, axis=1)
    slope = _cycle_trends(omega, end, cyc, periodic)
    ramp = slope[:, None] * (theta[None, :] - cyc / 2)
    W = np.fft.rfft(omega - ramp, axis=1) * (2.0 / P)
    speed_c = W[:, 1 : n_s + 1]
    # crank-train coefficients: I and k over the cycle, two-sided up to 2·n_s
    train = crank_train(engine, fidelity, grid_deg)
    val, _ = train.at(jnp.asarray(theta))
    N = n_s + n_out
    if N > nyq:
        N = nyq
    ci = np.fft.fft(np.asarray(val[:, COL_I])) / P
    ck = np.fft.fft(np.asarray(val[:, COL_K])) / P
    idx = np.arange(-N, N + 1) % P
    ci, ck = ci[idx], ck[idx]
    fa, fb, fc = (float(v) for v in friction_coefficients(engine, friction))
    out = np.zeros((C, n_out), complex)
    mean = np.zeros(C)
    for c in range(C):
        wb = wbar[c]
        if load_m is not None:
            l0, dl = jax.value_and_grad(lambda x: load_m.torque(x, 0.0))(jnp.asarray(wb))
            l0, dl = float(l0), float(dl)
        else:
            l0 = dl = 0.0
        offset, matrix = harmonic_response(ci, wb, revs, n_out, ck, fb + 2 * fc * wb + dl)
        wj = np.zeros(2 * N + 1, complex)
        wj[N + 1 : N + 1 + n_s] = speed_c[c] / 2
        wj[N - n_s : N] = np.conj(speed_c[c][::-1]) / 2
        out[c] = 2 * (offset + matrix @ wj)
        mean[c] = ci[N].real * wb * slope[c] - wb**2 * ck[N].real + fa + fb * wb + fc * wb**2 + l0
    # max |w|/ω̄ of the fluctuation rebuilt from the orders used
    fine = np.zeros((C, P // 2 + 1), complex)
    fine[:, 1 : n_s + 1] = speed_c * (P / 2)
    wfl = np.fft.irfft(fine, n=P, axis=1)
    rel = np.max(np.abs(wfl), axis=1) / wbar
    return HarmonicTorque(
        torque=TorqueOrders(np.arange(1, n_out + 1) / revs, mean, out),
        speed_orders=np.arange(1, n_s + 1) / revs,
        speed_complex=speed_c,
        mean_omega=wbar,
        trend=slope,
        relative_speed_amplitude=rel,
    )
