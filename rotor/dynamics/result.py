"""The result of a steady-state or transient run: ω(θ, t), δ, orders, plots, tables.

Arrays are JAX float64 arrays, so ``jax.grad`` flows through ``.delta`` and
``.orders()``; ``.to_pandas()``, ``.summary()``, ``.to_json_dict()`` and ``.plot()`` are
for people (the result protocol of :mod:`rotor.results`).
"""

from __future__ import annotations

import dataclasses
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from ..cycles import array_module, cycle_delta, cycle_ramp, cycle_slopes, cycle_spectrum, extreme_index
from ..programs import kept_program
from ..results import Result, json_safe
from ..units import RPM_PER_RAD_S

__all__ = ["SpeedResult", "Orders", "CycleSummary", "TORQUE_PARTS", "cycle_extremes"]

_ORDER_KEYS = ("order", "speed_amplitude_rad_s", "speed_phase_rad", "torque_amplitude_Nm", "torque_phase_rad")
#: the torque's parts (a steady state): field of :class:`SpeedResult`, key of :class:`Orders`, heading
TORQUE_PARTS = (
    ("gas_torque", "gas_torque_amplitude_Nm", "gas [N·m]"),
    ("reciprocating_torque", "reciprocating_torque_amplitude_Nm", "recip. [N·m]"),
    ("inertia_term_torque", "inertia_term_amplitude_Nm", "−I′ω²/2 [N·m]"),
    ("total_torque", "total_torque_amplitude_Nm", "total [N·m]"),
)
#: what the torque columns of a summary are, in one line
TORQUE_PARTS_NOTE = (
    "torque amplitudes: gas; recip. = the reciprocating masses' inertia torque (textbook, at the speed); "
    "−I′ω²/2 = the varying inertia's term; total = gas − I′ω²/2, the torque that drives the speed"
)

#: the heading and the note's words of the reciprocating inertia torque and the varying
#: inertia's term where their amplitudes are the same at every order (one column for both)
_SAME_HEAD = "recip.=I′ω²/2"
_SAME_NOTE = (
    "torque amplitudes: gas; recip.=I′ω²/2 = the reciprocating masses' inertia torque (textbook, at the speed), "
    "the same amplitude as the varying inertia's term −I′ω²/2 at every order; total = gas − I′ω²/2, the torque "
    "that drives the speed"
)


def distinct_parts(rows: list[dict], parts: list[tuple[str, str]]) -> tuple[list[tuple[str, str]], str]:
    """The torque columns (key, heading) of a summary's order table, one per distinct
    quantity: the reciprocating inertia torque and the varying inertia's term as one column
    where their amplitudes agree at every order of ``rows`` (to 1e-9 of the largest; the
    same function of θ where I(θ) carries the reciprocating inertia), and the note that says
    what the columns are."""
    keys = dict(parts)
    a, b = "reciprocating_torque_amplitude_Nm", "inertia_term_amplitude_Nm"
    if a in keys and b in keys and rows:
        x, y = (np.asarray([r[k] for r in rows]) for k in (a, b))
        if np.all(np.abs(x - y) <= 1e-9 * max(float(np.max(np.abs(x))), 1e-300)):
            return [(k, _SAME_HEAD if k == a else h) for k, h in parts if k != b], _SAME_NOTE
    return parts, TORQUE_PARTS_NOTE


