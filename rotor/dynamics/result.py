"""The result of a steady-state or transient run: ω(θ, t), δ, orders, plots, tables.

Arrays are JAX float64 arrays, so ``jax.grad`` flows through ``.delta`` and
``.orders()``; ``.to_pandas()``, ``.summary()`` and ``.plot()`` are for people.
"""

from __future__ import annotations

import dataclasses
import functools

import jax
import jax.numpy as jnp
import numpy as np

__all__ = ["SpeedResult", "Orders"]

RPM_PER_RAD_S = 30.0 / np.pi


@dataclasses.dataclass(frozen=True)
class Orders:
    """Harmonics of speed and engine torque by engine order (cycles per revolution).

    x(θ) = mean + Σ amplitude·cos(order·θ + phase), θ the engine crank angle from the
    start of the analysed cycle [rad]. ``order`` 0.5, 1, 1.5, … for a four-stroke engine.
    """

    order: np.ndarray
    speed_amplitude_rad_s: jnp.ndarray
    speed_phase_rad: jnp.ndarray
    torque_amplitude_Nm: jnp.ndarray
    torque_phase_rad: jnp.ndarray

    def to_list(self) -> list[dict]:
        return [
            {
                "order": float(o),
                "speed_amplitude_rad_s": float(a),
                "speed_phase_rad": float(p),
                "torque_amplitude_Nm": float(ta),
                "torque_phase_rad": float(tp),
            }
            for o, a, p, ta, tp in zip(
                self.order,
                np.asarray(self.speed_amplitude_rad_s),
                np.asarray(self.speed_phase_rad),
                np.asarray(self.torque_amplitude_Nm),
                np.asarray(self.torque_phase_rad),
            )
        ]


def _peak(y0, y1, y2, sign):
    """Extreme value of the parabola through three equally spaced samples (y1 the extreme sample)."""
    curv = y0 - 2 * y1 + y2
    ok = sign * curv < 0
    safe = jnp.where(ok, curv, -sign)
    return jnp.where(ok, y1 - (y0 - y2) ** 2 / (8 * safe), y1)


@functools.partial(jax.jit, static_argnums=1)
def _extremes(x, periodic: bool):
    """(max, min) of each row of x (rows: cycles) with parabolic refinement at the sample."""
    C, P = x.shape
    flat = x.reshape(-1)
    out = []
    for sign, arg in ((1.0, jnp.argmax), (-1.0, jnp.argmin)):
        i = arg(x, axis=1) + jnp.arange(C) * P
        if periodic:
            left = flat[jnp.where(i % P == 0, i + P - 1, i - 1)]
            right = flat[jnp.where(i % P == P - 1, i - P + 1, i + 1)]
            out.append(_peak(left, flat[i], right, sign))
        else:
            interior = (i > 0) & (i < flat.size - 1)
            left = flat[jnp.clip(i - 1, 0, flat.size - 1)]
            right = flat[jnp.clip(i + 1, 0, flat.size - 1)]
            out.append(jnp.where(interior, _peak(left, flat[i], right, sign), flat[i]))
    return out[0], out[1]


