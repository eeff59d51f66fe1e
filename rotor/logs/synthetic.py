"""Simulated analog trigger-wheel signals with their truth: what a variable-reluctance (VR)
or Hall pickup in front of a trigger wheel puts out while the crank turns along a given
speed profile, and the true time of every tooth edge that an edge finder should report.

**Speed.** :func:`speed_profile` builds the crank angle φ(t) [rad] of a steady run with a
firing ripple, an ignition cut, a coast-down to near standstill or cranking;
:class:`SpeedProfile` holds it on a uniform time grid (angle and speed at each node, a
cubic Hermite curve between them), evaluates it at any time and inverts it (the time at
which the crank reaches an angle).

**Wheel angle.** The wheel angle θ = φ + ``start_angle_deg`` is 0 at the nominal place
of tooth 0 of the wheel (the first tooth after gap 1, as :class:`rotor.logs.wheel.Wheel`
numbers them); tooth ``j`` sits at ``Wheel.tooth_angles_rad[j]`` plus its error.

**The true edge** of each tooth is at its angle θⱼ (its nominal place, plus the tooth's
error and any early/late or weak distortion of the tooth after a gap):

- ``sensor="vr"``: the pickup's voltage is ∝ dΦ/dt = dΦ/dθ·ω, Φ(θ) a smooth bump of
  flux per tooth centred on θⱼ, (1 − u²)³ for |u| < 1 with u = (θ − θⱼ)/(w·pitch), w the
  ``pulse_width`` (a compactly supported stand-in for a Gaussian, so that a pulse ends
  exactly): each tooth gives a bipolar pulse, positive as the tooth
  approaches and negative as it leaves, with its peak proportional to the speed. The true
  edge is the **falling zero crossing** at the tooth's centre θⱼ (the crossing a VR
  interface chip times after arming on the positive lobe).
- ``sensor="hall"``: a two-level square wave, high while a tooth is in front of the
  sensor (from θⱼ over ``duty`` of a pitch), with a linear ramp of ``rise_time_s`` centred
  on each switching instant. The true edge is the **rising edge** at the tooth's leading
  angle θⱼ: the signal crosses the mid level ``(low_v + high_v)/2`` there.

``inverted=True`` negates the whole signal (noise and offset included): the true edges
are then the rising zero crossings (VR) or the falling edges (Hall), at the same times.
:attr:`SimulatedSignal.edge` names the polarity of the true edges in ``v`` either way.

Only rotor's base layer and :mod:`rotor.logs.wheel` are imported here (no JAX).
"""

from __future__ import annotations

import dataclasses
import math
import os
import re
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from ..checks import check_size
from ..errors import LogError
from ..units import RAD_S_PER_RPM
from .reader import Log
from .wheel import Wheel, parse_wheel

__all__ = [
    "SPEED_KINDS",
    "STANDARD_LAYOUTS",
    "wheel_with_layout",
    "pattern_capture",
    "bench_capture",
    "SpeedProfile",
    "speed_profile",
    "SimulatedSignal",
    "wheel_signal",
    "write_log",
]

TWO_PI = 2.0 * math.pi

SPEED_KINDS = ("steady", "ignition_cut", "coast_down", "crank")
"""The kinds of :func:`speed_profile`."""

STANDARD_LAYOUTS = {
    "36-2-1": (16, 17),  # Mitsubishi 4B11: after the 2-gap 16 teeth, 1 missing, 17 teeth
    "36-2-1-1": (11, 11, 10),  # Mitsubishi 6G75: after the 2-gap 11, 1 missing, 11, 1 missing, 10
    "36-2-2-2": (16, 1, 13),  # Subaru H4: 16 teeth, a gap, a lone tooth, a gap, 13 teeth, a gap
}
"""Teeth that follow each gap (gap 1 first) of the standard multi-gap wheels: the layout
:func:`wheel_signal` gives a wheel spec that names several gaps, unless ``layout`` is given."""

_DEFAULT_RIPPLE = {"steady": 0.03, "ignition_cut": 0.03, "coast_down": 0.01, "crank": 0.8}
_COAST_RIPPLE_CAP = 1.0  # the coast-down's ripple grows as 1/ω̄² up to this δ (a 3:1 speed swing)
_GAUSS2 = (0.5 - 0.5 / math.sqrt(3.0), 0.5 + 0.5 / math.sqrt(3.0))  # 2-point Gauss–Legendre nodes on [0, 1]
_PULSE_PEAK = 0.8**2 / math.sqrt(5.0)  # the peak of u·(1 − u²)², at u = 1/√5
_CHUNK = 1 << 18  # samples computed at a time (keeps the temporaries in cache)
_MAX_PROFILE_NODES = 50_000_000


def _number(
    name: str, value: Any, *, low: float | None = None, high: float | None = None, low_ok=False, high_ok=False
) -> float:
    """``value`` as a finite float above ``low`` and below ``high`` (or equal to them where
    ``low_ok``/``high_ok``), else a :class:`LogError` that names the argument."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise LogError(f"{name}={value!r}: need a number") from None
    if isinstance(value, bool) or not math.isfinite(x):
        raise LogError(f"{name}={value!r}: need a finite number")
    too_low = low is not None and (x < low or (x == low and not low_ok))
    too_high = high is not None and (x > high or (x == high and not high_ok))
    if too_low or too_high:
        parts = []
        if low is not None:
            parts.append(f"{'≥' if low_ok else '>'} {low:g}")
        if high is not None:
            parts.append(f"{'≤' if high_ok else '<'} {high:g}")
        raise LogError(f"{name}={value!r}: need a number {' and '.join(parts)}")
    return x


# ------------------------------------------------------------------------------ the speed


def _hermite(phi: np.ndarray, omega: np.ndarray, h: float) -> tuple[np.ndarray, ...]:
    """Per-interval coefficients (a0, a1, a2, a3) of the cubic Hermite curve through the
    nodes' angles and slopes: φ(s) = a0 + a1·s + a2·s² + a3·s³, s ∈ [0, 1] across a step h."""
    d = np.diff(phi)
    m0 = h * omega[:-1]
    m1 = h * omega[1:]
    return phi[:-1], m0, 3.0 * d - 2.0 * m0 - m1, -2.0 * d + m0 + m1