@dataclasses.dataclass(frozen=True, eq=False, repr=False)
class Orders(Result):
    """Harmonics of speed and engine torque by engine order (cycles per revolution).

    x(θ) = mean + Σ amplitude·cos(order·θ + phase), θ the engine crank angle from the
    start of the analysed cycle [rad]. ``order`` 0.5, 1, 1.5, … for a four-stroke engine.

    **Fields:** ``order`` [per revolution]; ``speed_amplitude_rad_s`` [rad/s];
    ``speed_phase_rad`` [rad]; ``torque_amplitude_Nm`` and ``torque_phase_rad``: the
    engine torque of the run's equation (the gas torque; at the ``"constant"`` fidelity
    with the textbook inertia torque added) [N·m, rad]; ``engine_name``. A steady state
    also has the amplitudes [N·m] of the torque's parts: ``gas_torque_amplitude_Nm``,
    ``reciprocating_torque_amplitude_Nm`` (the textbook inertia torque of the reciprocating
    masses at the sample's speed), ``inertia_term_amplitude_Nm`` (−½·I′(θ)·ω², the varying
    inertia's term of the equation; zero at the ``"constant"`` fidelity) and
    ``total_torque_amplitude_Nm`` (the torque that drives the speed: gas plus the inertia
    torque of the moving masses); None where not known (a transient run).
    """

    order: np.ndarray
    speed_amplitude_rad_s: jnp.ndarray
    speed_phase_rad: jnp.ndarray
    torque_amplitude_Nm: jnp.ndarray
    torque_phase_rad: jnp.ndarray
    engine_name: str = ""
    gas_torque_amplitude_Nm: jnp.ndarray | None = None
    reciprocating_torque_amplitude_Nm: jnp.ndarray | None = None
    inertia_term_amplitude_Nm: jnp.ndarray | None = None
    total_torque_amplitude_Nm: jnp.ndarray | None = None

    @property
    def _keys(self) -> tuple[str, ...]:
        return _ORDER_KEYS + tuple(k for _, k, _ in TORQUE_PARTS if getattr(self, k) is not None)

    def to_list(self) -> list[dict]:
        """One dict per order with the keys of the fields that are known (plain floats)."""
        keys = self._keys
        cols = [np.asarray(getattr(self, k), dtype=np.float64) for k in keys]
        return [{k: float(v) for k, v in zip(keys, row)} for row in zip(*cols)]

    def summary(self) -> str:
        """The orders as a table: speed amplitude [rad/s and rpm] and the torque amplitudes
        [N·m], each column named (gas, reciprocating inertia, −I′ω²/2, total where known)."""
        parts = [(k, head) for _, k, head in TORQUE_PARTS if getattr(self, k) is not None]
        rows = self.to_list()
        parts, note = distinct_parts(rows, parts)
        if parts:
            heads = "".join(f"  {head:>14}" for _, head in parts)
            lines = [
                f"{self.engine_name + ': ' if self.engine_name else ''}speed and torque harmonics by engine order",
                f"  ({note})",
                f"  order  speed amplitude [rad/s]      [rpm]{heads}",
            ]
        else:
            lines = [
                f"{self.engine_name + ': ' if self.engine_name else ''}speed and torque harmonics by engine order",
                "  order  speed amplitude [rad/s]  [rpm]      engine (gas) torque amplitude [N·m]",
            ]
        shown = rows if len(rows) <= 50 else rows[:50]
        for o in shown:
            line = f"  {o['order']:5.1f}  {o['speed_amplitude_rad_s']:24.5f}  {o['speed_amplitude_rad_s'] * RPM_PER_RAD_S:9.4f}"
            if parts:
                line += "".join(f"  {o[k]:14.2f}" for k, _ in parts)
            else:
                line += f"  {o['torque_amplitude_Nm']:22.2f}"
            lines.append(line)
        if len(rows) > len(shown):
            lines.append(f"  … {len(rows) - len(shown)} more orders (to_pandas() has them all)")
        return "\n".join(lines) + "\n"

    def to_pandas(self) -> Any:
        """One row per order: ``order``, ``speed_amplitude_rad_s``, ``speed_phase_rad``,
        ``torque_amplitude_Nm``, ``torque_phase_rad`` and the torque parts' amplitudes where
        known (``gas_torque_amplitude_Nm``, ``reciprocating_torque_amplitude_Nm``,
        ``inertia_term_amplitude_Nm``, ``total_torque_amplitude_Nm``)."""
        import pandas as pd

        return pd.DataFrame({k: np.asarray(getattr(self, k), dtype=np.float64) for k in self._keys})

    def to_json_dict(self) -> dict:
        """``{"engine": name, "orders": [one dict per order]}``."""
        return json_safe({"engine": self.engine_name, "orders": self.to_list()})

    def plot(self, ax: Any = None) -> Any:
        """Bars of the speed amplitude [rad/s] by engine order on ``ax`` (a new figure if None);
        returns the Axes."""
        from ..plotting.speed import plot_orders

        amp = np.asarray(self.speed_amplitude_rad_s)
        return plot_orders(np.asarray(self.order), amp, f"{self.engine_name}: speed harmonics", ax=ax)


def _plural(n: int, noun: str) -> str:
    """``1 cycle``, ``2 cycles``."""
    return f"{n} {noun}" if n == 1 else f"{n} {noun}s"


def parabola_peak(y0, y1, y2, sign):
    """Extreme value of the parabola through three equally spaced samples (y1 the extreme sample)."""
    xp = array_module(y0, y1, y2)
    curv = y0 - 2 * y1 + y2
    ok = sign * curv < 0
    safe = xp.where(ok, curv, -sign)
    return xp.where(ok, y1 - (y0 - y2) ** 2 / (8 * safe), y1)


def _row_extremes(xp, x, slopes, cycle_rad):
    """(max, min) of each row of x (rows: consecutive cycles sampled uniformly in angle)
    with the row's linear trend ``slopes`` [per rad] removed (:func:`rotor.cycles.cycle_ramp`),
    refined by a parabola through the extreme sample and its neighbours (the neighbours in
    the next and previous rows detrended by the same row's line; none past the first and
    last row); ``xp``: numpy or jax.numpy."""
    C, P = x.shape
    h = cycle_rad / P
    xd = x - cycle_ramp(slopes, P, cycle_rad)
    flat = x.reshape(-1)
    rows = xp.arange(C)

    def line(j):  # the row's trend at sample j of the row (j may be −1 or P)
        return slopes * (j * h - cycle_rad / 2)

    out = []
    for sign in (1.0, -1.0):
        j = extreme_index(xp, xd, sign > 0)
        y1 = xd[rows, j]
        i = j + rows * P
        interior = (i > 0) & (i < flat.size - 1)
        left = flat[xp.clip(i - 1, 0, flat.size - 1)] - line(j - 1)
        right = flat[xp.clip(i + 1, 0, flat.size - 1)] - line(j + 1)
        out.append(xp.where(interior, parabola_peak(left, y1, right, sign), y1))
    return out[0], out[1]


@kept_program()
@jax.jit
def _compiled_extremes(x, slopes, cycle_rad):
    return _row_extremes(jnp, x, slopes, cycle_rad)


def periodic_extremes(xp, omega):
    """The highest and lowest value of each periodic row of ``omega`` (one period sampled
    uniformly along the last axis: a steady state's speed [rad/s], a shaft's in a forced
    response), each refined by a parabola through the extreme sample and its neighbours
    across the period's ends, and the extreme samples themselves: (high, low, highest
    sample, lowest sample), shape ``omega.shape[:-1]``; ``xp``: numpy or jax.numpy. One
    period has no trend to remove. :attr:`SpeedResult.delta` of a steady state, the steady
    state's compiled program (which hands δ back with the result) and the torsional forced
    response's range compute here."""
    P = omega.shape[-1]

    def at(j):
        return xp.take_along_axis(omega, j % P, axis=-1)[..., 0]

    out = []
    for sign in (1.0, -1.0):
        j = extreme_index(xp, omega, sign > 0)[..., None]
        sample = at(j)
        out.append((parabola_peak(at(j - 1), sample, at(j + 1), sign), sample))
    (high, highest), (low, lowest) = out
    return high, low, highest, lowest


