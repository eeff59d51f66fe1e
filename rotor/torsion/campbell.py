"""The Campbell diagram: natural frequencies against engine speed, with the engine orders.

An engine excites its crankshaft at the orders of its speed: a four-stroke cylinder's
gas and inertia torque repeats every two revolutions, so it has the orders 0.5, 1, 1.5, …
(harmonics per revolution); a two-stroke's 1, 2, 3, …. Order q at speed n [rpm] is the
frequency q·n/60 [Hz]; where it meets a natural frequency f_j the engine runs at a
**critical speed**, n = 60·f_j/q.

How hard order q drives mode j depends on how the cylinders' excitations add up along
the mode: cylinder c fires at the crank angle ψ_c and sits on a throw whose mass swings
with the amplitude φ_j(c), so the work of order q on mode j goes with the **phase sum**
(the "vector sum" of the classic torsional analysis; Ker Wilson, *Practical Solution of
Torsional Vibration Problems*, vol. 2; Nestorides, *A Handbook on Torsional Vibration*,
BICERA 1958)

    |Σ_c φ_j(c)·exp(i·q·ψ_c)|,

reported relative to Σ_c |φ_j(c)| (``relative_amplitudes``: 1 when every cylinder's
excitation adds in phase along the mode). The **major orders** are those at which every
cylinder's excitation has the same phase (q·ψ_c equal modulo 2π: for an evenly firing
four-stroke with z cylinders, the multiples of z/2); they excite the one-node mode of an
inline engine with everything it has. The phase sum is a property of the firing order
and the mode, independent of speed; the harmonic amplitudes of the torque itself (which
grow with load and fall with order) are the forced response's business
(:mod:`rotor.torsion.response`).

The linear chain's natural frequencies do not depend on speed; for an engine, the band
each one sweeps as the mechanisms' inertia varies over a revolution is shaded
(:func:`rotor.torsion.modes.frequency_spread`). Over the speeds the result also gives
the **separation margin** at each speed, min over modes and orders of |q·n/60 − f_j|/f_j,
with the mode and order that set it (a common design rule asks for 10 % or more in the
running range). The whole sweep is one compiled JAX function of the inertias,
stiffnesses, orders, speeds and firing angles (:func:`campbell_arrays`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike

from ..checks import check_size
from ..engine.model import Engine
from ..engine.plausible import PLAUSIBLE, check_speed_rpm, what_it_is
from ..errors import EngineError
from ..results import Result, json_safe
from .model import TorsionalChain, cylinder_masses
from .modes import chain_of, check_mode_size, frequency_spread

__all__ = ["Campbell", "campbell", "campbell_arrays", "engine_orders", "MAX_ORDER", "RANGE_POINTS"]

MAX_ORDER = 12.0
"""The highest engine order drawn by default [-]."""

RANGE_POINTS = 1000
"""Speeds in a sweep given as a range ``(lo, hi)``."""

BYTES_PER_GAP = 3
"""Arrays of (modes × orders × speeds) numbers that a Campbell sweep holds at once (the
gaps to each order's line, their flattened copy, a margin), for its memory check."""

_MAJOR_TOL = 1e-6  # |mean of exp(i·q·ψ)| ≥ 1 − this: every cylinder in phase


def engine_orders(strokes: int, max_order: float = MAX_ORDER) -> np.ndarray:
    """The engine orders up to ``max_order`` [-]: 0.5, 1, 1.5, … for a four-stroke
    (``strokes`` = 4), 1, 2, 3, … for a two-stroke (``strokes`` = 2)."""
    step = 0.5 if strokes == 4 else 1.0
    return np.arange(step, max_order + step / 2, step)


def _arrays(
    inertias: Array, stiffnesses: Array, orders: Array, rpm: Array, phases: Array, cyl_mass: Array
) -> dict[str, Array]:
    n = inertias.shape[0]
    diag = jnp.zeros(n).at[:-1].add(stiffnesses).at[1:].add(stiffnesses)
    K = jnp.diag(diag) - jnp.diag(stiffnesses, 1) - jnp.diag(stiffnesses, -1)
    s = 1.0 / jnp.sqrt(inertias)
    lam, psi = jnp.linalg.eigh(K * s[:, None] * s[None, :])
    f = jnp.sqrt(jnp.clip(lam[1:], 0.0)) / (2 * jnp.pi)
    phi = (psi * s[:, None]).T[1:]  # (modes, n)
    a = phi[:, cyl_mass]  # (modes, cylinders)
    e = jnp.exp(1j * orders[:, None] * phases[None, :])  # (orders, cylinders)
    rel = jnp.abs(a @ e.T) / jnp.sum(jnp.abs(a), axis=1, keepdims=True)  # (modes, orders)
    in_phase = jnp.abs(jnp.mean(e, axis=1))  # (orders,)
    order_f = orders[:, None] * rpm[None, :] / 60.0  # (orders, speeds)
    critical_rpm = 60.0 * f[:, None] / orders[None, :]  # (modes, orders)
    gap = jnp.abs(order_f[None, :, :] - f[:, None, None]) / f[:, None, None]  # (modes, orders, speeds)
    flat = gap.reshape(-1, gap.shape[-1])
    best = jnp.argmin(flat, axis=0)
    return {
        "frequencies_hz": f,
        "relative_amplitudes": rel,
        "in_phase": in_phase,
        "order_frequencies_hz": order_f,
        "critical_rpm": critical_rpm,
        "margin": jnp.min(flat, axis=0),
        "nearest_mode": best // orders.shape[0],
        "nearest_order": best % orders.shape[0],
    }


campbell_arrays = jax.jit(_arrays)
"""``campbell_arrays(inertias_kgm2, stiffnesses_Nm_per_rad, orders, rpm, phases_rad,
cylinder_mass)``: the Campbell sweep as one compiled function: the chain's inertias
[kg·m², (n,)] and stiffnesses [N·m/rad, (n − 1,)], the orders [-, (q,)], the speeds
[rev/min, (s,)], each cylinder's firing angle [rad, (c,)] and the 0-based index of its
mass [(c,) ints]. Returns a dict: ``frequencies_hz`` (modes,), ``relative_amplitudes``
(modes, q), ``in_phase`` (q,) (1 for a major order), ``order_frequencies_hz`` (q, s),
``critical_rpm`` (modes, q), ``margin`` (s,) and the 0-based ``nearest_mode`` and
``nearest_order`` (s,)."""


def shown_critical(amplitude: np.ndarray, most: int) -> np.ndarray:
    """The indices of the critical speeds a summary lists: the ``most`` with the largest
    relative ``amplitude`` (an unknown one, NaN, counted as 1) and every other whose
    amplitude ties with the smallest of those (to 1e-9 of it), so that what is left out is
    smaller than all that is shown."""
    a = np.nan_to_num(np.asarray(amplitude, dtype=np.float64), nan=1.0)
    order = np.argsort(-a, kind="stable")
    if len(order) <= most:
        return order
    floor = a[order[most - 1]]
    return order[a[order] >= floor - 1e-9 * abs(floor)]


@dataclass(frozen=True, eq=False, repr=False)
class Campbell(Result):
    """A Campbell diagram (:func:`rotor.campbell`).

    **Attributes:**

    - ``name``; ``strokes`` (2 or 4).
    - ``rpm`` (s,) [rev/min]: the speeds; ``orders`` (q,) [-].
    - ``natural_frequencies_hz`` (m,) [Hz]: the elastic modes, ascending;
      ``frequency_min_hz``, ``frequency_max_hz`` (m,) [Hz]: their range over the crank
      angle (an engine), or ``None``.
    - ``relative_amplitudes`` (m, q) [-]: the phase sum of each order on each mode, relative
      to all cylinders in phase; ``None`` without firing angles.
    - ``major_orders``: the orders at which all cylinders excite in phase (empty without
      firing angles).
    - ``critical_mode`` (1-based), ``critical_order``, ``critical_rpm`` [rev/min],
      ``critical_frequency_hz`` [Hz], ``critical_relative_amplitude`` [-] (NaN without
      firing angles), ``critical_major`` (bool): the critical speeds inside the speed range,
      sorted by speed.
    - ``separation_margin`` (s,) [-]: at each speed, min over modes and orders of
      |q·n/60 − f|/f; ``nearest_mode`` (1-based) and ``nearest_order`` (s,) that set it.
    """

    name: str
    strokes: int
    rpm: np.ndarray
    orders: np.ndarray
    natural_frequencies_hz: np.ndarray
    frequency_min_hz: np.ndarray | None
    frequency_max_hz: np.ndarray | None
    relative_amplitudes: np.ndarray | None
    major_orders: tuple[float, ...]
    critical_mode: np.ndarray
    critical_order: np.ndarray
    critical_rpm: np.ndarray
    critical_frequency_hz: np.ndarray
    critical_relative_amplitude: np.ndarray
    critical_major: np.ndarray
    separation_margin: np.ndarray
    nearest_mode: np.ndarray
    nearest_order: np.ndarray

    @property
    def critical_speeds(self) -> list[dict[str, Any]]:
        """The critical speeds in the range as a list of dicts (``mode``, ``order``, ``rpm``,
        ``frequency_hz``, ``relative_amplitude``, ``major``), sorted by speed."""
        out = []
        for i in range(len(self.critical_rpm)):
            amp = float(self.critical_relative_amplitude[i])
            out.append(
                {
                    "mode": int(self.critical_mode[i]),
                    "order": float(self.critical_order[i]),
                    "rpm": float(self.critical_rpm[i]),
                    "frequency_hz": float(self.critical_frequency_hz[i]),
                    "relative_amplitude": amp if np.isfinite(amp) else None,
                    "major": bool(self.critical_major[i]),
                }
            )
        return out

    def summary(self) -> str:
        lo, hi = float(self.rpm.min()), float(self.rpm.max())
        f = self.natural_frequencies_hz
        shown_f = ", ".join(f"{x:.1f}" for x in f[:8]) + (" …" if len(f) > 8 else "")
        lines = [
            f"Campbell diagram of {self.name}: {lo:g}…{hi:g} rpm, orders {self.orders[0]:g}…{self.orders[-1]:g}",
            f"  natural frequencies [Hz]: {shown_f}",
        ]
        if self.major_orders:
            lines.append(f"  major orders (all cylinders in phase): {', '.join(f'{q:g}' for q in self.major_orders)}")
        n = len(self.critical_rpm)
        lines.append(f"  {n} critical speed{'s' if n != 1 else ''} in the range" + (":" if n else ""))
        if n:
            lines.append(f"  {'rpm':>9} {'order':>6} {'mode':>5} {'f [Hz]':>9} {'rel. amplitude':>15}")
            order = shown_critical(self.critical_relative_amplitude, 30)
            for i in sorted(order, key=lambda i: self.critical_rpm[i]):
                amp = self.critical_relative_amplitude[i]
                amp_s = f"{amp:.3f}" if np.isfinite(amp) else "-"
                mark = "  major" if self.critical_major[i] else ""
                lines.append(
                    f"  {self.critical_rpm[i]:9.0f} {self.critical_order[i]:6g} {self.critical_mode[i]:5d} "
                    f"{self.critical_frequency_hz[i]:9.1f} {amp_s:>15}{mark}"
                )
            if n > len(order):
                lines.append(f"  … {n - len(order)} more with smaller amplitudes (critical_speeds lists them all)")
        worst = int(np.argmin(self.separation_margin))
        sampled = (
            f"{100 * self.separation_margin[worst]:.2f} % at {self.rpm[worst]:.0f} rpm "
            f"(mode {self.nearest_mode[worst]}, order {self.nearest_order[worst]:g})"
        )
        n_crit = len(self.critical_rpm)
        if n_crit:  # the margin is zero at every critical speed inside the range, wherever the samples fall
            lines.append(
                f"  separation margin: 0 at each of the {n_crit} critical speeds in the range (a margin needs a "
                f"range free of them); the sampled speeds come closest at {sampled}"
            )
        else:
            lines.append(f"  smallest separation margin {sampled}")
        return "\n".join(lines)

    def to_pandas(self) -> Any:
        """One row per mode and order: ``mode``, ``frequency_hz``, ``order``,
        ``critical_rpm`` (60·f/q) [rev/min], ``in_range`` and ``relative_amplitude`` [-]."""
        import pandas as pd

        lo, hi = float(self.rpm.min()), float(self.rpm.max())
        rows = []
        for j, fj in enumerate(self.natural_frequencies_hz):
            for i, q in enumerate(self.orders):
                n = 60.0 * fj / q
                rows.append(
                    {
                        "mode": j + 1,
                        "frequency_hz": float(fj),
                        "order": float(q),
                        "critical_rpm": float(n),
                        "in_range": bool(lo <= n <= hi),
                        "relative_amplitude": None
                        if self.relative_amplitudes is None
                        else float(self.relative_amplitudes[j, i]),
                    }
                )
        return pd.DataFrame(rows)

    def to_json_dict(self) -> dict:
        """The fields as plain JSON; the critical speeds as a list of records."""
        return json_safe(
            {
                "name": self.name,
                "strokes": self.strokes,
                "rpm_range": [float(self.rpm.min()), float(self.rpm.max())],
                "speeds": len(self.rpm),
                "orders": self.orders,
                "natural_frequencies_hz": self.natural_frequencies_hz,
                "frequency_min_hz": self.frequency_min_hz,
                "frequency_max_hz": self.frequency_max_hz,
                "relative_amplitudes": self.relative_amplitudes,
                "major_orders": list(self.major_orders),
                "critical_speeds": self.critical_speeds,
                "smallest_separation_margin": float(np.min(self.separation_margin)),
                "smallest_separation_margin_rpm": float(self.rpm[int(np.argmin(self.separation_margin))]),
            }
        )

    def plot(self, ax: Any = None) -> Any:
        """Draw the diagram: natural frequencies, order rays (major orders bold), critical
        speeds marked, on ``ax`` or a new figure. **Returns:** the Axes."""
        from ..plotting.torsion import plot_campbell

        return plot_campbell(
            self.rpm,
            self.orders,
            self.natural_frequencies_hz,
            f"{self.name}: Campbell diagram",
            self.critical_rpm,
            self.critical_frequency_hz,
            self.critical_major,
            frequency_min_hz=self.frequency_min_hz,
            frequency_max_hz=self.frequency_max_hz,
            major_orders=self.major_orders,
            ax=ax,
        )


def _speeds(rpm: Any, engine: Engine | None) -> np.ndarray:
    if rpm is None:
        if engine is None:
            raise EngineError("campbell(rpm): give the speed range for a bare chain, e.g. rpm=(600, 2400)")
        op = float(engine.operating.rpm)
        rpm = (0.25 * op, 1.25 * op)
    if isinstance(rpm, (str, bytes)) or not isinstance(rpm, Sequence | np.ndarray | jax.Array):
        raise TypeError(f"campbell(rpm): expected (lo, hi) or an array of speeds [rpm], got {what_it_is(rpm)}")
    if isinstance(rpm, Sequence) and len(rpm) == 2:
        lo = check_speed_rpm(rpm[0], "campbell(rpm) lower end")
        hi = check_speed_rpm(rpm[1], "campbell(rpm) upper end")
        if not hi > lo:
            raise EngineError(f"campbell(rpm) = ({lo:g}, {hi:g}): the upper end must be above the lower")
        return np.linspace(lo, hi, RANGE_POINTS)
    a = np.asarray(rpm, dtype=np.float64)
    if a.ndim != 1 or a.size < 2:
        raise EngineError("campbell(rpm): give (lo, hi) or a 1-D array of two or more speeds [rpm]")
    lo_ok, hi_ok = PLAUSIBLE[("operating", "rpm")][:2]
    if not (np.all(np.isfinite(a)) and np.all((a >= lo_ok) & (a <= hi_ok))):
        raise EngineError(f"campbell(rpm): every speed must be finite and within {lo_ok:g}…{hi_ok:g} rpm")
    return a


def campbell(
    engine_or_chain: Engine | TorsionalChain,
    *,
    rpm: tuple[float, float] | ArrayLike | None = None,
    orders: ArrayLike | None = None,
    firing_angles_deg: ArrayLike | None = None,
    strokes: int = 4,
) -> Campbell:
    """The Campbell diagram of an engine's torsional chain (or of a bare chain).

    **Arguments:**

    - ``engine_or_chain``: a :class:`rotor.Engine` with a ``[torsion]`` table, or a
      :class:`rotor.TorsionalChain`.
    - ``rpm``: ``(lo, hi)`` [rev/min] (1000 speeds between) or an array of speeds; default
      for an engine 0.25…1.25 times its ``[operating] rpm``.
    - ``orders``: the engine orders [-]; default 0.5, 1, … 12 (four-stroke) or 1 … 12.
    - ``firing_angles_deg``: a bare chain's firing angles [deg], one per throw mass (in
      ``throw_masses`` order, one cylinder per throw), for the phase sums; an engine's
      come from its layout and firing order.
    - ``strokes``: a bare chain's cycle, 4 or 2 (an engine's own is used).

    **Returns:** a :class:`Campbell`: the natural frequencies, the critical speeds in the
    range with each order's relative amplitude on each mode (the phase sum over the
    cylinders), the major orders and the separation margin over the speeds.
    """
    chain, engine = chain_of(engine_or_chain, "campbell(engine_or_chain)")
    if engine is not None:
        strokes = engine.strokes
    elif strokes not in (2, 4) or isinstance(strokes, bool):
        raise EngineError(f"campbell(strokes = {strokes!r}): 4 (four-stroke) or 2 (two-stroke)")
    n = int(np.size(chain.inertias_kgm2))
    check_mode_size(n, "campbell(engine_or_chain)")
    speeds = _speeds(rpm, engine)
    if orders is None:
        q = engine_orders(strokes)
    else:
        q = np.atleast_1d(np.asarray(orders, dtype=np.float64))
        if q.ndim != 1 or q.size == 0 or not np.all(np.isfinite(q)) or np.any(q <= 0):
            raise EngineError(f"campbell(orders): positive, finite engine orders, e.g. [0.5, 1, 1.5, …], got {q!r:.60}")
        q = np.sort(q)
    if engine is not None:
        phases = np.asarray(engine.firing_angles_rad, dtype=np.float64)
        cyl_mass = np.asarray(cylinder_masses(engine), dtype=np.int32)
    elif firing_angles_deg is not None:
        fa = np.atleast_1d(np.asarray(firing_angles_deg, dtype=np.float64))
        if fa.shape != (len(chain.throw_masses),) or not chain.throw_masses:
            raise EngineError(
                f"campbell(firing_angles_deg): needs one angle per throw mass of the chain "
                f"({len(chain.throw_masses)}: give the chain throw_masses), got {fa.size}"
            )
        if not np.all(np.isfinite(fa)):
            raise EngineError("campbell(firing_angles_deg): must be finite")
        phases = np.deg2rad(fa)
        cyl_mass = np.asarray(chain.throw_masses, dtype=np.int32)
    else:
        phases = np.zeros(1)
        cyl_mass = np.zeros(1, dtype=np.int32)
    known = engine is not None or firing_angles_deg is not None
    check_size(
        8.0 * (n - 1) * q.size * speeds.size * BYTES_PER_GAP + 8.0 * 3 * n * n,
        f"campbell(rpm): {speeds.size} speeds × {q.size} orders × {n - 1} modes",
        "give fewer speeds (rpm=; a range (lo, hi) takes 1000) or fewer orders (orders=)",
    )
    out = {
        key: np.asarray(v)
        for key, v in campbell_arrays(
            chain.inertias_kgm2, chain.stiffnesses_Nm_per_rad, jnp.asarray(q), jnp.asarray(speeds), phases, cyl_mass
        ).items()
    }
    f = out["frequencies_hz"]
    rel = out["relative_amplitudes"] if known else None
    major = tuple(float(x) for x in q[out["in_phase"] >= 1 - _MAJOR_TOL]) if known else ()
    crit = out["critical_rpm"]
    lo, hi = float(speeds.min()), float(speeds.max())
    jj, ii = np.nonzero((crit >= lo) & (crit <= hi))
    by_speed = np.argsort(crit[jj, ii], kind="stable")
    jj, ii = jj[by_speed], ii[by_speed]
    fmin = fmax = None
    if engine is not None:
        fmin, fmax = frequency_spread(engine)
    return Campbell(
        name=engine.name if engine is not None else "chain",
        strokes=int(strokes),
        rpm=speeds,
        orders=q,
        natural_frequencies_hz=f,
        frequency_min_hz=fmin,
        frequency_max_hz=fmax,
        relative_amplitudes=rel,
        major_orders=major,
        critical_mode=(jj + 1).astype(int),
        critical_order=q[ii],
        critical_rpm=crit[jj, ii],
        critical_frequency_hz=f[jj],
        critical_relative_amplitude=rel[jj, ii] if rel is not None else np.full(len(jj), np.nan),
        critical_major=np.isin(q[ii], np.asarray(major)) if major else np.zeros(len(jj), dtype=bool),
        separation_margin=out["margin"],
        nearest_mode=out["nearest_mode"].astype(int) + 1,
        nearest_order=q[out["nearest_order"]],
    )