@dataclasses.dataclass(frozen=True, eq=False)
class SpeedProfile:
    """The crank angle φ(t) [rad] and speed ω(t) = dφ/dt [rad/s] on a uniform time grid.

    **Attributes:** ``t0_s``: time of the first node [s]; ``step_s``: the grid step [s];
    ``phi_rad``: φ at each node [rad], increasing; ``omega_rad_s``: ω at each node
    [rad/s], positive; ``kind``: what built it (a :data:`SPEED_KINDS` name, ``"samples"``
    or ``"function"``); ``description``: in words. Between the nodes φ is the cubic
    Hermite curve through the nodes' angles and speeds (its error is far below a
    microradian on the grids :func:`speed_profile` makes). Calling the profile,
    ``profile(t)``, is :meth:`phi`.
    """

    t0_s: float
    step_s: float
    phi_rad: np.ndarray
    omega_rad_s: np.ndarray
    kind: str = "given"
    description: str = ""

    def __post_init__(self):
        phi = np.ascontiguousarray(self.phi_rad, dtype=np.float64)
        om = np.ascontiguousarray(self.omega_rad_s, dtype=np.float64)
        if phi.ndim != 1 or phi.shape != om.shape or phi.size < 2:
            raise LogError(f"speed profile: {phi.size} angles and {om.size} speeds; need two or more of each, alike")
        if not (np.all(np.isfinite(phi)) and np.all(np.isfinite(om))):
            raise LogError("speed profile: angles and speeds must be finite")
        if not np.all(om > 0) or not np.all(np.diff(phi) > 0):
            raise LogError("speed profile: the crank must turn forwards all through (φ increasing, ω > 0)")
        if not (math.isfinite(self.step_s) and self.step_s > 0 and math.isfinite(self.t0_s)):
            raise LogError(f"speed profile: step {self.step_s!r} s; need a finite step > 0")
        object.__setattr__(self, "phi_rad", phi)
        object.__setattr__(self, "omega_rad_s", om)
        object.__setattr__(self, "t0_s", float(self.t0_s))
        object.__setattr__(self, "step_s", float(self.step_s))

    @property
    def t_s(self) -> np.ndarray:
        """The nodes' times [s]."""
        return self.t0_s + self.step_s * np.arange(self.phi_rad.size)

    @property
    def end_s(self) -> float:
        """Time of the last node [s]."""
        return self.t0_s + self.step_s * (self.phi_rad.size - 1)

    @property
    def duration_s(self) -> float:
        """From the first to the last node [s]."""
        return self.step_s * (self.phi_rad.size - 1)

    @property
    def revolutions(self) -> float:
        """Revolutions turned from the first to the last node [-]."""
        return float(self.phi_rad[-1] - self.phi_rad[0]) / TWO_PI

    def _interval(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        u = (t - self.t0_s) / self.step_s
        if u.size and (np.min(u) < -1e-9 or np.max(u) > self.phi_rad.size - 1 + 1e-9):
            raise LogError(
                f"speed profile: times {np.min(t):.6g} … {np.max(t):.6g} s outside its "
                f"{self.t0_s:.6g} … {self.end_s:.6g} s"
            )
        k = np.clip(np.floor(u), 0, self.phi_rad.size - 2).astype(np.int64)
        return k, u - k

    def phi(self, t: Any) -> np.ndarray:
        """φ [rad] at the times ``t`` [s] (inside the grid)."""
        t = np.asarray(t, dtype=np.float64)
        k, s = self._interval(t.ravel())
        a0, a1, a2, a3 = (c[k] for c in _hermite(self.phi_rad, self.omega_rad_s, self.step_s))
        return (a0 + s * (a1 + s * (a2 + s * a3))).reshape(t.shape)

    def omega(self, t: Any) -> np.ndarray:
        """ω = dφ/dt [rad/s] at the times ``t`` [s] (inside the grid): the slope of the
        curve :meth:`phi` evaluates."""
        t = np.asarray(t, dtype=np.float64)
        k, s = self._interval(t.ravel())
        _, a1, a2, a3 = (c[k] for c in _hermite(self.phi_rad, self.omega_rad_s, self.step_s))
        return ((a1 + s * (2.0 * a2 + s * 3.0 * a3)) / self.step_s).reshape(t.shape)

    def time_of(self, phi: Any) -> np.ndarray:
        """The time [s] at which the crank reaches each angle ``phi`` [rad] (between the
        first and the last node's): the inverse of :meth:`phi`, to rounding."""
        return _invert(self.phi_rad, self.omega_rad_s, self.t0_s, self.step_s, np.asarray(phi, dtype=np.float64))

    def __call__(self, t: Any) -> np.ndarray:
        return self.phi(t)

    @classmethod
    def from_samples(cls, t_s: Any, phi_rad: Any, *, kind: str = "samples") -> SpeedProfile:
        """A profile through the angles ``phi_rad`` [rad] at the times ``t_s`` [s]
        (increasing; a cubic spline through them, resampled on a uniform grid of their
        median step)."""
        from scipy.interpolate import CubicSpline

        t = np.asarray(t_s, dtype=np.float64)
        p = np.asarray(phi_rad, dtype=np.float64)
        if t.ndim != 1 or t.shape != p.shape or t.size < 4:
            raise LogError(f"profile: {t.size} times and {p.size} angles; need 4 or more of each, alike")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(p))):
            raise LogError("profile: times and angles must be finite")
        dt = np.diff(t)
        if not np.all(dt > 0):
            raise LogError("profile: the times must increase")
        if not np.all(np.diff(p) > 0):
            raise LogError("profile: the crank angle must increase with time (φ [rad] of an engine turning forwards)")
        h = float(np.median(dt))
        n = int(math.floor((t[-1] - t[0]) / h + 1e-9)) + 1
        cs = CubicSpline(t, p)
        tt = t[0] + h * np.arange(n)
        return cls(float(t[0]), h, cs(tt), cs(tt, 1), kind, f"given as {t.size} samples")

    @classmethod
    def from_function(cls, phi_of_t: Callable, duration_s: float, step_s: float) -> SpeedProfile:
        """A profile of a vectorised function φ(t) [rad] of time [s], sampled every
        ``step_s`` [s] from 0 to ``duration_s`` [s]; the speed by central differences."""
        duration = _number("duration_s", duration_s, low=0.0)
        n = int(math.floor(duration / step_s + 1e-9)) + 1
        if n < 4:
            raise LogError(f"duration_s={duration_s!r}: shorter than a few steps of {step_s:g} s")
        check_size(24.0 * n, f"a profile of {n} nodes", "give a shorter duration_s", error=LogError)
        tt = step_s * np.arange(n)
        p = np.asarray(phi_of_t(tt), dtype=np.float64)
        if p.shape != tt.shape:
            raise LogError(f"phi_of_t: returned shape {p.shape} for {tt.size} times; need one angle [rad] per time")
        om = np.gradient(p, step_s, edge_order=2)
        return cls(0.0, float(step_s), p, om, "function", "given as a function of time")


def _invert(phi: np.ndarray, omega: np.ndarray, t0: float, h: float, target: np.ndarray) -> np.ndarray:
    """Times at which the Hermite curve through (phi, omega) on the grid t0 + k·h reaches ``target``."""
    flat = target.ravel()
    if flat.size and (flat.min() < phi[0] - 1e-9 or flat.max() > phi[-1] + 1e-9):
        raise LogError(
            f"speed profile: angles {flat.min():.6g} … {flat.max():.6g} rad outside {phi[0]:.6g} … {phi[-1]:.6g}"
        )
    k = np.clip(np.searchsorted(phi, flat, side="right") - 1, 0, phi.size - 2)
    a0, a1, a2, a3 = (c[k] for c in _hermite(phi, omega, h))
    s = np.clip((flat - a0) / (phi[k + 1] - a0), 0.0, 1.0)
    for _ in range(6):  # Newton from the secant's guess; the curve is monotonic on a fine grid
        g = a0 + s * (a1 + s * (a2 + s * a3)) - flat
        dg = a1 + s * (2.0 * a2 + s * 3.0 * a3)
        s = np.clip(s - g / np.maximum(dg, 1e-300), 0.0, 1.0)
    return (t0 + h * (k + s)).reshape(target.shape)


def _ramp01(z: np.ndarray) -> np.ndarray:
    """A smooth step from 0 (z ≤ 0) to 1 (z ≥ 1): (1 − cos πz)/2."""
    zc = np.clip(z, 0.0, 1.0)
    return 0.5 - 0.5 * np.cos(np.pi * zc)