def _extremes(x, slopes, cycle_rad):
    """:func:`_row_extremes` compiled where ``x`` or ``slopes`` is traced, in NumPy for
    concrete values (a compiled call and the copies back cost more than the arithmetic)."""
    if array_module(x, slopes) is np:
        x, slopes = np.asarray(x, dtype=np.float64), np.asarray(slopes, dtype=np.float64)
        return _row_extremes(np, x, slopes, float(cycle_rad))
    return _compiled_extremes(x, slopes, cycle_rad)


def _flat_range(xp, x):
    """(max, min) over all of x (rows: consecutive cycles) with parabolic refinement at the
    sample (none past the first and last sample); ``xp``: numpy or jax.numpy."""
    flat = x.reshape(-1)
    out = []
    for sign in (1.0, -1.0):
        i = extreme_index(xp, flat, sign > 0)
        interior = (i > 0) & (i < flat.size - 1)
        left = flat[xp.clip(i - 1, 0, flat.size - 1)]
        right = flat[xp.clip(i + 1, 0, flat.size - 1)]
        out.append(xp.where(interior, parabola_peak(left, flat[i], right, sign), flat[i]))
    return out[0], out[1]


@kept_program()
@jax.jit
def _compiled_range(x):
    return _flat_range(jnp, x)


def _range(x):
    """:func:`_flat_range` compiled where ``x`` is traced, in NumPy for concrete values."""
    if array_module(x) is np:
        return _flat_range(np, np.asarray(x, dtype=np.float64))
    return _compiled_range(x)


def cycle_extremes(x: ArrayLike, slopes: ArrayLike, cycle_rad: float) -> tuple[Array, Array, Array, Array]:
    """Per row of ``x`` (consecutive cycles sampled uniformly in angle, speed [rad/s]):
    (max, min) with the row's linear trend ``slopes`` [rad/s per rad] removed and (max, min)
    of the raw row, each refined by a parabola through the extreme sample and its neighbours
    in the flattened rows (none past the first and last row). ``cycle_rad``: the cycle [rad].

    The first and last rows of a window of a longer run serve as context: the rows between
    get the figures that :class:`SpeedResult` computes over the whole run."""
    xp = array_module(x, slopes)  # NumPy for concrete rows: no JAX operation on them
    rows = xp.asarray(x, dtype=xp.float64)
    dmax, dmin = _extremes(rows, xp.asarray(slopes, dtype=xp.float64), cycle_rad)
    rmax, rmin = _extremes(rows, xp.zeros(rows.shape[0]), cycle_rad)
    return dmax, dmin, rmax, rmin


def _spectrum(x, slopes, cycle_rad):
    """:func:`rotor.cycles.cycle_spectrum` of the rows ``x`` with given trends ``slopes``."""
    xp = array_module(x, slopes)
    P = x.shape[1]
    w = x - cycle_ramp(xp.asarray(slopes), P, cycle_rad)
    return xp.fft.rfft(w, axis=1) * (2.0 / P)


@dataclasses.dataclass(frozen=True, eq=False, repr=False)
class CycleSummary:
    """Per-cycle figures of every complete cycle of a transient run whose samples were not
    all kept (``simulate(..., keep_cycles=N)``), so that δ, the speeds and the range come
    out as they would from every sample.

    **Per cycle** (numpy arrays, shape (cycles,)): ``t_start_s``, ``t_end_s`` [s];
    ``mean_omega`` (time-mean speed) [rad/s]; ``mean_torque_Nm`` (mean engine torque over
    the cycle's samples) [N·m]; ``max_omega``, ``min_omega`` (raw sampled extremes)
    [rad/s]; ``delta`` (δ with the cycle's linear trend removed) [-]; ``range_max``,
    ``range_min`` (the raw extremes refined by a parabola) [rad/s]. **Over the run:**
    ``omega_max_all``, ``omega_min_all`` (every sample, those after the last whole cycle
    included) [rad/s]; ``theta_first_rad`` [rad] and ``t_first_s`` [s] of the first sample.
    """

    t_start_s: np.ndarray
    t_end_s: np.ndarray
    mean_omega: np.ndarray
    mean_torque_Nm: np.ndarray
    max_omega: np.ndarray
    min_omega: np.ndarray
    delta: np.ndarray
    range_max: np.ndarray
    range_min: np.ndarray
    omega_max_all: float
    omega_min_all: float
    theta_first_rad: float
    t_first_s: float