@dataclasses.dataclass(frozen=True, eq=False)
class SpeedResult:
    """ω(θ) and friends from :func:`rotor.steady_state` or :func:`rotor.simulate`.

    **Arrays** (one entry per sample): ``t`` [s], ``theta`` [rad], ``omega`` [rad/s],
    ``accel`` (dω/dt) [rad/s²], ``torque`` (engine torque: gas, plus the explicit
    inertia torque at the ``"constant"`` fidelity) [N·m], ``load_torque`` (friction and
    load) [N·m]. ``imep_pa``: each cylinder's IMEP in each cycle (cycles, cylinders) [Pa].

    **Attributes:** ``method``, ``fidelity``, ``kind`` (``"steady"``/``"transient"``),
    ``stalled`` and, if so, ``stall_time_s`` and ``stall_angle_rad``; ``cycle_rad``,
    ``strokes``, ``points_per_cycle`` (samples per cycle of the uniform part);
    ``uniform_cycles``: how many whole cycles are sampled uniformly in θ; ``info``:
    extra figures (load or fuel balance of a steady state, solver statistics).
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
    info: dict = dataclasses.field(default_factory=dict)

    # ------------------------------------------------------------------ cycles
    def _cycle_matrix(self, x):
        n = self.uniform_cycles * self.points_per_cycle
        return x[:n].reshape(self.uniform_cycles, self.points_per_cycle)

    def _need_cycles(self):
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
    def mean_omega(self):
        """Time-mean speed over the whole run, angle travelled / time taken [rad/s]."""
        if self.kind == "steady":
            return self.cycle_rad / self.info["period_s"]
        return (self.theta[-1] - self.theta[0]) / (self.t[-1] - self.t[0])

    @property
    def mean_rpm(self):
        return self.mean_omega * RPM_PER_RAD_S

    @property
    def cycle_mean_omega(self):
        """Time-mean speed of each complete cycle [rad/s], shape (cycles,)."""
        self._need_cycles()
        P = self.points_per_cycle
        if self.kind == "steady":
            return jnp.reshape(self.mean_omega, (1,))
        n = self.uniform_cycles * P
        t_start = self.t[:n:P]
        if self.t.shape[0] > n:  # the sample that ends the last whole cycle
            t_end = jnp.concatenate([t_start[1:], self.t[n : n + 1]])
        else:
            last = self.t[n - 1] + (self.cycle_rad / P) / self.omega[n - 1]
            t_end = jnp.concatenate([t_start[1:], jnp.reshape(last, (1,))])
        return self.cycle_rad / (t_end - t_start)

    @property
    def delta_per_cycle(self):
        """δ of each complete cycle, (ω_max − ω_min)/ω_mean [-], shape (cycles,)."""
        self._need_cycles()
        hi, lo = _extremes(self._cycle_matrix(self.omega), periodic=self.kind == "steady")
        return (hi - lo) / self.cycle_mean_omega

    @property
    def delta(self):
        """δ over the whole run (all complete cycles), (ω_max − ω_min)/ω_mean [-]."""
        self._need_cycles()
        hi, lo = _extremes(self._cycle_matrix(self.omega), periodic=self.kind == "steady")
        mean = self.mean_omega if self.kind == "steady" else jnp.mean(self.cycle_mean_omega)
        return (jnp.max(hi) - jnp.min(lo)) / mean

    @property
    def min_rpm(self):
        return jnp.min(self.omega) * RPM_PER_RAD_S

    @property
    def max_rpm(self):
        return jnp.max(self.omega) * RPM_PER_RAD_S

    def orders(self, cycle=-1, max_order: float = 12.0) -> Orders:
        """Amplitude and phase of the speed and engine-torque harmonics by engine order.

        **Arguments:** ``cycle``: which complete cycle (default the last), or ``"mean"``
        for the average of the complex harmonics over all complete cycles;
        ``max_order``: the highest order returned.
        """
        self._need_cycles()
        P = self.points_per_cycle
        revs = self.strokes / 2  # revolutions per cycle
        w = self._cycle_matrix(self.omega)
        m = self._cycle_matrix(self.torque)
        if cycle == "mean":
            W, M = jnp.mean(jnp.fft.rfft(w, axis=1), axis=0), jnp.mean(jnp.fft.rfft(m, axis=1), axis=0)
        else:
            W, M = jnp.fft.rfft(w[cycle]), jnp.fft.rfft(m[cycle])
        k_max = min(int(np.floor(max_order * revs + 1e-9)), P // 2 - 1)
        k = np.arange(1, k_max + 1)
        W, M = W[1 : k_max + 1] * 2 / P, M[1 : k_max + 1] * 2 / P
        return Orders(k / revs, jnp.abs(W), jnp.angle(W), jnp.abs(M), jnp.angle(M))

    # ------------------------------------------------------------------ people
    def summary(self, max_order: float = 6.0) -> dict:
        """Plain numbers for JSON: mean/min/max rpm, δ, method, fidelity, stall, orders."""
        out = {
            "engine": self.engine_name,
            "kind": self.kind,
            "method": self.method,
            "fidelity": self.fidelity,
            "cycles": int(self.uniform_cycles),
            "mean_rpm": float(self.mean_rpm),
            "min_rpm": float(self.min_rpm),
            "max_rpm": float(self.max_rpm),
            "delta": float(self.delta) if self.uniform_cycles else None,
            "stalled": bool(self.stalled),
            "stall_time_s": None if self.stall_time_s is None else float(self.stall_time_s),
            "stall_angle_deg": None if self.stall_angle_rad is None else float(np.rad2deg(self.stall_angle_rad)),
            "wall_s": float(self.wall_s),
        }
        out.update(
            {
                k: (float(v) if np.ndim(v) == 0 else np.asarray(v).tolist())
                for k, v in self.info.items()
                if k in ("load_torque_Nm", "fuel_scale", "periodicity_error", "excess_work_J", "textbook_delta")
            }
        )
        if self.uniform_cycles:
            o = self.orders(max_order=max_order)
            out["orders"] = [
                {k: d[k] for k in ("order", "speed_amplitude_rad_s", "torque_amplitude_Nm")} for d in o.to_list()
            ]
        else:
            out["orders"] = []
        return out

    def to_pandas(self):
        """The samples as a ``pandas.DataFrame`` (one row per sample, SI units in the names)."""
        import pandas as pd

        cycle = np.floor(np.asarray(self.theta) / self.cycle_rad + 1e-9).astype(int)
        return pd.DataFrame(
            {
                "t_s": np.asarray(self.t),
                "theta_rad": np.asarray(self.theta),
                "angle_deg": np.rad2deg(np.asarray(self.theta)),
                "cycle": cycle,
                "omega_rad_s": np.asarray(self.omega),
                "rpm": np.asarray(self.omega) * RPM_PER_RAD_S,
                "accel_rad_s2": np.asarray(self.accel),
                "torque_Nm": np.asarray(self.torque),
                "load_torque_Nm": np.asarray(self.load_torque),
            }
        )

    def plot(self, ax=None, kind: str = "cycle"):
        """Draw on ``ax`` (a new figure if None) and return it.

        ``kind``: ``"cycle"`` (rpm over the last cycle against crank angle), ``"time"``
        (rpm against time over the run), ``"torque"`` (engine and load torque over the
        last cycle) or ``"orders"`` (speed harmonics by engine order).
        """
        from ..plotting import plot_speed

        return plot_speed(self, ax=ax, kind=kind)