def speed_profile(
    kind: str,
    *,
    rpm: float,
    duration_s: float | None = None,
    revolutions: float | None = None,
    ripple: float | None = None,
    order: float = 2.0,
    ripple_phase_deg: float = 0.0,
    drop: float = 0.3,
    cut_revolution: float | None = None,
    drop_revolutions: float = 3.0,
    end_rpm: float | None = None,
    nodes_per_rev: int = 64,
) -> SpeedProfile:
    """The crank angle φ(t) [rad] of a simulated run, φ(0) = 0, as a :class:`SpeedProfile`.

    The speed is given as a function of the crank angle, ω(φ) = ω̄(φ)·(1 + δ/2·sin(k·φ + ψ)),
    so the ripple is locked to the crank as an engine's is; the time follows as
    t(φ) = ∫dφ/ω (Gauss–Legendre quadrature), inverted onto a uniform time grid.

    **Arguments:**
    - ``kind``: ``"steady"`` (a constant mean speed with the ripple); ``"ignition_cut"``
      (steady, then at ``cut_revolution`` the mean speed falls by ``drop`` over
      ``drop_revolutions`` along a smooth half-cosine, then stays there); ``"coast_down"``
      (a constant deceleration in time, ω̄² falling linearly with the angle as under a
      constant drag torque, from ``rpm`` down to ``end_rpm``, where it ends: near
      standstill; the ripple is a constant torque's, so δ grows as 1/ω̄² up to 1.0);
      ``"crank"`` (cranking: a low constant mean speed with a strong compression ripple).
    - ``rpm``: the mean speed at the start [rev/min].
    - ``duration_s`` [s] or ``revolutions`` [-]: how long; exactly one of them. A coast-down
      given a duration lasts about that (its ripple changes the time a little).
    - ``ripple``: δ = (ω_max − ω_min)/ω̄ of the ripple [-], 0 ≤ δ < 2; default 0.03
      (steady, ignition cut), 0.01 at the start of a coast-down, 0.8 cranking (a 2.3:1 swing).
    - ``order``: the ripple's order k, per revolution [-] (2: a four-cylinder
      four-stroke's firing); ``ripple_phase_deg``: its phase ψ [deg].
    - ``drop``: the ignition cut's fall of the mean speed, a fraction [-] (0.3: 30 %);
      ``cut_revolution``: where it starts [revolutions from φ = 0], default 40 % of the
      run; ``drop_revolutions``: how many revolutions the fall takes [-].
    - ``end_rpm``: the coast-down's last mean speed [rev/min], default ``rpm``/20.
    - ``nodes_per_rev``: grid nodes per revolution at the highest speed [-].

    **Returns:** :class:`SpeedProfile`. Bad arguments raise :class:`rotor.LogError` naming
    the argument (``kind=``, ``rpm=``, …).
    """
    if kind not in SPEED_KINDS:
        raise LogError(f"kind={kind!r}: one of {', '.join(map(repr, SPEED_KINDS))}")
    rpm_ = _number("rpm", rpm, low=0.0)
    w0 = rpm_ * RAD_S_PER_RPM
    if (duration_s is None) == (revolutions is None):
        raise LogError(
            f"duration_s={duration_s!r}, revolutions={revolutions!r}: give exactly one of them (how long the run lasts)"
        )
    dur = None if duration_s is None else _number("duration_s", duration_s, low=0.0)
    revs = None if revolutions is None else _number("revolutions", revolutions, low=0.0)
    delta0 = _DEFAULT_RIPPLE[kind] if ripple is None else _number("ripple", ripple, low=0.0, high=2.0, low_ok=True)
    k_ord = _number("order", order, low=0.0)
    psi = math.radians(_number("ripple_phase_deg", ripple_phase_deg))
    if not (
        isinstance(nodes_per_rev, (int, np.integer)) and not isinstance(nodes_per_rev, bool) and nodes_per_rev >= 16
    ):
        raise LogError(f"nodes_per_rev={nodes_per_rev!r}: need a whole number, 16 or more")
    w_end = 0.0
    alpha = 0.0
    phi_cut = phi_drop = 0.0
    drop_ = 0.0
    if kind == "ignition_cut":
        drop_ = _number("drop", drop, low=0.0, high=1.0)
        n_drop = _number("drop_revolutions", drop_revolutions, low=0.0)
        if cut_revolution is None:
            cut = 0.4 * (revs if revs is not None else dur * rpm_ / 60.0)  # type: ignore[operator]
        else:
            cut = _number("cut_revolution", cut_revolution, low=0.0, low_ok=True)
        phi_cut, phi_drop = TWO_PI * cut, TWO_PI * n_drop
    if kind == "coast_down":
        end = rpm_ / 20.0 if end_rpm is None else _number("end_rpm", end_rpm, low=0.0, high=rpm_)
        w_end = end * RAD_S_PER_RPM
        if dur is not None:
            alpha = (w0 - w_end) / dur
            phi_end = (w0**2 - w_end**2) / (2.0 * alpha)
        else:
            phi_end = TWO_PI * revs  # type: ignore[operator]
            alpha = (w0**2 - w_end**2) / (2.0 * phi_end)
    elif revs is not None:
        phi_end = TWO_PI * revs
    else:
        phi_end = (dur * w0 * (1.0 + delta0 / 2.0)) * 1.02 + TWO_PI  # type: ignore[operator]
        if kind == "ignition_cut":
            phi_end = max(phi_end, phi_cut + phi_drop + dur * w0) + TWO_PI  # type: ignore[operator]

    def mean_speed(p: np.ndarray) -> np.ndarray:
        if kind == "coast_down":
            return np.sqrt(np.maximum(w0**2 - 2.0 * alpha * p, w_end**2))
        if kind == "ignition_cut":
            return w0 * (1.0 - drop_ * _ramp01((p - phi_cut) / phi_drop))
        return np.full_like(p, w0)

    def speed(p: np.ndarray) -> np.ndarray:
        wm = mean_speed(p)
        d = np.minimum(delta0 * (w0 / wm) ** 2, max(delta0, _COAST_RIPPLE_CAP)) if kind == "coast_down" else delta0
        return wm * (1.0 + 0.5 * d * np.sin(k_ord * p + psi))

    # t(φ) on a fine angle grid: 256 nodes per revolution, 8 per ripple period at least
    per_rev = max(256, int(math.ceil(8 * k_ord)))
    n_ang = int(math.ceil(phi_end / TWO_PI * per_rev)) + 1
    if n_ang > _MAX_PROFILE_NODES:
        raise LogError(f"a run of {phi_end / TWO_PI:.4g} revolutions is too long to simulate; give a shorter one")
    check_size(
        80.0 * n_ang, f"a speed profile of {phi_end / TWO_PI:.4g} revolutions", "give a shorter run", error=LogError
    )
    pa = np.linspace(0.0, phi_end, n_ang)
    hp = pa[1] - pa[0]
    inv = sum(0.5 / speed(pa[:-1] + g * hp) for g in _GAUSS2)
    ta = np.concatenate([[0.0], np.cumsum(inv * hp)])
    wa = speed(pa)
    t_end = float(ta[-1]) if (dur is None or kind == "coast_down") else dur
    if t_end > ta[-1] * (1 + 1e-12):
        raise LogError(f"duration_s={duration_s!r}: the profile fell short; give revolutions instead")  # not reached
    # onto a uniform time grid: nodes_per_rev nodes per revolution at the top speed, 16 per ripple period at least
    w_max = float(np.max(wa))
    n_t = int(math.ceil(t_end * w_max / TWO_PI * max(nodes_per_rev, 16 * k_ord))) + 1
    if n_t > _MAX_PROFILE_NODES:
        raise LogError(f"a run of {t_end:.4g} s is too long to simulate; give a shorter one")
    h = t_end / (n_t - 1)
    tt = h * np.arange(n_t)
    tt[-1] = min(tt[-1], ta[-1])
    # φ(t): the inverse of the Hermite curve of t(φ) (slopes 1/ω at the angle nodes)
    phi_t = _invert(ta, 1.0 / wa, 0.0, hp, tt)  # the curve t(φ), slopes 1/ω, on the angle grid, inverted
    om_t = speed(phi_t)
    desc = {
        "steady": f"steady {rpm_:g} rpm",
        "ignition_cut": (
            f"{rpm_:g} rpm, cut at revolution {phi_cut / TWO_PI:g}: −{100 * drop_:g} % in "
            f"{phi_drop / TWO_PI:g} revolutions"
        ),
        "coast_down": f"coast-down {rpm_:g} → {w_end / RAD_S_PER_RPM:g} rpm",
        "crank": f"cranking at {rpm_:g} rpm",
    }[kind]
    desc += f", ripple δ {delta0:g} at order {k_ord:g}, {t_end:.4g} s"
    return SpeedProfile(0.0, h, phi_t, om_t, kind, desc)