@dataclasses.dataclass(frozen=True, eq=False, repr=False)
class SpeedResult(Result):
    """ω(θ) and friends from :func:`rotor.steady_state` or :func:`rotor.simulate`.

    **Arrays** (one entry per sample): ``t`` [s], ``theta`` [rad], ``omega`` [rad/s],
    ``accel`` (dω/dt) [rad/s²], ``torque`` (engine torque: gas, plus the explicit
    inertia torque at the ``"constant"`` fidelity) [N·m], ``load_torque`` (friction and
    load) [N·m]. ``imep_pa``: each cylinder's IMEP in each cycle (cycles, cylinders) [Pa].

    **Attributes:** ``method``, ``fidelity``, ``kind`` (``"steady"``/``"transient"``),
    ``stalled`` and, if so, ``stall_time_s`` and ``stall_angle_rad``; ``cycle_rad``,
    ``strokes``, ``points_per_cycle`` (samples per cycle of the uniform part);
    ``uniform_cycles``: how many whole cycles are sampled uniformly in θ; ``engine_name``;
    ``wall_s``: wall-clock time of the run [s].

    **Irregularity:** ``delta_per_cycle`` (each complete cycle's δ with its linear trend
    removed, as :func:`rotor.analyze_log` defines it), ``delta`` (the last cycle's; for a
    steady state its one periodic cycle's, the classic (ω_max − ω_min)/ω_mean) and
    ``speed_range_ratio`` ((ω_max − ω_min)/ω_mean over the whole run, drift included).

    **The operating point:** ``load_torque_Nm`` (the load torque carried, friction apart;
    the time mean of a speed-dependent load) [N·m], ``fuel_scale`` (the combustion as a
    multiple of the engine file's, the mean over the cylinders) [-] and ``solved_for``:
    which of the two was solved (``"load"``, ``"fuel_scale"``) while the other was given, or
    None (both given, a transient run). Either may be None where it is not one number (a
    load step, a governor).

    **A steady state** also has ``period_s`` (the cycle's duration) [s];
    the torque's parts over the cycle [N·m]: ``gas_torque``, ``reciprocating_torque`` (the
    textbook inertia torque of the reciprocating masses at the sample's speed),
    ``inertia_term_torque`` (−½·I′(θ)·ω², the varying inertia's term of the equation; zero at
    the ``"constant"`` fidelity, whose ``torque`` holds the textbook inertia torque) and
    ``total_torque`` (``torque`` + ``inertia_term_torque``: the torque that drives the speed,
    I(θ)·dω/dt = total − load − friction);
    ``excess_work_J`` (Shishkov, "Dinamika dvigatelei", SUSU 2014, §3.2.12: the largest swing of the work of the textbook
    total torque) [J] and ``textbook_delta`` (its δ ≈ L_excess/(J·ω²)) [-];
    ``periodicity_error`` (|E(Θ) − E(0)|/E(0), shooting only) [-]; ``note``: why the
    method is what it is, where ``method="auto"`` did not take the closed form; ``converged``: whether
    the solver reached the periodic solution and the kinetic energy stays above 10⁻⁴ of
    its mean (a JAX bool under ``jit``/``vmap``; False only where the steady state was
    asked for with ``throw=False``, which returns the finding instead of raising it).

    A result is a pytree: a compiled function may return it (its words and counts are the
    structure, its numbers and arrays the leaves).

    **A transient run** may have ``steps_per_cycle`` (``method="grid"``),
    ``solver_steps`` (accepted steps of ``method="angle"``), ``fuel`` (the governor's
    fuel scale at each sample) [-] and ``incomplete`` (why the run ended before its last
    cycle, if it did).
    """

    t: jnp.ndarray
    theta: jnp.ndarray
    omega: jnp.ndarray
    accel: jnp.ndarray
    torque: jnp.ndarray
    load_torque: jnp.ndarray
    imep_pa: jnp.ndarray
    method: str
    fidelity: str
    kind: str
    strokes: int
    cycle_rad: float
    points_per_cycle: int
    uniform_cycles: int
    stalled: bool = False
    stall_time_s: float | None = None
    stall_angle_rad: float | None = None
    engine_name: str = ""
    wall_s: float = float("nan")
    # the steady state
    period_s: ArrayLike | None = None
    load_torque_Nm: ArrayLike | None = None
    fuel_scale: ArrayLike | None = None
    solved_for: str | None = None
    gas_torque: jnp.ndarray | None = None
    reciprocating_torque: jnp.ndarray | None = None
    inertia_term_torque: jnp.ndarray | None = None
    total_torque: jnp.ndarray | None = None
    excess_work_J: ArrayLike | None = None
    textbook_delta: ArrayLike | None = None
    periodicity_error: ArrayLike | None = None
    converged: ArrayLike = True
    note: str | None = None
    # a transient run
    steps_per_cycle: int | None = None
    solver_steps: int | None = None
    fuel: jnp.ndarray | None = None
    incomplete: str | None = None
    # a long run that kept only its last cycles' samples (simulate(..., keep_cycles=N))
    first_kept_cycle_index: int = 0
    cycle_summary: CycleSummary | None = None
    # a steady state's δ computed with its arrays (:func:`periodic_extremes`), with the ω,
    # period and cycle it belongs to: (omega, period_s, cycle_rad, delta), used while ω and the
    # period are the same objects and the cycle the same number
    _known_delta: tuple[Any, Any, float, Any] | None = dataclasses.field(default=None, compare=False)

    # ------------------------------------------------------------------ cycles
    @property
    def _streamed(self) -> bool:
        """True where the early cycles' samples were dropped: the per-cycle figures come from
        :attr:`cycle_summary`."""
        return self.first_kept_cycle_index > 0 and self.cycle_summary is not None

    @property
    def kept_cycles(self) -> int:
        """Number of complete cycles whose samples the result holds (the last ones of the
        run: cycles ``first_kept_cycle_index + 1`` … ``uniform_cycles``, counted from 1)."""
        return self.uniform_cycles - self.first_kept_cycle_index

    def _cycle_matrix(self, x: jnp.ndarray) -> jnp.ndarray:
        n = self.kept_cycles * self.points_per_cycle
        return array_module(x).asarray(x)[:n].reshape(self.kept_cycles, self.points_per_cycle)

    def _need_cycles(self) -> None:
        if self.uniform_cycles < 1:
            raise ValueError(
                "the run holds no complete cycle sampled in the angle domain (it stalled or started from rest "
                "within the first cycle): δ and orders need at least one"
            )

    @property
    def cycles(self) -> int:
        """Number of complete cycles (uniformly sampled in θ)."""
        return self.uniform_cycles

    @property
    def mean_omega(self) -> Array:
        """Time-mean speed over the whole run, angle travelled / time taken [rad/s]."""
        if self.kind == "steady":
            return self.cycle_rad / array_module(self.period_s).asarray(self.period_s)
        xp = array_module(self.theta, self.t)  # NumPy for a concrete run: no program for a difference
        theta, t = xp.asarray(self.theta), xp.asarray(self.t)
        if self._streamed:
            cs = self.cycle_summary
            assert cs is not None
            return (theta[-1] - cs.theta_first_rad) / (t[-1] - cs.t_first_s)
        return (theta[-1] - theta[0]) / (t[-1] - t[0])

    @property
    def mean_rpm(self) -> Array:
        """Time-mean speed over the whole run [rpm]."""
        return self.mean_omega * RPM_PER_RAD_S

    @property
    def cycle_mean_omega(self) -> Float[Array, " cycles"]:
        """Time-mean speed of each complete cycle [rad/s], shape (cycles,)."""
        self._need_cycles()
        P = self.points_per_cycle
        xp = array_module(self.t, self.omega, self.period_s)
        if self.kind == "steady":
            return xp.reshape(self.mean_omega, (1,))
        if self.cycle_summary is not None and self._streamed:
            return xp.asarray(self.cycle_summary.mean_omega)
        n = self.uniform_cycles * P
        t, omega = xp.asarray(self.t), xp.asarray(self.omega)
        t_start = t[:n:P]
        if t.shape[0] > n:  # the sample that ends the last whole cycle
            t_end = xp.concatenate([t_start[1:], t[n : n + 1]])
        else:
            last = t[n - 1] + (self.cycle_rad / P) / omega[n - 1]
            t_end = xp.concatenate([t_start[1:], xp.reshape(last, (1,))])
        return self.cycle_rad / (t_end - t_start)

    @property
    def delta_per_cycle(self) -> Float[Array, " cycles"]:
        """δ of each complete cycle [-], shape (cycles,): (ω_max − ω_min)/ω_mean of the cycle's
        speed with its linear trend removed (the trend from the neighbouring cycles' mean
        speeds, :mod:`rotor.cycles`: the definition and code of :func:`rotor.analyze_log`),
        so that a run-up or a run-down adds nothing. A steady state's single periodic cycle
        has no trend: its classic δ."""
        self._need_cycles()
        if self.cycle_summary is not None and self._streamed:
            return array_module(self.omega).asarray(self.cycle_summary.delta)
        if self.kind == "steady":  # one periodic cycle
            known = self._steady_delta()
            if known is not None:
                return array_module(known).reshape(known, (1,))
            xp = array_module(self.omega)
            high, low, _, _ = periodic_extremes(xp, xp.asarray(self.omega, dtype=xp.float64))
            return cycle_delta(xp.reshape(high, (1,)), xp.reshape(low, (1,)), self.cycle_mean_omega)
        mean = self.cycle_mean_omega
        slopes = cycle_slopes(mean, self.cycle_rad)
        hi, lo = _extremes(self._cycle_matrix(self.omega), slopes, self.cycle_rad)
        return cycle_delta(hi, lo, mean)

    @property
    def delta(self) -> Array:
        """Speed irregularity δ of the last complete cycle, its linear trend removed [-]
        (``delta_per_cycle[-1]``; for a steady state its one periodic cycle). The range of
        the speed over the whole run is :attr:`speed_range_ratio`."""
        known = self._steady_delta()
        return self.delta_per_cycle[-1] if known is None else known

    def _steady_delta(self) -> Array | None:
        """A steady state's δ computed with its arrays (:func:`periodic_extremes`), while ω,
        the period and the cycle are the ones it was computed from; else None."""
        known = self._known_delta
        if known is None or self.kind != "steady" or known[0] is not self.omega or known[1] is not self.period_s:
            return None
        if known[2] != self.cycle_rad:
            return None
        self._need_cycles()
        return known[3]

    @property
    def speed_range_ratio(self) -> Array:
        """(ω_max − ω_min)/ω_mean over all complete cycles of the run, drift included [-];
        equal to δ for a steady state, not an irregularity for a transient."""
        self._need_cycles()
        if self.cycle_summary is not None and self._streamed:
            cs = self.cycle_summary  # the refined extremes at the run's first highest and lowest sample
            hi = cs.range_max[int(np.argmax(cs.max_omega))]
            lo = cs.range_min[int(np.argmin(cs.min_omega))]
            return (hi - lo) / np.mean(cs.mean_omega)
        if self.kind == "steady":  # one periodic cycle: its δ
            return self.delta
        hi, lo = _range(self._cycle_matrix(self.omega))
        return (hi - lo) / array_module(self.omega).mean(self.cycle_mean_omega)

    @property
    def min_rpm(self) -> Array:
        """Lowest sampled speed [rpm] (of every sample, kept or not)."""
        if self.cycle_summary is not None and self._streamed:
            return array_module(self.omega).asarray(self.cycle_summary.omega_min_all) * RPM_PER_RAD_S
        xp = array_module(self.omega)
        return xp.min(xp.asarray(self.omega)) * RPM_PER_RAD_S

    @property
    def max_rpm(self) -> Array:
        """Highest sampled speed [rpm] (of every sample, kept or not)."""
        if self.cycle_summary is not None and self._streamed:
            return array_module(self.omega).asarray(self.cycle_summary.omega_max_all) * RPM_PER_RAD_S
        xp = array_module(self.omega)
        return xp.max(xp.asarray(self.omega)) * RPM_PER_RAD_S

    def orders(self, cycle: int | str = -1, max_order: float = 12.0) -> Orders:
        """Amplitude and phase of the speed and engine-torque harmonics by engine order.

        **Arguments:** ``cycle``: which complete cycle, counted from 1 over the whole run
        (default −1, the last; a negative number counts from the end), or ``"mean"`` for the
        average of the complex harmonics over all complete cycles whose samples the result
        holds; ``max_order``: the highest order returned [per revolution]. A run that kept
        only its last cycles' samples (``keep_cycles``) has the orders of those only (from
        cycle ``first_kept_cycle_index + 1``).
        """
        self._need_cycles()
        P = self.points_per_cycle
        revs = self.strokes / 2  # revolutions per cycle
        C, first = self.uniform_cycles, self.first_kept_cycle_index
        if isinstance(cycle, str) and cycle != "mean":
            raise ValueError(f"cycle = {cycle!r}: a cycle number (from 1; −1 the last) or 'mean'")
        if not isinstance(cycle, str) and (cycle == 0 or not -C <= cycle <= C):
            raise ValueError(
                f"cycle = {cycle!r}: the run has {_plural(C, 'complete cycle')}; "
                f"give 1 … {C} (cycles count from 1), a negative number from the end, or 'mean'"
            )
        index = None if isinstance(cycle, str) else (cycle - 1 if cycle > 0 else C + cycle)  # the row, from 0
        if index is not None and index < first:
            raise ValueError(
                f"cycle = {cycle!r}: only the samples of the last {_plural(self.kept_cycles, 'cycle')} were kept "
                f"(cycles {first + 1} … {C}); give one of those, or run with a larger keep_cycles"
            )
        # each cycle detrended as in rotor.analyze_log (rotor.cycles): a run-up leaks into no order
        xp = array_module(self.omega, self.torque)
        m = self._cycle_matrix(self.torque)
        if self.cycle_summary is not None and self._streamed:
            # the trends from the whole run's cycle means, as if every sample were there
            cs = self.cycle_summary
            Ws = _spectrum(
                self._cycle_matrix(self.omega), cycle_slopes(cs.mean_omega, self.cycle_rad)[first:], self.cycle_rad
            )
            Ms = _spectrum(m, cycle_slopes(cs.mean_torque_Nm, self.cycle_rad)[first:], self.cycle_rad)
        else:
            Ws = cycle_spectrum(self._cycle_matrix(self.omega), self.cycle_mean_omega, self.cycle_rad)
            Ms = cycle_spectrum(m, xp.mean(m, axis=1), self.cycle_rad)
        k_max = min(int(np.floor(max_order * revs + 1e-9)), P // 2 - 1)

        def pick(spectra):
            one = xp.mean(spectra, axis=0) if index is None else spectra[index - first]
            return one[1 : k_max + 1]

        W, M = pick(Ws), pick(Ms)
        parts = {}
        for field, key, _ in TORQUE_PARTS:
            x = getattr(self, field)
            if x is not None and not self._streamed:
                xm = self._cycle_matrix(x)
                parts[key] = xp.abs(pick(cycle_spectrum(xm, xp.mean(xm, axis=1), self.cycle_rad)))
        k = np.arange(1, k_max + 1)
        return Orders(k / revs, xp.abs(W), xp.angle(W), xp.abs(M), xp.angle(M), self.engine_name, **parts)

    # ------------------------------------------------------------------ people
    def to_json_dict(self, max_order: float = 6.0) -> dict:
        """What ``rotor steady --json`` and ``rotor simulate --json`` print: engine, kind,
        method, fidelity, cycles, mean/min/max rpm; for a transient ``kept_cycles`` (how many
        of the last complete cycles' samples the result holds: orders and plots are of
        those; every other figure covers the whole run); ``delta`` (δ of the last complete cycle,
        its linear trend removed; ``delta_of`` says so in words); for a transient also
        ``delta_max`` (the largest per-cycle δ) with ``delta_max_cycle`` (counted from 1) and
        ``speed_range_ratio`` ((ω_max − ω_min)/ω_mean over the whole run, drift included);
        the stall (``stall_cycle`` from 1, ``stall_angle_deg`` within that cycle,
        ``stall_angle_total_deg`` from the start); wall time; the operating point
        (``load_torque_Nm``, ``fuel_scale``, ``solved_for``: see the class); the steady
        state's textbook figures; and the orders of the last cycle, detrended, up to
        ``max_order`` [per revolution] (speed amplitude [rad/s], the engine torque's
        amplitude ``torque_amplitude_Nm`` and, for a steady state, its parts' [N·m]:
        ``gas_…``, ``reciprocating_…``, ``inertia_term_…``, ``total_torque_amplitude_Nm``)."""
        steady = self.kind == "steady"
        out: dict[str, Any] = {
            "engine": self.engine_name,
            "kind": self.kind,
            "method": self.method,
            "fidelity": self.fidelity,
            "cycles": int(self.uniform_cycles),
            "mean_rpm": float(self.mean_rpm),
            "min_rpm": float(self.min_rpm),
            "max_rpm": float(self.max_rpm),
            "delta": None,
            "delta_of": "the periodic cycle" if steady else "the last complete cycle, its linear trend removed",
        }
        if not steady:
            out["kept_cycles"] = int(self.kept_cycles)
        if self.uniform_cycles:
            per_cycle = np.asarray(self.delta_per_cycle)
            out["delta"] = float(per_cycle[-1])
            if not steady:
                out["delta_max"] = float(per_cycle.max())
                out["delta_max_cycle"] = int(per_cycle.argmax()) + 1
                out["speed_range_ratio"] = float(self.speed_range_ratio)
        stall_deg = None if self.stall_angle_rad is None else float(np.rad2deg(self.stall_angle_rad))
        cycle_deg = float(np.rad2deg(self.cycle_rad))
        out.update(
            {
                "stalled": bool(self.stalled),
                "stall_time_s": None if self.stall_time_s is None else float(self.stall_time_s),
                "stall_cycle": None if stall_deg is None else int(np.floor(stall_deg / cycle_deg + 1e-9)) + 1,
                "stall_angle_deg": None
                if stall_deg is None
                else stall_deg - cycle_deg * np.floor(stall_deg / cycle_deg + 1e-9),
                "stall_angle_total_deg": stall_deg,
                "wall_s": float(self.wall_s),
            }
        )
        out["load_torque_Nm"] = None
        out["fuel_scale"] = None
        out["solved_for"] = self.solved_for
        if self.note:
            out["note"] = self.note
        for key in ("load_torque_Nm", "fuel_scale", "excess_work_J", "textbook_delta", "periodicity_error"):
            v = getattr(self, key)
            if v is not None:
                out[key] = float(v) if np.ndim(v) == 0 else np.asarray(v).tolist()
        if self.uniform_cycles:
            o = self.orders(max_order=max_order)
            keys = ("order", "speed_amplitude_rad_s", "torque_amplitude_Nm") + tuple(
                k for _, k, _ in TORQUE_PARTS if getattr(o, k) is not None
            )
            out["orders"] = [{k: d[k] for k in keys} for d in o.to_list()]
        else:
            out["orders"] = []
        return json_safe(out)

    def summary(self, max_order: float = 6.0) -> str:
        """What ``rotor steady`` and ``rotor simulate`` print: speeds, δ (and which), the
        steady state's balance, a stall, and the orders up to ``max_order`` [per revolution]."""
        s = self.to_json_dict(max_order)
        lines = [
            f"{s['engine']}: {s['kind']} run, method {s['method']}, {s['fidelity']} inertia, "
            f"{_plural(s['cycles'], 'complete cycle')}",
            f"  mean speed      {s['mean_rpm']:10.2f} rpm   (min {s['min_rpm']:.2f}, max {s['max_rpm']:.2f})",
        ]
        if s["delta"] is not None:
            lines.append(f"  irregularity δ  {s['delta']:10.5f}      (1/δ = {1 / s['delta']:.1f}; {s['delta_of']})")
        if "delta_max" in s and s["cycles"] > 1:
            lines.append(f"  largest δ       {s['delta_max']:10.5f}      (cycle {s['delta_max_cycle']}, trend removed)")
        if "speed_range_ratio" in s:
            lines.append(
                f"  speed range     {s['speed_range_ratio']:10.5f}      ((max − min)/mean over the run, drift included)"
            )
        if "textbook_delta" in s:
            lines.append(
                f"  textbook δ      {s['textbook_delta']:10.5f}      (Shishkov (2014) §3.2.12: L_excess / (J·ω²), "
                f"L_excess = {s['excess_work_J']:.1f} J)"
            )
        lines.extend(self.operating_point_lines())
        if s["stalled"]:
            lines.append(
                f"  STALLED at t = {s['stall_time_s']:.4f} s in cycle {s['stall_cycle']}, crank angle "
                f"{s['stall_angle_deg']:.1f}° of the cycle"
            )
        if self.incomplete:
            lines.append(f"  note: {self.incomplete}")
        if self.note:
            lines.append(f"  note: {self.note}")
        if self._streamed:
            lines.append(
                f"  samples kept    the last {_plural(self.kept_cycles, 'cycle')} of {s['cycles']} (keep_cycles; "
                "δ, speeds and range cover every cycle)"
            )
        if s["orders"]:
            parts = [(k, head) for _, k, head in TORQUE_PARTS if k in s["orders"][0]]
            parts, note = distinct_parts(s["orders"], parts)
            lines.append("  orders of the last cycle (trend removed):")
            if parts:
                lines.append(f"  ({note})")
                lines.append("  order  speed amplitude [rad/s]" + "".join(f"  {head:>14}" for _, head in parts))
            else:
                lines.append("  order  speed amplitude [rad/s]  engine (gas) torque amplitude [N·m]")
            for o in s["orders"]:
                line = f"  {o['order']:5.1f}  {o['speed_amplitude_rad_s']:24.5f}"
                if parts:
                    line += "".join(f"  {o[k]:14.2f}" for k, _ in parts)
                else:
                    line += f"  {o['torque_amplitude_Nm']:22.2f}"
                lines.append(line)
        lines.append(f"  wall time {s['wall_s']:.3f} s")
        return "\n".join(lines) + "\n"

    def operating_point_lines(self) -> list[str]:
        """The load and the fuel scale, each marked given or solved, as summary lines."""
        lines = []
        load, fuel, solved = self.load_torque_Nm, self.fuel_scale, self.solved_for
        if load is not None and np.ndim(load) == 0:
            how = (
                "solved: the load that the engine's mean torque carries at this fuelling"
                if solved == "load"
                else "given"
            )
            lines.append(f"  load torque     {float(np.asarray(load)):10.2f} N·m ({how})")
        if fuel is not None and np.ndim(fuel) == 0:
            how = "solved: the fuelling that carries the load" if solved == "fuel_scale" else "given"
            lines.append(
                f"  fuel scale      {float(np.asarray(fuel)):10.4f}      ({how}; 1 = the engine file's pressure)"
            )
        return lines

    def to_pandas(self) -> Any:
        """The samples as a ``pandas.DataFrame`` (one row per sample, SI units in the names):
        those the result holds (after a ``keep_cycles`` run the last cycles' only; ``cycle``
        counts over the whole run, from 1). ``torque_Nm`` is the engine torque of the
        equation; a steady state adds its parts, ``gas_torque_Nm``,
        ``reciprocating_torque_Nm``, ``inertia_term_torque_Nm`` and ``total_torque_Nm``."""
        import pandas as pd

        cycle = np.floor(np.asarray(self.theta) / self.cycle_rad + 1e-9).astype(int) + 1
        cols = {
            "t_s": np.asarray(self.t),
            "theta_rad": np.asarray(self.theta),
            "angle_deg": np.rad2deg(np.asarray(self.theta)),
            "cycle": cycle,
            "omega_rad_s": np.asarray(self.omega),
            "rpm": np.asarray(self.omega) * RPM_PER_RAD_S,
            "accel_rad_s2": np.asarray(self.accel),
            "torque_Nm": np.asarray(self.torque),
        }
        for field, _, _ in TORQUE_PARTS:
            x = getattr(self, field)
            if x is not None:
                cols[f"{field}_Nm"] = np.asarray(x)
        cols["load_torque_Nm"] = np.asarray(self.load_torque)
        return pd.DataFrame(cols)

    def plot(self, ax: Any = None, kind: str = "cycle") -> Any:
        """Draw on ``ax`` (a new figure if None) and return it.

        ``kind``: ``"cycle"`` (rpm over the last cycle against crank angle, titled with
        its δ), ``"time"`` (rpm against time over the run), ``"torque"`` (engine and load
        torque over the last cycle; a steady state's total torque, gas plus the inertia of
        the moving masses, against the load, with the gas torque thin) or ``"orders"`` (speed harmonics [rad/s] of the last
        cycle by engine order, detrended like δ). After a ``keep_cycles`` run, the time plot
        shows the kept cycles only and its title says so.
        """
        from ..plotting.speed import plot_cycle_torque, plot_orders, plot_speed, plot_speed_time

        kinds = ("cycle", "time", "torque", "orders")
        if kind not in kinds:
            raise ValueError(f"kind = {kind!r}: one of {', '.join(kinds)}")
        rpm = np.asarray(self.omega) * RPM_PER_RAD_S
        cycle_deg = float(np.rad2deg(self.cycle_rad))
        title = f"{self.engine_name} — {self.kind}, {self.method}, {self.fidelity} inertia"
        if kind == "time":
            stall = self.stall_time_s if self.stalled else None
            if self._streamed:
                title = f"{title}\nthe last {_plural(self.kept_cycles, 'cycle')} of {self.uniform_cycles} (keep_cycles)"
            return plot_speed_time(np.asarray(self.t), rpm, title, stall_time_s=stall, ax=ax)
        which = "" if self.kind == "steady" else " of the last cycle, trend removed"
        if kind == "orders":
            o = self.orders()
            amp = np.asarray(o.speed_amplitude_rad_s)
            return plot_orders(o.order, amp, f"{title}\norders and δ{which}: δ = {float(self.delta):.4g}", ax=ax)
        P, C = self.points_per_cycle, self.kept_cycles
        if C < 1:
            raise ValueError("the run holds no complete cycle to plot against crank angle")
        sl = slice((C - 1) * P, C * P)
        angle = np.arange(P) * cycle_deg / P
        if kind == "cycle":
            mean_rpm = float(self.cycle_mean_omega[-1]) * RPM_PER_RAD_S
            trend = "" if self.kind == "steady" else " (trend removed)"
            title = f"{title}\nlast cycle, its δ{trend} = {float(self.delta):.4g}"
            return plot_speed(angle, rpm[sl], mean_rpm, title, cycle_deg, ax=ax)
        load = np.asarray(self.load_torque)[sl]
        if self.total_torque is None:
            return plot_cycle_torque(angle, np.asarray(self.torque)[sl], load, title, cycle_deg, ax=ax)
        gas = np.asarray(self.torque if self.gas_torque is None else self.gas_torque)[sl]
        total = np.asarray(self.total_torque)[sl]
        return plot_cycle_torque(angle, gas, load, title, cycle_deg, ax=ax, total_Nm=total)


# A result is a pytree, so that a function returning one can be compiled
# (``eqx.filter_jit(lambda rpm: rotor.steady_state(engine, rpm))``) or vmapped: its numbers
# and arrays are leaves, its words and counts the structure. The δ kept with a steady
# state's arrays is dropped (it belongs to those very array objects, which a transformation
# replaces): δ is computed again from ω.
_SPEED_RESULT_META = (
    "method",
    "fidelity",
    "kind",
    "strokes",
    "cycle_rad",
    "points_per_cycle",
    "uniform_cycles",
    "engine_name",
    "solved_for",
    "steps_per_cycle",
    "incomplete",
    "note",
    "first_kept_cycle_index",
)
jax.tree_util.register_dataclass(
    SpeedResult,
    data_fields=[
        f.name for f in dataclasses.fields(SpeedResult) if f.name not in (*_SPEED_RESULT_META, "_known_delta")
    ],
    meta_fields=list(_SPEED_RESULT_META),
    drop_fields=["_known_delta"],
)