# ------------------------------------------------------------------------------ the wheel


def wheel_with_layout(wheel: Any, layout: Sequence[int] | None) -> Wheel:
    """The :class:`Wheel` of ``wheel`` with where its gaps lie (``layout``, the standard
    one, or the teeth spread as evenly as can be), gap 1 as :class:`Wheel` defines it."""
    try:
        w = parse_wheel(wheel)
    except LogError as e:
        raise LogError(f"wheel={wheel!r}: {e}") from None
    except TypeError:
        raise LogError(f"wheel={wheel!r}: a spec such as '60-2' or '36-2-1', or a Wheel") from None
    if w.missing == 0:
        raise LogError(
            f"wheel={wheel!r}: a wheel without a gap needs an index signal, which is not simulated; "
            "give one with missing teeth (60-2, 36-1, 36-2-1, …)"
        )
    if layout is not None:
        lay = tuple(int(x) for x in layout)
        if len(lay) != len(w.gaps) or any(x < 1 for x in lay) or sum(lay) != w.edges_per_rev:
            raise LogError(
                f"layout={layout!r}: the teeth after each of the {len(w.gaps)} gaps of {w.spec}, "
                f"{w.edges_per_rev} in all, each 1 or more"
            )
    elif w.layout is not None:
        lay = w.layout
    elif w.spec in STANDARD_LAYOUTS:
        lay = STANDARD_LAYOUTS[w.spec]
    else:
        q, r = divmod(w.edges_per_rev, len(w.gaps))
        lay = tuple(q + (1 if i < r else 0) for i in range(len(w.gaps)))
    # gap 1 is the gap named first; of equal rotations of the gaps, the one followed by the largest layout
    g = w.gaps
    rots = [i for i in range(len(g)) if g[i:] + g[:i] == g]
    best = max(rots, key=lambda i: lay[i:] + lay[:i])
    lay = lay[best:] + lay[:best]
    try:
        return Wheel(w.teeth, w.missing, w.gaps, lay, w.angles_deg)
    except LogError as e:
        raise LogError(f"wheel={wheel!r}: {e}") from None


GAP_TOOTH_KINDS = ("weak", "early", "late")


@dataclasses.dataclass(frozen=True, eq=False)
class SimulatedSignal:
    """A simulated trigger-wheel signal and its truth (:func:`wheel_signal`).

    **Attributes:**
    - ``t_s``: sample times [s], uniform; ``v``: the sampled voltage [V].
    - ``edge_times_s``: the true time of each tooth edge that lies at least half a pitch
      inside the record [s]: the falling zero crossing at the tooth's centre (VR) or the
      rising edge at its leading angle (Hall), the other polarity when inverted (see
      ``edge``).
    - ``tooth_index``: the tooth of each edge (0 … teeth−missing−1, 0 = the first after
      gap 1, as :class:`rotor.logs.wheel.ToothTrack` numbers them); ``revolution``: its
      revolution (0 = the revolution of the first tooth 0 in ``edge_times_s``, −1 before);
      ``edge_angles_rad``: its true wheel angle, 2π·revolution + the tooth's angle with
      its error and distortion [rad]; ``after_gap``: whether the tooth follows a gap.
    - ``wheel``: the :class:`rotor.logs.wheel.Wheel` (with where its gaps lie).
    - ``sensor``: ``"vr"`` or ``"hall"``; ``edge``: ``"falling"`` or ``"rising"``, the
      polarity of the true edges in ``v``; ``level_v``: the level they cross at the true
      time [V] (VR: its offset; Hall: the mid level; negated when inverted).
    - ``sample_rate_hz`` [Hz]; ``profile``: the :class:`SpeedProfile`; ``description``:
      what was simulated, in words.
    """

    t_s: np.ndarray
    v: np.ndarray
    edge_times_s: np.ndarray
    tooth_index: np.ndarray
    revolution: np.ndarray
    edge_angles_rad: np.ndarray
    after_gap: np.ndarray
    wheel: Wheel
    sensor: str
    edge: str
    level_v: float
    sample_rate_hz: float
    profile: SpeedProfile
    description: str = ""

    @property
    def gap_edge_times_s(self) -> np.ndarray:
        """The true times [s] of the edges of the teeth that follow a gap (tooth 0 after
        gap 1, and the first tooth after every other gap of a multi-gap wheel)."""
        return self.edge_times_s[self.after_gap]

    @property
    def reference_times_s(self) -> np.ndarray:
        """The true times [s] of tooth 0's edges, one per revolution."""
        return self.edge_times_s[self.tooth_index == 0]

    @property
    def omega_at_edges_rad_s(self) -> np.ndarray:
        """The true crank speed at each edge [rad/s]."""
        return self.profile.omega(self.edge_times_s)

    @property
    def columns(self) -> str:
        """The column spec of :func:`write_log`'s file: ``"time,encoder_v"``."""
        return "time,encoder_v"


def _tooth_tables(w: Wheel, sensor: str, gap_kinds: set, amp_gap: float, shift: float, duty: float, err: np.ndarray):
    """Per position of the wheel (0 … teeth−1): whether it holds a tooth, the tooth's
    amplitude (0: none), the offset of its true edge from the position and (Hall) its high
    width, in pitches, and whether it follows a gap."""
    n = w.teeth
    pos = w.positions
    present = np.zeros(n, bool)
    present[pos] = True
    after = present & ~np.roll(present, 1)
    amp = present.astype(np.float64)
    on = np.zeros(n)
    width = np.where(present, duty, 0.0)
    on[pos] += err
    if w.angles_deg is not None:
        pitch_deg = 360.0 / n
        on[pos] += (np.asarray(w.angles_deg) - pos * pitch_deg) / pitch_deg
    if "early" in gap_kinds:
        on[after] -= shift
    if "late" in gap_kinds:
        on[after] += shift
    if "weak" in gap_kinds:
        if sensor == "vr":
            amp[after] *= amp_gap
        else:  # a Hall tooth the sensor barely sees switches late and drops early: a narrower pulse
            on[after] += 0.5 * (1.0 - amp_gap) * duty
            width[after] *= amp_gap
    return present, amp, on, width, after


def _check_tables(present, on, width, sensor, pulse_width) -> None:
    """The distorted teeth must stay in order and apart: a tooth within its pitch, a Hall
    tooth's high ending before the next one starts, no VR pulse reaching its neighbour's
    centre (which would move the neighbour's zero crossing off its true time)."""
    p = np.flatnonzero(present)
    start = p + on[p]
    if np.any(np.abs(on[p]) > 0.45):
        raise LogError(
            "gap_tooth_shift/tooth_error_deg: a tooth moved by more than 0.45 of a pitch; give smaller distortions"
        )
    nxt = np.concatenate([start[1:], [start[0] + present.size]])
    end = start + (width[p] if sensor == "hall" else 0.0)
    if np.any(end >= nxt - 0.05):
        raise LogError(
            "gap_tooth_shift/tooth_error_deg/duty: neighbouring teeth would touch; give smaller distortions or duty"
        )
    if sensor == "vr" and np.any(nxt - start <= pulse_width):
        raise LogError(
            "gap_tooth_shift/tooth_error_deg/pulse_width: a tooth's pulse would reach its neighbour's centre; "
            "give smaller distortions or a narrower pulse_width"
        )


def wheel_signal(
    profile: SpeedProfile | tuple | Callable,
    wheel: str | Wheel,
    *,
    sensor: str = "vr",
    sample_rate_hz: float = 100e3,
    inverted: bool = False,
    noise_v: float = 0.01,
    gap_tooth: str | Sequence[str] | None = None,
    tooth_error_deg: float | Sequence[float] = 0.0,
    seed: int = 0,
    start_angle_deg: float = 100.0,
    layout: Sequence[int] | None = None,
    sensitivity_v_per_rad_s: float = 0.02,
    pulse_width: float = 0.45,
    offset_v: float = 0.0,
    duty: float = 0.5,
    low_v: float = 0.0,
    high_v: float = 5.0,
    rise_time_s: float = 2e-6,
    gap_tooth_amplitude: float = 0.3,
    gap_tooth_shift: float = 0.15,
    duration_s: float | None = None,
) -> SimulatedSignal:
    """A sampled analog trigger-wheel signal of a crank turning as ``profile`` says, with
    the true time of every tooth edge (see the module notes for the physics and which
    edge is the true one).

    **Arguments:**
    - ``profile``: the crank angle φ(t) [rad] of time [s]: a :class:`SpeedProfile`
      (:func:`speed_profile`), a pair of arrays ``(t_s, phi_rad)``, or a vectorised
      function of time (then ``duration_s`` [s] says how long, from t = 0).
    - ``wheel``: a spec (``"60-2"``, ``"36-1"``, ``"36-2-1"``, ``"36-2-1-1"``,
      ``"36-2-2-2"``, …; :func:`rotor.logs.wheel.parse_wheel`), a wheel file or a
      :class:`rotor.logs.wheel.Wheel`. Where the gaps lie: ``layout`` (the teeth after
      each gap, gap 1 first), else the wheel's own, else :data:`STANDARD_LAYOUTS`, else
      the teeth spread evenly between the gaps. A wheel file's measured tooth angles are
      used as the teeth's true places.
    - ``sensor``: ``"vr"`` (variable reluctance: a bipolar pulse per tooth, amplitude ∝
      speed) or ``"hall"`` (a two-level square wave).
    - ``sample_rate_hz``: the sampling rate [Hz]; ``noise_v``: the standard deviation of
      white Gaussian noise added [V]; ``seed``: the seed of the noise and of the drawn
      tooth errors (the same seed gives the same signal).
    - ``inverted``: negate the signal (a pickup wired the other way round).
    - ``gap_tooth``: how the tooth after each gap is distorted, one of, or a list of:
      ``"weak"`` (VR: its pulse ``gap_tooth_amplitude`` [-] of the others'; Hall: its high
      lasts that fraction of the others', centred on the tooth, so it rises late),
      ``"early"`` or ``"late"`` (its edge ``gap_tooth_shift`` [pitches] before or after its
      place); ``None``: none.
    - ``tooth_error_deg``: each tooth's angle error [deg]: a standard deviation (the errors
      drawn once per tooth from ``seed``, the same in every revolution) or one error per
      tooth, tooth 0 first.
    - ``start_angle_deg``: the wheel angle at φ = 0 [deg] (0: tooth 0's place), so the
      record starts part-way round the wheel.
    - VR: ``sensitivity_v_per_rad_s``: a tooth's peak voltage per unit crank speed
      [V/(rad/s)] (0.02: 2.1 V at 1000 rpm); ``pulse_width``: the half-width w of a tooth's
      flux bump [pitches], 0 < w ≤ 0.5 (its pulse is 0 beyond ±w, its peaks at ±w/√5); ``offset_v``: a constant added [V].
    - Hall: ``low_v``, ``high_v``: the two levels [V]; ``duty``: the high fraction of a
      tooth pitch [-]; ``rise_time_s``: the time of each switching ramp [s].

    **Returns:** :class:`SimulatedSignal`. Bad arguments raise :class:`rotor.LogError` (a
    ``ValueError``) naming the argument (``wheel=``, ``sensor=``, …). Cost: about 40
    floating-point operations per sample (no Python loop over samples or teeth).
    """
    if sensor not in ("vr", "hall"):
        raise LogError(f"sensor={sensor!r}: 'vr' (variable reluctance) or 'hall'")
    fs = _number("sample_rate_hz", sample_rate_hz, low=0.0)
    noise = _number("noise_v", noise_v, low=0.0, low_ok=True)
    if not isinstance(inverted, (bool, np.bool_)):
        raise LogError(f"inverted={inverted!r}: True or False")
    if not isinstance(seed, (int, np.integer)) or isinstance(seed, bool) or seed < 0:
        raise LogError(f"seed={seed!r}: a whole number, 0 or more")
    theta0 = math.radians(_number("start_angle_deg", start_angle_deg))
    amp_gap = _number("gap_tooth_amplitude", gap_tooth_amplitude, low=0.0, high=1.0, high_ok=True)
    shift = _number("gap_tooth_shift", gap_tooth_shift, low=0.0, high=0.45, low_ok=True, high_ok=True)
    kinds = _gap_kinds(gap_tooth)
    sen = _sensor(sensor, sensitivity_v_per_rad_s, pulse_width, offset_v, low_v, high_v, duty, rise_time_s)
    w = wheel_with_layout(wheel, layout)
    err_deg = _tooth_errors_deg(w, tooth_error_deg, seed)
    N, pitch = w.teeth, w.pitch_rad
    present, amp, on, width, after = _tooth_tables(w, sensor, kinds, amp_gap, shift, sen.duty, err_deg / (360.0 / N))
    _check_tables(present, on, width, sensor, sen.sigma)
    prof = _as_profile(profile, duration_s, fs)
    grid = _sample_grid(prof, fs, sample_rate_hz)
    if sensor == "hall" and float(np.max(grid.wn)) * sen.tau / pitch > 0.25 * sen.duty * min(
        1.0, amp_gap if "weak" in kinds else 1.0
    ):
        raise LogError(
            f"rise_time_s={rise_time_s!r}: at the top speed the ramp takes over a quarter of a tooth's high time; "
            "give a shorter one"
        )
    coeffs = _hermite(grid.pn, grid.wn, grid.h)
    tables = (present, amp, on, width)
    v = _sampled(sen, grid, coeffs, w, tables, theta0, inverted, noise, seed)
    edge_t, tooth, rev, ang, rev_abs, pos = _true_edges(w, on, grid, coeffs, theta0)
    n, lo, hi, sens, offset = grid.n, sen.lo, sen.hi, sen.sens, sen.offset
    sign = -1.0 if inverted else 1.0
    t_s = prof.t0_s + np.arange(n) / fs
    if sensor == "vr":
        edge, level = ("rising" if inverted else "falling"), sign * offset
        sensor_desc = f"VR {sens:g} V/(rad/s)"
    else:
        edge, level = ("falling" if inverted else "rising"), sign * 0.5 * (lo + hi)
        sensor_desc = f"Hall {lo:g}/{hi:g} V"
    desc = (
        f"{w.spec} wheel, {sensor_desc}, {prof.description}; "
        + (f"tooth after the gap {'+'.join(sorted(kinds))}, " if kinds else "")
        + ("inverted, " if inverted else "")
        + f"noise {noise:g} V, {fs:g} Hz, seed {seed}"
    )
    return SimulatedSignal(
        t_s=t_s,
        v=v,
        edge_times_s=edge_t,
        tooth_index=tooth.astype(np.int64),
        revolution=rev.astype(np.int64),
        edge_angles_rad=TWO_PI * rev + (ang - TWO_PI * rev_abs),
        after_gap=after[pos][tooth],
        wheel=w,
        sensor=sensor,
        edge=edge,
        level_v=float(level),
        sample_rate_hz=fs,
        profile=prof,
        description=desc,
    )


def _gap_kinds(gap_tooth) -> set:
    """The distortions of the tooth after each gap asked for (``gap_tooth``), checked."""
    if gap_tooth is None:
        kinds: set = set()
    elif isinstance(gap_tooth, str):
        kinds = {gap_tooth}
    elif isinstance(gap_tooth, Sequence):
        kinds = set(gap_tooth)
    else:
        kinds = {gap_tooth}
    if not kinds <= set(GAP_TOOTH_KINDS) or {"early", "late"} <= kinds:
        raise LogError(
            f"gap_tooth={gap_tooth!r}: None, 'weak', 'early' or 'late' (or a list of them; not early and late both)"
        )
    return kinds


@dataclasses.dataclass(frozen=True)
class _Sensor:
    """The sensor's settings, checked: ``kind`` (``"vr"`` or ``"hall"``); VR: ``sens``
    [V/(rad/s)], ``sigma`` (the pulse's half-width [pitches]), ``offset`` [V]; Hall: ``lo``,
    ``hi`` [V], ``tau`` (the ramp [s]); ``duty`` (0.5 for VR)."""

    kind: str
    duty: float
    sens: float = 0.0
    sigma: float = 0.0
    offset: float = 0.0
    lo: float = 0.0
    hi: float = 0.0
    tau: float = 0.0


def _sensor(sensor, sensitivity_v_per_rad_s, pulse_width, offset_v, low_v, high_v, duty, rise_time_s) -> _Sensor:
    """The settings of ``sensor``, each checked (:class:`rotor.LogError` naming the argument)."""
    if sensor == "vr":
        sens = _number("sensitivity_v_per_rad_s", sensitivity_v_per_rad_s, low=0.0)
        sigma = _number("pulse_width", pulse_width, low=0.0, high=0.5, high_ok=True)
        offset = _number("offset_v", offset_v)
        return _Sensor("vr", 0.5, sens=sens, sigma=sigma, offset=offset)
    lo = _number("low_v", low_v)
    hi = _number("high_v", high_v)
    if not hi > lo:
        raise LogError(f"high_v={high_v!r}, low_v={low_v!r}: high_v must be above low_v")
    duty_ = _number("duty", duty, low=0.0, high=1.0)
    tau = _number("rise_time_s", rise_time_s, low=0.0)
    return _Sensor("hall", duty_, lo=lo, hi=hi, tau=tau)


def _tooth_errors_deg(w: Wheel, tooth_error_deg, seed: int) -> np.ndarray:
    """Each tooth's angle error [deg]: drawn once per tooth from ``seed`` with the standard
    deviation ``tooth_error_deg``, or given one per tooth."""
    E, N = w.edges_per_rev, w.teeth
    rng_teeth = np.random.default_rng([int(seed), 1])
    if np.ndim(tooth_error_deg) == 0:
        sd = _number("tooth_error_deg", tooth_error_deg, low=0.0, low_ok=True)
        if sd > 0.08 * 360.0 / N:
            raise LogError(
                f"tooth_error_deg={tooth_error_deg!r}: over 8 % of the {360.0 / N:g}° pitch; give a smaller spread"
            )
        err_deg = np.clip(rng_teeth.standard_normal(E), -2.5, 2.5) * sd
    else:
        err_deg = np.asarray(tooth_error_deg, dtype=np.float64)
        if err_deg.shape != (E,) or not np.all(np.isfinite(err_deg)):
            raise LogError(
                f"tooth_error_deg: {err_deg.size} values; need one finite error [deg] per tooth, {E} for {w.spec}"
            )
    return err_deg


def _as_profile(profile, duration_s, fs: float) -> SpeedProfile:
    """``profile`` as a :class:`SpeedProfile` (a pair of arrays, or a function of time over ``duration_s``)."""
    if isinstance(profile, SpeedProfile):
        return profile
    if isinstance(profile, tuple) and len(profile) == 2:
        return SpeedProfile.from_samples(profile[0], profile[1])
    if callable(profile):
        if duration_s is None:
            raise LogError("duration_s=None: give how long [s] to sample a profile given as a function of time")
        return SpeedProfile.from_function(profile, duration_s, 4.0 / fs)
    raise LogError(
        f"profile={type(profile).__name__}: a SpeedProfile, a pair (t_s, phi_rad) of arrays or a function φ(t)"
    )


@dataclasses.dataclass(frozen=True)
class _Grid:
    """The profile on a grid aligned with the samples: ``m`` samples per step of ``h`` [s],
    ``K`` steps, ``n`` samples; the grid's times ``tn`` [s], angles ``pn`` [rad] and speeds
    ``wn`` [rad/s]."""

    m: int
    h: float
    K: int
    n: int
    tn: np.ndarray
    pn: np.ndarray
    wn: np.ndarray


def _sample_grid(prof: SpeedProfile, fs: float, sample_rate_hz) -> _Grid:
    """The profile on a grid of whole sample steps, checked against the memory budget."""
    m = max(1, int(math.floor(prof.step_s * fs)))
    h = m / fs
    K = int(math.floor(prof.duration_s / h + 1e-9))
    if K < 1:
        raise LogError(
            f"sample_rate_hz={sample_rate_hz!r}: the run of {prof.duration_s:.3g} s holds less than one sample step"
        )
    n = K * m
    check_size(
        8.0 * 2 * n + 64.0 * _CHUNK,
        f"{n} samples ({prof.duration_s:.4g} s at {fs:g} Hz)",
        "give a shorter run or a lower sample_rate_hz",
        error=LogError,
    )
    tn = prof.t0_s + h * np.arange(K + 1)
    tn[-1] = min(tn[-1], prof.end_s)
    pn = prof.phi(tn)
    wn = prof.omega(tn)
    return _Grid(m, h, K, n, tn, pn, wn)


def _sampled(
    sen: _Sensor, grid: _Grid, coeffs, w: Wheel, tables, theta0: float, inverted: bool, noise: float, seed
) -> np.ndarray:
    """The signal at the samples [V]: the teeth's pulses (VR) or levels (Hall) summed per
    chunk of rows, scaled, with the noise (drawn from ``seed``), inverted if asked."""
    a0, a1, a2, a3 = coeffs
    present, amp, on, width = tables
    m, h, K, n, pn, wn = grid.m, grid.h, grid.K, grid.n, grid.pn, grid.wn
    N, pitch = w.teeth, w.pitch_rad
    sensor, sigma, tau, sens, offset, lo, hi = sen.kind, sen.sigma, sen.tau, sen.sens, sen.offset, sen.lo, sen.hi
    # per row (grid step) k and sample j: the wheel angle in pitches is row_base + x, x = c0 + s(c1 + s(c2 +
    # s·c3)), s = j/m; row_base, the position at the row's start within one revolution, indexes the
    # per-position tables; x, below a few pitches, is computed in single precision (rounding < 1e-6 pitch)
    ip = 1.0 / pitch
    start = (a0 + theta0) * ip
    start -= N * np.floor(start / N)
    row_base = np.floor(start).astype(np.intp)
    f32 = np.float32
    c0, c1, c2, c3 = (c.astype(f32) for c in (start - row_base, a1 * ip, a2 * ip, a3 * ip))
    d1, d2, d3 = ((c / h).astype(f32) for c in (a1, 2.0 * a2, 3.0 * a3))  # ω = d1 + s(d2 + s·d3)
    sj = (np.arange(m) / m).astype(f32)

    # the positions whose tooth can reach a sample: base = floor(x + b), candidates base + d
    if sensor == "vr":
        lo_reach = hi_reach = sigma + float(np.max(np.abs(on[present])))
    else:
        ramp = float(np.max(wn)) * tau / pitch
        lo_reach = float(np.max((on + width)[present])) + ramp  # a tooth whose high started before x
        hi_reach = -float(np.min(on[present])) + ramp  # a tooth whose high starts after x
    best = None
    for b in np.linspace(0.0, 1.0, 41)[:-1]:
        d_min = math.floor(-b - lo_reach) + 1
        d_max = math.ceil(1.0 - b + hi_reach) - 1
        if best is None or d_max - d_min < best[2] - best[1]:
            best = (float(b), d_min, d_max)
    assert best is not None
    b_shift, d_min, d_max = best
    span = int(math.ceil(float(np.max(np.diff(pn))) * ip)) + 2  # pitches a row can cover
    lo_pad, hi_pad = max(0, -d_min) + 1, d_max + span + 1
    ext = np.arange(-lo_pad, N + hi_pad) % N
    amp_x, wid_x = amp[ext].astype(f32), width[ext].astype(f32)
    on_x = np.where(present[ext], on[ext], 1e6).astype(f32)  # a missing tooth: an edge far away, never reached

    scale, base = (-sens / _PULSE_PEAK, offset) if sensor == "vr" else (hi - lo, lo)
    rng_noise = np.random.default_rng([int(seed), 2])
    v = np.empty(n)
    rows = max(1, _CHUNK // m)
    for r0 in range(0, K, rows):
        r1 = min(K, r0 + rows)
        x = c0[r0:r1, None] + sj * (c1[r0:r1, None] + sj * (c2[r0:r1, None] + sj * c3[r0:r1, None]))
        om = (d1[r0:r1, None] + sj * (d2[r0:r1, None] + sj * d3[r0:r1, None])).ravel()
        x += f32(b_shift)
        f = np.floor(x)
        fr = x - f
        fr -= f32(b_shift)  # x − base
        p0 = (f.astype(np.intp) + (row_base[r0:r1, None] + lo_pad)).ravel()
        fr = fr.ravel()
        if sensor == "vr":
            acc = np.zeros(fr.size, f32)
            inv_s = f32(1.0 / sigma)
            for d in range(d_min, d_max + 1):
                idx = p0 + d
                u = (fr - f32(d) - on_x[idx]) * inv_s
                g = np.maximum(f32(1.0) - u * u, f32(0.0))
                acc += amp_x[idx] * u * g * g
            acc *= om
            out = acc
        else:
            acc = np.zeros(fr.size, f32)
            q = f32(pitch / tau) / om  # pitches → ramps
            for d in range(d_min, d_max + 1):
                idx = p0 + d
                z = (fr - f32(d) - on_x[idx]) * q
                up = np.minimum(np.maximum(z + f32(0.5), f32(0.0)), f32(1.0))
                down = np.minimum(np.maximum((wid_x[idx] * q - z) + f32(0.5), f32(0.0)), f32(1.0))
                acc += up * down
            out = np.minimum(acc, f32(1.0))
        seg = v[r0 * m : r1 * m]
        np.multiply(out, scale, out=seg)
        seg += base
        if noise > 0:
            seg += noise * rng_noise.standard_normal(seg.size)
        if inverted:
            np.negative(seg, out=seg)

    return v


def _true_edges(w: Wheel, on: np.ndarray, grid: _Grid, coeffs, theta0: float):
    """Every tooth edge at least half a pitch inside the record: its time [s], tooth,
    revolution (0: that of the first tooth 0 in the record), wheel angle [rad], absolute
    revolution, and the teeth's positions."""
    a0, a1, a2, a3 = coeffs
    m, h, pn, wn, tn = grid.m, grid.h, grid.pn, grid.wn, grid.tn
    E, pitch = w.edges_per_rev, w.pitch_rad
    th_first = float(pn[0]) + theta0
    th_last = float(a0[-1] + (m - 1) / m * (a1[-1] + (m - 1) / m * (a2[-1] + (m - 1) / m * a3[-1]))) + theta0
    pos = w.positions
    rev_lo = int(math.floor(th_first / TWO_PI)) - 1
    rev_hi = int(math.ceil(th_last / TWO_PI)) + 1
    revs = np.arange(rev_lo, rev_hi + 1)
    ang = (TWO_PI * revs[:, None] + pitch * (pos + on[pos])[None, :]).ravel()
    tooth = np.broadcast_to(np.arange(E), (revs.size, E)).ravel()
    rev_abs = np.broadcast_to(revs[:, None], (revs.size, E)).ravel()
    keep = (ang >= th_first + 0.5 * pitch) & (ang <= th_last - 0.5 * pitch)
    ang, tooth, rev_abs = ang[keep], tooth[keep], rev_abs[keep]
    edge_t = _invert(pn, wn, float(tn[0]), h, ang - theta0)
    zero = rev_abs[tooth == 0]
    if zero.size:
        rev0 = int(zero[0])  # revolution 0: that of the first tooth 0 in the record
    else:
        rev0 = int(rev_abs[0]) + 1 if rev_abs.size else 0  # no tooth 0: every edge is before revolution 0
    rev = rev_abs - rev0
    return edge_t, tooth, rev, ang, rev_abs, pos


def _fixed_width(x: np.ndarray, int_digits: int, decimals: int, signed: bool) -> np.ndarray:
    """The numbers ``x`` as zero-padded fixed-width decimal text, one row of ASCII bytes each
    (``[+-]`` if ``signed``, ``int_digits`` digits, a point, ``decimals`` digits)."""
    scaled = np.rint(np.abs(x) * 10.0**decimals).astype(np.int64)
    total = int_digits + decimals
    width = int(signed) + total + 1
    out = np.empty((x.size, width), np.uint8)
    col = 0
    if signed:
        out[:, 0] = np.where(x < 0, ord("-"), ord("+"))
        col = 1
    for k in range(total):
        if k == int_digits:
            out[:, col] = ord(".")
            col += 1
        out[:, col] = (scaled // 10 ** (total - 1 - k)) % 10 + ord("0")
        col += 1
    return out


def write_log(path: str | os.PathLike, signal: SimulatedSignal, *, rows_per_block: int = 1 << 20) -> None:
    """Write ``signal`` to ``path`` as a tab-separated log with the header line
    ``time<TAB>encoder_v``: time [s] with 9 decimals, voltage [V] with 6, in zero-padded
    fixed-width columns. :func:`rotor.read_log` reads it with no column spec (the header
    names its columns; ``columns="time,encoder_v"`` says the same). Several million rows
    a second."""
    t = np.asarray(signal.t_s, dtype=np.float64)
    v = np.asarray(signal.v, dtype=np.float64)
    if t.shape != v.shape or t.ndim != 1 or not (np.all(np.isfinite(t)) and np.all(np.isfinite(v))):
        raise LogError("write_log: the signal's times and voltages must be finite and alike")
    t_int = max(1, len(str(int(np.max(np.abs(t))) if t.size else 0)))
    v_int = max(1, len(str(int(np.max(np.abs(v))) if v.size else 0)))
    signed_t = bool(t.size and np.min(t) < 0)
    with open(os.fspath(path), "wb") as f:
        f.write(b"time\tencoder_v\n")
        for i in range(0, t.size, rows_per_block):
            tb = _fixed_width(t[i : i + rows_per_block], t_int, 9, signed_t)
            vb = _fixed_width(v[i : i + rows_per_block], v_int, 6, True)
            sep = np.full((tb.shape[0], 1), ord("\t"), np.uint8)
            eol = np.full((tb.shape[0], 1), ord("\n"), np.uint8)
            f.write(np.concatenate([tb, sep, vb, eol], axis=1).tobytes())


def pattern_capture(
    pattern: Any,
    *,
    rpm: float = 900.0,
    turns: int = 14,
    swing: float = 0.03,
    jitter_deg: float = 0.0,
    displace: float = 0.0,
    glitch: bool = False,
    invert: bool = False,
    seed: int = 0,
) -> Log:
    """A logic-analyser export of a trigger pattern (:class:`rotor.logs.patterns.TriggerPattern`):
    the time [s] and the 0/1 level at each transition, as a :class:`rotor.logs.reader.Log`
    (``time``, ``encoder_d``), with the defects real captures carry.

    **Arguments:** ``rpm`` [rev/min], rising 10 % over the record; ``turns`` of the pattern;
    ``swing``: the speed's swing twice a revolution [-] (a four-cylinder's compressions);
    ``jitter_deg``: a normal error of each edge's angle [deg]; ``displace``: a missing-tooth
    wheel's edges on either side of its widest gap moved into it by this share of a pitch [-];
    ``glitch``: a 1 µs pulse in the middle; ``invert``: the levels inverted; ``seed``. Where the
    pattern states one polarity only, the other's edges follow at 0.3 of the shortest spacing
    (at most 4°)."""
    rng = np.random.default_rng(seed)
    P = pattern.period_deg
    r = np.asarray(pattern.rising_deg)
    f = np.asarray(pattern.falling_deg)
    if f.size == 0:
        f = (r + min(np.diff(np.r_[r, r[0] + P]).min() * 0.3, 4.0)) % P
    if r.size == 0:
        r = (f - min(np.diff(np.r_[f, f[0] + P]).min() * 0.3, 4.0)) % P
    if displace and re.fullmatch(r"\d+(-\d+)+", pattern.name):
        # a toothed wheel's edges on either side of its gap moved into it by ``displace`` of a pitch
        a = pattern.angles_deg()
        gaps = np.diff(np.r_[a, a[0] + P])
        k = int(np.argmax(gaps))
        pitch = float(np.median(gaps))
        shift = {float(a[k]): displace * pitch, float(a[(k + 1) % a.size]): -displace * pitch}
        r = np.array([x + shift.get(float(x), 0.0) if pattern.read in ("rising", "both") else x for x in r]) % P
        f = np.array([x + shift.get(float(x), 0.0) if pattern.read in ("falling", "both") else x for x in f]) % P
    ang = np.concatenate(
        [(r[None, :] + P * np.arange(turns)[:, None]).ravel(), (f[None, :] + P * np.arange(turns)[:, None]).ravel()]
    )
    lev = np.concatenate([np.ones(r.size * turns), np.zeros(f.size * turns)])
    ang = ang + 3.0 + rng.normal(0.0, jitter_deg, ang.size)
    order = np.argsort(ang)
    ang, lev = ang[order], lev[order]
    w0 = rpm * 6.0
    t = np.linspace(0.0, 1.2 * ang.max() / w0, 400_000)
    theta = w0 * t * (1 + 0.1 * t / t[-1]) + swing * 360 / (4 * math.pi) * np.sin(4 * math.pi * w0 * t / 360)
    te = np.interp(ang, theta, t) + 1e-3
    if glitch:  # a pulse of a microsecond in the middle
        i = te.size // 2
        te = np.insert(te, i, [te[i - 1] + 0.4 * (te[i] - te[i - 1]), te[i - 1] + 0.4 * (te[i] - te[i - 1]) + 1e-6])
        lev = np.insert(lev, i, [1 - lev[i - 1], lev[i - 1]])
    if invert:
        lev = 1 - lev
    return Log.from_arrays(time=np.r_[0.0, te], encoder_d=np.r_[1 - lev[0], lev])


def bench_capture(
    wheel: str = "60-2",
    *,
    rpm: float = 3000.0,
    revolutions: int = 20,
    sample_rate_hz: float = 100e3,
    noise_v: float = 0.01,
    faint: float = 1.0,
    faint_share: float = 1.0,
    late_pitch: tuple[float, float] = (0.0, 0.0),
    wide_pitch: float = 0.45,
    gap_level: float = 0.0,
    swing: float = 0.02,
    invert: bool = False,
    seed: int = 0,
) -> Log:
    """An analog two-level wheel signal of a bench (``time``, ``encoder_v``, as a
    :class:`rotor.logs.reader.Log`) with the defects a real installation's sensor shows near the
    gap of a missing-tooth wheel: high for 45 % of each pitch from its rising edge, low −0.73 V,
    high 4.0 V, each edge a ramp of four samples, white noise ``noise_v`` [V].

    **Arguments:** ``wheel``: an ``N-M`` spec (one gap); ``rpm`` [rev/min] with a swing of
    ``swing`` [-] twice a revolution; ``revolutions``; ``sample_rate_hz`` [Hz]; ``faint``: the
    swing of the first tooth after the gap, a share of the others' [-] (it crosses a low level
    only), in ``faint_share`` of the revolutions (drawn from ``seed``) [-]; ``late_pitch``: the
    first and second teeth after the gap start this late [pitches]; ``wide_pitch``: the last
    tooth before the gap stays high this long [pitches] (1.5: its falling edge merges with the
    gap on that polarity); ``gap_level``: the signal's level in the gap above the low level
    between teeth, a share of the swing [-]; ``invert``: negated; ``seed``."""
    from .wheel import parse_wheel

    w = parse_wheel(wheel)
    if len(w.gaps) != 1:
        raise LogError(f"wheel={wheel!r}: a wheel of one gap (N-M)")
    n, teeth = w.teeth, w.teeth - w.missing  # positions a revolution, teeth present
    rng = np.random.default_rng(seed)
    omega = rpm * TWO_PI / 60.0
    t = np.arange(0.0, revolutions * TWO_PI / omega, 1.0 / sample_rate_hz)
    x = (omega * t + swing / 2.0 * np.sin(2.0 * omega * t) + 0.3) / TWO_PI * n  # in pitches
    rev = np.floor(x / n).astype(np.int64)
    faint_rev = rng.random(int(rev.max()) + 1) < faint_share
    p = np.mod(x, n)
    v = np.where((p >= teeth) | (p < late_pitch[0]), gap_level, 0.0)
    for k in range(teeth):
        start = k + (late_pitch[0] if k == 0 else late_pitch[1] if k == 1 else 0.0)
        inside = np.mod(p - start, n) < (wide_pitch if k == teeth - 1 else 0.45)
        amp = np.where(faint_rev[rev], faint, 1.0) if k == 0 else 1.0
        v = np.where(inside, amp, v)
    v = np.convolve(v, np.ones(4) / 4.0, mode="same")
    v = -0.73 + 4.73 * v + noise_v * rng.standard_normal(t.size)
    return Log.from_arrays(time=t, encoder_v=-v if invert else v)
